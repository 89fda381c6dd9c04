"""What the main commands cost end to end: ``gpsaccel montecarlo --runs 10000`` (with and without
its figures) and ``gpsaccel run``; CPU (children included) and wall, side by side with an earlier
version.

Each case is a fresh ``python -m gpsaccel.cli ...`` in an empty folder of its own (a figure the
command writes by default lands there), repeated and alternated between the versions; the table
shows medians.  ``--before DIR`` runs the same cases on the checkout in DIR (its ``gpsaccel/``
first on ``PYTHONPATH``, this environment's packages), e.g. ``git worktree add --detach DIR main``.
Before issue 43 (figures when asked), ``montecarlo`` drew its four figures into ``out/`` unasked and
every figure was laid out by matplotlib's constrained layout (docs/cli.md).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import _cpu

ROOT = Path(__file__).resolve().parents[1]

CASES = [
    ("gpsaccel montecarlo --runs 10000", ["montecarlo", "--runs", "10000", "--no-progress"]),
    ("gpsaccel montecarlo --runs 10000 --out DIR (its 4 figures)",
     ["montecarlo", "--runs", "10000", "--no-progress", "--out", "figures"]),
    ("gpsaccel run (report 000's 9 figures in out/)", ["run"]),
]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    _cpu.version_flags(parser, repeats=3)
    args = parser.parse_args(argv)
    roots = _cpu.versions(args.before, ROOT)
    print(f"start: {_cpu.load()}")
    rows = [(name, _cpu.medians(["-m", "gpsaccel.cli", *cmd], roots, args.repeats))
            for name, cmd in CASES]
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print(_cpu.table(rows, list(roots)))


if __name__ == "__main__":
    main()
