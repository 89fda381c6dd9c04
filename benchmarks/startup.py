"""What starting costs: ``import gpsaccel``, the command's help and argument errors, the first names a
notebook imports, nbformat; CPU (children included) and wall, side by side with an earlier version.

Every case is a fresh interpreter (``python -c ...`` or ``python -m gpsaccel.cli ...``) in an empty
folder, repeated and alternated between the versions; the table shows medians.  ``--before DIR``
runs the same cases on the checkout in DIR (its ``gpsaccel/`` first on ``PYTHONPATH``, this
environment's packages), e.g. ``git worktree add --detach DIR main``.  The nbformat rows do not
depend on gpsaccel: they show what jsonschema >= 4.25 added to every ``import nbformat`` (its
rfc3987-syntax import, which pyproject.toml's ``jsonschema<4.25`` keeps out).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import _cpu

ROOT = Path(__file__).resolve().parents[1]

CASES = [
    ("python -c pass (the floor)", ["-c", "pass"]),
    ("import numpy", ["-c", "import numpy"]),
    ("import gpsaccel", ["-c", "import gpsaccel"]),
    ("import gpsaccel.cli", ["-c", "import gpsaccel.cli"]),
    ("gpsaccel --help", ["-m", "gpsaccel.cli", "--help"]),
    ("gpsaccel --version", ["-m", "gpsaccel.cli", "--version"]),
    ("gpsaccel check --help", ["-m", "gpsaccel.cli", "check", "--help"]),
    ("gpsaccel montecarlo --help", ["-m", "gpsaccel.cli", "montecarlo", "--help"]),
    ("gpsaccel grade --help", ["-m", "gpsaccel.cli", "grade", "--help"]),
    ("gpsaccel check --no-such-flag (argparse error)",
     ["-m", "gpsaccel.cli", "check", "--no-such-flag"]),
    ("gpsaccel check x.py --runs 0 (argparse error)",
     ["-m", "gpsaccel.cli", "check", "x.py", "--runs", "0"]),
    ("gpsaccel grade x --assignment nope (argparse error)",
     ["-m", "gpsaccel.cli", "grade", "x", "--assignment", "nope"]),
    ("from gpsaccel import CalibrationModel, CoopModel, ShipModel",
     ["-c", "from gpsaccel import CalibrationModel, CoopModel, ShipModel"]),
]

#: Cases that do not depend on gpsaccel's version (run once per repetition).
PACKAGES = [
    ("import nbformat (this environment's jsonschema)", ["-c", "import nbformat"]),
    ("import rfc3987_syntax (what jsonschema >= 4.25 adds to it)",
     ["-c", "import rfc3987_syntax"]),
]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    _cpu.version_flags(parser, repeats=5)
    args = parser.parse_args(argv)
    roots = _cpu.versions(args.before, ROOT)
    print(f"start: {_cpu.load()}")
    rows: list[tuple[str, dict[str, tuple[float, float]]]] = []
    with tempfile.TemporaryDirectory() as empty:
        for name, cmd in CASES:  # an argument error exits 2: any exit code is the case's own
            rows.append((name, _cpu.medians(cmd, roots, args.repeats, cwd=empty, ok=None)))
        for name, cmd in PACKAGES:
            s = [_cpu.run([sys.executable, *cmd], cwd=empty) for _ in range(args.repeats)]
            if any(x.returncode for x in s):
                continue  # not installed here
            rows.append((name, {"now": _cpu.median(s)}))
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print(_cpu.table(rows, list(roots)))


if __name__ == "__main__":
    main()
