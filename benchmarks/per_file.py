"""What one file costs the checker and one notebook the grader, end to end through the command:
CPU (the command and every box and worker, children included) and wall, side by side with an
earlier version.

* ``gpsaccel check DIR --workers 1`` on copies of a correct calibration filter, at the problem's
  default number of runs and at 2 runs (the floor: one box and the reference per file);
* ``gpsaccel grade DIR --jobs 1`` on copies of a homework notebook's student version as handed out
  (otter's init and check cells included, no answers): the floor of a notebook; and on copies of
  the same notebook filled in, the master's solutions in (an honest student's, as
  tests/assignments/conftest.py's ``solved`` makes it): what a notebook that answers costs.

Each runs on a class of 1 and of 3; the "one more file" rows are the difference per file (what a
class pays per student, the command's start-up and the summary paid once).

``--before DIR`` runs the same commands on the checkout in DIR (its ``gpsaccel/`` first on
``PYTHONPATH``, this environment's packages; e.g. ``git worktree add --detach DIR main``).
Where boxes can start warm (as root on Linux: docs/sandbox.md), every command runs with
``--boxes cold`` (a fresh Python per box) and ``--boxes warm`` side by side, so the table shows
what warm boxes save and what their zygotes cost a class (``--no-cold``: the default alone).  Both
versions use this environment's jsonschema: where it is >= 4.25, every box that imports otter pays
about 2 CPU s more (benchmarks/startup.py's rfc3987_syntax row).  ``make bench`` publishes the
medians (benchmarks/_figures.py): ``cpu_s/V/KIND/N`` for a class of N, ``cpu_s/V/KIND/one_more``
(V: cold, warm, or now where boxes cannot start warm).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

import _cpu
from _figures import publish

ROOT = Path(__file__).resolve().parents[1]
SUBMISSION = ROOT / "tests" / "submissions" / "correct_joseph.py"
STUDENT = ROOT / "gpsaccel" / "assignments" / "student"


#: Class sizes run: the difference between the two, per file, is what one more file costs (the
#: command's start-up, the summary figure and the like are paid once per class).
SIZES = (1, 3)


def _filled(name: str, target: Path) -> bool:
    """The master of homework ``name`` filled in as an honest student hands it in (the homework
    tests' own maker); False where the master is not in this checkout."""
    import nbformat

    sys.path.insert(0, str(ROOT))
    from tests.assignments.conftest import solved

    try:
        nb = solved(name)
    except (FileNotFoundError, KeyError, ValueError):
        return False
    nbformat.write(nb, str(target))
    return True


def _cases(tmp: Path) -> list[tuple[str, str, int, list[str]]]:
    """(kind, its key, files, command arguments) for each kind of file at each class size."""
    cases = []
    for n in SIZES:
        folder = tmp / f"check-{n}"
        folder.mkdir()
        for i in range(n):
            shutil.copy(SUBMISSION, folder / f"student{i}.py")
        cases.append(("check (default runs)", "check/default", n,
                      ["check", str(folder), "--seed", "0", "--workers", "1"]))
        cases.append(("check (--runs 2)", "check/runs2", n,
                      ["check", str(folder), "--seed", "0", "--workers", "1", "--runs", "2"]))
    for name in ("calibration", "coop"):
        notebook = STUDENT / name / f"{name}.ipynb"
        if not notebook.exists():
            continue
        filled = tmp / f"{name}-filled.ipynb"
        kinds = [("as handed out", "blank", notebook)]
        if _filled(name, filled):
            kinds.append(("filled: the master's solutions", "filled", filled))
        for what, key, source in kinds:
            for n in SIZES:
                folder = tmp / f"class-{name}-{key}-{n}"
                folder.mkdir()
                for i in range(n):
                    shutil.copy(source, folder / f"student{i}.ipynb")
                cases.append((f"grade ({name} notebook {what})", f"grade/{name}/{key}", n,
                              ["grade", str(folder), "--assignment", name, "--jobs", "1",
                               "--seed", "0", "--out", str(tmp / f"grades-{name}-{key}-{n}")]))
    return cases


def _warm_possible() -> bool:
    from gpsaccel.sandbox import zygote

    return zygote.usable()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", metavar="DIR", default=None,
                        help="a checkout of an earlier version (its gpsaccel/ is imported)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", default="", help="only the cases whose kind contains this")
    parser.add_argument("--no-cold", action="store_true",
                        help="leave out the column of every command with --boxes cold")
    args = parser.parse_args(argv)
    roots: dict[str, tuple[Path, list[str]]] = {"now": (ROOT, [])}
    if not args.no_cold and _warm_possible():
        roots = {"cold": (ROOT, ["--boxes", "cold"]), "warm": (ROOT, ["--boxes", "warm"])}
    if args.before:
        roots = {"before": (Path(args.before).resolve(), []), **roots}
    print(f"start: {_cpu.load()}")
    rows: list[tuple[str, dict[str, tuple[float, float]]]] = []
    medians: dict[tuple[str, int], dict[str, tuple[float, float]]] = {}
    keys: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for kind, key, n, cmd in _cases(Path(tmp)):
            if args.only not in kind:
                continue
            keys[kind] = key
            samples: dict[str, list[_cpu.Sample]] = {v: [] for v in roots}
            for _ in range(args.repeats):
                for version, (root, extra) in roots.items():
                    env = dict(os.environ, PYTHONPATH=str(root), MPLBACKEND="Agg")
                    s = _cpu.run([sys.executable, "-m", "gpsaccel.cli", *cmd, *extra], env=env,
                                 cwd=tmp)
                    if s.returncode not in (0, 1):  # 1: check's "not all passed"
                        raise SystemExit(f"{version}: {kind} failed ({s.returncode}):\n{s.stdout}")
                    samples[version].append(s)
            medians[kind, n] = {v: _cpu.median(s) for v, s in samples.items()}
            rows.append((f"{kind}, class of {n}", medians[kind, n]))
    small, large = SIZES
    figures: dict[str, float] = {}
    mine = [v for v in roots if v != "before"]
    for (kind, n), by_version in medians.items():
        for v in mine:
            figures[f"cpu_s/{v}/{keys[kind]}/{n}"] = by_version[v][0]
    for kind in dict.fromkeys(k for k, _ in medians):
        a, b = medians[kind, small], medians[kind, large]
        rows.append((f"{kind}: one more file", {
            v: ((b[v][0] - a[v][0]) / (large - small), (b[v][1] - a[v][1]) / (large - small))
            for v in roots}))
        for v in mine:
            figures[f"cpu_s/{v}/{keys[kind]}/one_more"] = rows[-1][1][v][0]
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print(_cpu.table(rows, list(roots)))
    publish(figures)


if __name__ == "__main__":
    main()
