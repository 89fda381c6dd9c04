"""The README opens with exactly two set-up commands, the main job and the whole test suite
(``make test-all``), and CI (.ci/run) runs that test command: a subset under the README's name
would leave tests no one runs by the book (``make test``, the default while developing, is the
subset, under "Developing")."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _first_block(text: str) -> list[str]:
    """The commands of the README's first fenced block (comments dropped)."""
    block = re.search(r"```\w*\n(.*?)```", text, re.S)
    assert block is not None, "README.md has no fenced block"
    return [line.split("#")[0].strip() for line in block.group(1).splitlines() if line.strip()]


def _pytest_argv(target: str) -> list[str]:
    """The arguments make's ``target`` gives pytest (``make -n``: printed, not run), as the README
    runs it: no PYTEST_ARGS, and none of an enclosing make's variables (under ``make test
    PYTEST_ARGS=...`` they reach this make through MAKEFLAGS)."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL", "PYTEST_ARGS", "JOBS")}
    out = subprocess.run(["make", "-n", "-C", str(ROOT), target, "VENV=.venv-never-made"],
                         capture_output=True, text=True, timeout=60, env=env).stdout
    lines = [line for line in out.splitlines() if " -m pytest" in line]
    assert len(lines) == 1, out
    return shlex.split(lines[0].split(" -m pytest", 1)[1])


def test_the_readme_opens_with_the_main_job_and_the_test_command():
    assert _first_block((ROOT / "README.md").read_text(encoding="utf-8")) == \
        ["make run", "make test-all"]


@pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")
def test_make_test_all_selects_every_test_and_test_leaves_the_slow_ones_out():
    whole, quick = _pytest_argv("test-all"), _pytest_argv("test")
    # no marker, keyword, file or folder narrows the whole run; only its workers
    assert not {"-m", "-k"} & set(whole) and not [a for a in whole if a.startswith("tests")], whole
    assert quick[-2:] == ["-m", "not slow"] and quick[:-2] == whole, quick


def test_ci_runs_the_readmes_test_command():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    command = _first_block((ROOT / "README.md").read_text(encoding="utf-8"))[1]
    assert re.search(rf"^\s*{re.escape(command)} PYTHON=", ci, re.M), f"CI does not run `{command}`"
