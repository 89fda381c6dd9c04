"""docs/cli.md is where the README sends a reader for "every command and flag": a sub-command or a
flag added to the parser without a word there fails here (the page drifted from the command once
already: ``lab`` and ``lessons --copy`` were missing while docs/student.md told students to use
them)."""

from __future__ import annotations

from pathlib import Path

from gpsaccel.cli import build_parser

CLI_MD = Path(__file__).resolve().parents[2] / "docs" / "cli.md"


def _subparsers():
    parser = build_parser()
    (action,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    return action.choices


def _rows(text: str, name: str) -> str:
    """The lines of the page's sub-command table that describe ``gpsaccel NAME``."""
    return "\n".join(line for line in text.splitlines()
                     if line.startswith((f"| `gpsaccel {name} ", f"| `gpsaccel {name}`")))


def test_every_sub_command_and_flag_is_in_its_row_of_the_cli_page():
    text = CLI_MD.read_text(encoding="utf-8")
    missing = []
    for name, sub in _subparsers().items():
        rows = _rows(text, name)
        if not rows:
            missing.append(f"gpsaccel {name}")
        for action in sub._actions:
            longest = max(action.option_strings, key=len, default=None)
            if longest and longest != "--help" and longest not in rows:
                missing.append(f"gpsaccel {name} {longest}")
    assert not missing, f"docs/cli.md's table does not mention: {missing}"
