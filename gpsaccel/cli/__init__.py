"""The ``gpsaccel`` command: ``run`` (the main job), ``compare``, ``figures`` and the others.

This module parses and dispatches; each group of sub-commands is a module of its own
(:mod:`~gpsaccel.cli.reports`, :mod:`~gpsaccel.cli.lessons`, :mod:`~gpsaccel.cli.checking`,
:mod:`~gpsaccel.cli.homework`), a small function per command that calls the package, where the
work lives.  Building the parser imports none of the work, not even numpy: the help of every
sub-command, ``--version`` and an argument error come back at the cost of Python's start
(tests/test_lazy_imports.py, tests/cli/test_front_door.py; measured in benchmarks/startup.py).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence

from gpsaccel._interrupt import exit_status, why
from gpsaccel.cli.checking import add_check
from gpsaccel.cli.homework import add_assignment, add_grade
from gpsaccel.cli.lessons import add_lab, add_lessons
from gpsaccel.cli.reports import add_compare, add_coop, add_figures, add_montecarlo, add_run, add_ship

#: what ``gpsaccel --help`` says first (the docstring's reST markup would print as is)
DESCRIPTION = ("The gpsaccel command: run (the main job), compare, figures, the lessons, and the "
               "checking and grading of homework.")

#: The sub-commands in the order ``gpsaccel --help`` lists them; each function adds one parser.
SUBCOMMANDS = (
    add_run,
    add_compare,
    add_figures,
    add_lessons,
    add_lab,
    add_coop,
    add_montecarlo,
    add_ship,
    add_check,
    add_assignment,
    add_grade,
)


def build_parser() -> argparse.ArgumentParser:
    from gpsaccel._version import __version__

    parser = _Parser(prog="gpsaccel", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Command)
    for add in SUBCOMMANDS:  # a new sub-command: an add_NAME function and one line above
        add(sub)
    return parser


#: What argparse takes for a negative number rather than a flag (its ``_negative_number_matcher``).
_NEGATIVE = re.compile(r"-\d+|-\d*\.\d+")


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error: ``gpsaccel check: error: argument --runs: must be ...``,
    which names an unknown flag first.

    Every flag's ``type=`` is a validator of :mod:`gpsaccel._validation` (``flag_int``,
    ``flag_float``, ``flag_seed``, ``flag_probability``, ``output_dir``, ``output_file``), so a bad
    number or an unusable output path is refused here, exit 2, before any work; sub-commands
    added later should use the same ones.

    argparse reports a missing argument before an unknown flag (``gpsaccel check --no-such-flag``
    said "the following arguments are required: paths"): whatever the error, a flag that none of
    the parser's options matches is what it names.
    """

    _given: Sequence[str] = ()

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        self._given = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def error(self, message: str):  # type: ignore[override]
        unknown = self.unknown_flags(self._given)
        if unknown:
            message = f"unrecognized arguments: {' '.join(unknown)}"
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def unknown_flags(self, args: Sequence[str]) -> list[str]:
        """The flags in ``args`` that no option of this parser takes, matched as argparse matches
        them: exactly, a long one by a prefix (``--run``), a short one with its value attached
        (``-vx``), ``--flag=value``.  A negative number is a value, ``--`` ends the flags, and a
        parser with sub-commands reads only up to the sub-command (its parser judges the rest)."""
        known = [s for a in self._actions for s in a.option_strings]
        commands = any(isinstance(a, argparse._SubParsersAction) for a in self._actions)
        unknown = []
        for arg in args:
            if arg == "--":
                break
            if not arg.startswith("-") or arg == "-" or _NEGATIVE.fullmatch(arg) or " " in arg:
                if commands:
                    break
                continue
            flag = arg.split("=", 1)[0]
            if flag.startswith("--"):
                matched = any(k.startswith(flag) for k in known)
            else:
                matched = flag[:2] in known
            if not matched:
                unknown.append(flag)
        return unknown


class _Command(_Parser):
    """A sub-command's parser: what it does not take is refused under its own name
    (``gpsaccel check: error: unrecognized arguments: --no-such-flag``), not the top level's."""

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras


#: The extra that installs what a sub-command imports beyond the core (pyproject.toml).
_EXTRAS = {"lessons": "lessons", "lab": "lab", "assignment": "grading", "grade": "grading",
           "montecarlo": "dask", "check": "dask"}


def main(argv: Sequence[str] | None = None) -> int:
    """Parse, run, and turn the expected failures into one line on stderr.

    Exit codes: 0 success; 1 a sub-command's own "not all passed" (``check``); 2 bad input
    (ValueError) or a file-system error (OSError: disk full, permission, ...); 130 interrupted
    (Ctrl-C; 143 SIGTERM, 129 SIGHUP where a class run took them as Ctrl-C: 128 + the signal),
    after which no half-written file is left (:mod:`gpsaccel._atomic`).
    """
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0) or a refused flag (2): returned, for callers in-process
        return exc.code if isinstance(exc.code, int) else 2
    except KeyboardInterrupt:
        print("gpsaccel: interrupted", file=sys.stderr)
        return 130
    try:
        return int(args.func(args) or 0)
    except ModuleNotFoundError as exc:  # an optional part not installed: name the extra
        extra = _EXTRAS.get(args.command, "test")
        print(f"gpsaccel {args.command}: error: {exc.msg}: the module {exc.name} is not "
              f"installed (pip install 'gpsaccel[{extra}]')", file=sys.stderr)
        return 2
    except ValueError as exc:  # bad input: one clear line, not a traceback
        print(f"gpsaccel {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # the file system said no: say what and where, in one line
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"gpsaccel {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM / SIGHUP where a run latches them
        print(f"gpsaccel {args.command}: interrupted{why(exc)}", file=sys.stderr)
        return exit_status(exc)


if __name__ == "__main__":
    sys.exit(main())
