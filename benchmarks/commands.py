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
import os
import sys
import tempfile
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
    parser.add_argument("--before", metavar="DIR", default=None,
                        help="a checkout of an earlier version (its gpsaccel/ is imported)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    roots = {"now": ROOT}
    if args.before:
        roots = {"before": Path(args.before).resolve(), "now": ROOT}
    print(f"start: {_cpu.load()}")
    rows: list[tuple[str, dict[str, tuple[float, float]]]] = []
    for name, cmd in CASES:
        samples: dict[str, list[_cpu.Sample]] = {v: [] for v in roots}
        for _ in range(args.repeats):
            for version, root in roots.items():
                env = dict(os.environ, PYTHONPATH=str(root), MPLBACKEND="Agg")
                with tempfile.TemporaryDirectory() as empty:
                    sample = _cpu.run([sys.executable, "-m", "gpsaccel.cli", *cmd], env=env,
                                      cwd=empty)
                if sample.returncode:
                    raise SystemExit(f"{name} ({version}) failed:\n{sample.stdout}")
                samples[version].append(sample)
        rows.append((name, {v: _cpu.median(s) for v, s in samples.items()}))
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print(_cpu.table(rows, list(roots)))


if __name__ == "__main__":
    main()
