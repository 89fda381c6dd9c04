"""What one file costs the checker and one notebook the grader, end to end through the command:
CPU (the command and every box and worker, children included) and wall, side by side with an
earlier version.

* ``gpsaccel check FILE --workers 1`` on a correct calibration filter, at the problem's default
  number of runs and at 2 runs (the floor: start-up, one box, the reference);
* ``gpsaccel grade DIR --jobs 1`` on a class of one: the student version of a homework notebook as
  handed out (otter's init and check cells included, no answers), so the floor of a notebook.

``--before DIR`` runs the same commands on the checkout in DIR (its ``gpsaccel/`` first on
``PYTHONPATH``, this environment's packages; e.g. ``git worktree add --detach DIR main``).  Both
versions use this environment's jsonschema: where it is >= 4.25, every box that imports otter pays
about 2 CPU s more (benchmarks/startup.py's rfc3987_syntax row).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

import _cpu

ROOT = Path(__file__).resolve().parents[1]
SUBMISSION = ROOT / "tests" / "submissions" / "correct_joseph.py"
STUDENT = ROOT / "gpsaccel" / "assignments" / "student"


def _cases(tmp: Path) -> list[tuple[str, list[str]]]:
    cases = [
        ("check 1 file (default runs)", ["check", str(SUBMISSION), "--seed", "0", "--workers", "1"]),
        ("check 1 file (--runs 2)", ["check", str(SUBMISSION), "--seed", "0", "--workers", "1",
                                     "--runs", "2"]),
    ]
    for name in ("calibration", "coop"):
        notebook = STUDENT / name / f"{name}.ipynb"
        if not notebook.exists():
            continue
        folder = tmp / f"class-{name}"
        folder.mkdir()
        shutil.copy(notebook, folder / "alice.ipynb")
        cases.append((f"grade 1 notebook ({name}, as handed out)",
                      ["grade", str(folder), "--assignment", name, "--jobs", "1", "--seed", "0",
                       "--out", str(tmp / f"grades-{name}")]))
    return cases


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
    with tempfile.TemporaryDirectory() as tmp:
        for name, cmd in _cases(Path(tmp)):
            samples: dict[str, list[_cpu.Sample]] = {v: [] for v in roots}
            for _ in range(args.repeats):
                for version, root in roots.items():
                    env = dict(os.environ, PYTHONPATH=str(root), MPLBACKEND="Agg")
                    s = _cpu.run([sys.executable, "-m", "gpsaccel.cli", *cmd], env=env, cwd=tmp)
                    if s.returncode not in (0, 1):  # 1: check's "not all passed"
                        raise SystemExit(f"{version}: {name} failed ({s.returncode}):\n{s.stdout}")
                    samples[version].append(s)
            rows.append((name, {v: _cpu.median(s) for v, s in samples.items()}))
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print(_cpu.table(rows, list(roots)))


if __name__ == "__main__":
    main()
