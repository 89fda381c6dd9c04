"""Lessons' Run All at full size, before and after a change, side by side in one run.

    python benchmarks/lessons.py 07 00 14 [--before main] [--repeat 1]
    python benchmarks/lessons.py            # every lesson whose master differs from main's
    python benchmarks/lessons.py 05 10b 11 --before REV --rest --write docs/benchmarks/lessons.txt
    python benchmarks/lessons.py --all --before REV --versions before --save before.json
    python benchmarks/lessons.py --all --versions after --add before.json --write docs/benchmarks/lessons.txt


For each lesson (a master's name prefix) the solutions version runs top to bottom in a fresh
kernel, as ``python -m gpsaccel.lessons measure`` runs it, once with the code of this checkout
("after") and once with the code of git revision ``--before`` ("before", unpacked with
``git archive`` into a temporary folder and put first on ``PYTHONPATH``, so its kernel imports that
gpsaccel).  A lesson the revision does not have is reported as new.  Before and after alternate
per lesson, so a change of the machine's load hits both alike.

``--versions before`` (or ``after``) runs one side only and ``--save`` keeps its figures as JSON;
``--add`` merges such a file into this run's table: the two sides can then be measured at different
times (each on a quiet machine) and still meet in one table, whose head names both runs.

At the end a Markdown table (one row per lesson: CPU and wall before and after, CPU after/before,
the load) is printed, and with ``--write PATH`` written there under a line saying when, where and
at what load (``docs/benchmarks/lessons.txt``; the benchmark page is made of these files).
``--rest`` adds a row for every other lesson, not run here: the wall time and load its own
``measure`` recorded in lessons/measured/ (a shared machine's wall time, not CPU: read it as an
upper bound).

Reported per lesson: wall time and CPU time (user + system of the process that runs the notebook
and its children, the kernel included: ``resource.getrusage(RUSAGE_CHILDREN)`` around a
subprocess), the ratio after/before, and the 1-minute load average before each run.  The machine
is shared: read the ratio and the CPU time, not the wall time alone.  Nothing here is asserted
(timings belong in benchmarks/, not in tests).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import resource
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: Runs one notebook in a child process: the solutions version at full size (no
#: GPSACCEL_LESSON_RUNS), as ``gpsaccel.lessons.measure`` does.
_RUN = """
import sys
from gpsaccel.lessons import execute
execute(sys.argv[1], timeout=1800)
"""


def _unpack(revision: str, into: Path) -> Path:
    """The tree of ``revision`` (``git archive``; symlinks such as gpsaccel/_lessons kept)."""
    archive = into / "tree.tar"
    with archive.open("wb") as f:
        subprocess.run(["git", "-C", str(ROOT), "archive", revision], stdout=f, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into / "tree", filter="tar")
    return into / "tree"


def _lesson(tree: Path, prefix: str) -> Path | None:
    found = sorted((tree / "lessons" / "masters").glob(f"{prefix}*.ipynb"))
    return found[0] if found else None


def _solutions_copy(tree: Path, master: Path, tmp: Path) -> Path:
    """The solutions version of ``master``, built by the tree's own release code, written into
    ``tmp`` (where ``gpsaccel.lessons.measure`` runs a lesson too: never into a checkout)."""
    code = ("import sys, nbformat; from pathlib import Path; from gpsaccel import lessons as L\n"
            "m = Path(sys.argv[1]); nb = nbformat.read(m, as_version=4)\n"
            "Path(sys.argv[2]).write_text(L.lab_text(L.solutions_version(nb, m.stem, "
            "L.measured(m.stem))), encoding='utf-8')\n")
    target = tmp / f"{'before' if tree != ROOT else 'after'}-{master.name}"
    subprocess.run([sys.executable, "-c", code, str(master), str(target)], check=True,
                   env=_env(tree), cwd=tmp)
    return target


def _env(tree: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "GPSACCEL_LESSON_RUNS"}
    env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("MPLBACKEND", "Agg")
    return env


def run_once(tree: Path, notebook: Path, cwd: Path) -> tuple[float, float, float]:
    """(wall s, CPU s of the child and its descendants, load average before)."""
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", _RUN, str(notebook)], check=True, env=_env(tree),
                   cwd=cwd, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, load


def changed_lessons(revision: str) -> list[str]:
    """The masters that differ from (or are not in) ``revision``, as name prefixes."""
    out = subprocess.run(["git", "-C", str(ROOT), "diff", "--name-only", revision, "--",
                          "lessons/masters"], capture_output=True, text=True, check=True).stdout
    new = subprocess.run(["git", "-C", str(ROOT), "ls-files", "--others", "--exclude-standard",
                          "lessons/masters"], capture_output=True, text=True, check=True).stdout
    names = {Path(line).stem for line in (out + new).split() if line.endswith(".ipynb")}
    return sorted(n for n in names if (ROOT / "lessons" / "masters" / f"{n}.ipynb").exists())


def _table(results: dict[str, dict[str, tuple[float, float, float]]]) -> list[str]:
    """Markdown rows: CPU and wall per version, CPU after/before, the loads before the runs."""
    lines = ["| lesson | before CPU s | after CPU s | before wall s | after wall s | "
             "CPU after/before | load (1 min) before / after |", "|---|---|---|---|---|---|---|"]
    for name, by in results.items():
        b, a = by.get("before"), by.get("after")
        cpu = [f"{b[1]:.1f}" if b else "(new)", f"{a[1]:.1f}" if a else "not run"]
        wall = [f"{v[0]:.1f}" if v else "-" for v in (b, a)]
        ratio = f"{a[1] / b[1]:.2f}" if a and b else ""
        load = " / ".join(f"{v[2]:.1f}" if v else "-" for v in (b, a))
        lines.append(f"| {name} | {cpu[0]} | {cpu[1]} | {wall[0]} | {wall[1]} | {ratio} | {load} |")
    return lines


def _recorded(skip: set[str]) -> list[str]:
    """Rows for the lessons not run: what their own ``measure`` recorded (wall s at a load)."""
    lines = []
    for path in sorted((ROOT / "lessons" / "measured").glob("*.json")):
        if path.stem in skip:
            continue
        rec = json.loads(path.read_text(encoding="utf-8"))
        lines.append(f"| {path.stem} | not run | not run | - | {rec.get('seconds', float('nan')):.1f} "
                     f"(recorded) | | - / {rec.get('load', float('nan')):.1f} |")
    return lines


def _measure(prefix: str, trees: dict[str, Path], tmp: Path,
             repeat: int) -> tuple[str, dict[str, tuple[float, float, float]]]:
    """The lesson's row name (its name in this checkout, else in --before) and the best run of
    each version."""
    found = _lesson(ROOT, prefix) or next(
        (m for m in (_lesson(t, prefix) for t in trees.values()) if m), None)
    name = found.stem if found else prefix
    best: dict[str, tuple[float, float, float]] = {}
    for _ in range(repeat):
        for version, tree in trees.items():
            master = _lesson(tree, prefix)
            if master is None:
                continue
            nb = _solutions_copy(tree, master, tmp)
            try:
                result = run_once(tree, nb, tmp)
            finally:
                nb.unlink(missing_ok=True)
            if version not in best or result[1] < best[version][1]:
                best[version] = result
    return name, best


def _print(name: str, best: dict[str, tuple[float, float, float]], trees: dict[str, Path]) -> None:
    for version in trees:
        if version not in best:
            print(f"{name:<34} {version:<7} {'(new)' if version == 'before' else '-':>8}")
            continue
        wall, cpu, load = best[version]
        print(f"{name:<34} {version:<7} {wall:8.1f} {cpu:8.1f} {load:5.1f}")
    if len(best) == 2:
        print(f"{'':<34} {'after/before':<7}  wall {best['after'][0] / best['before'][0]:.2f}, "
              f"CPU {best['after'][1] / best['before'][1]:.2f}", flush=True)


def _save(path: str, results: dict, head: str) -> None:
    """The figures so far, with when and at what load they were taken (for a later ``--add``)."""
    load = os.getloadavg()
    text = json.dumps({"head": f"{head}, {datetime.datetime.now().isoformat(timespec='minutes')}, "
                               f"load {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} at its end",
                       "results": results}, indent=1)
    Path(path).write_text(text, encoding="utf-8")


def _arguments(argv: list[str] | None) -> tuple[argparse.Namespace, list[str], list[str]]:
    """The parsed arguments, the versions to run and the lessons (name prefixes or names)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("lessons", nargs="*", metavar="NN",
                   help="master name prefixes, e.g. 07 14 (default: the masters changed since --before)")
    p.add_argument("--before", default="main", help="git revision to compare with (default main)")
    p.add_argument("--repeat", type=int, default=1, help="runs of each version (the best kept)")
    p.add_argument("--rest", action="store_true",
                   help="also list every other lesson with the wall time its measure recorded")
    p.add_argument("--write", metavar="PATH", help="also write the Markdown table to PATH")
    p.add_argument("--all", action="store_true", help="every lesson of this checkout")
    p.add_argument("--versions", default="before,after",
                   help="which sides to run: before,after (default), before or after")
    p.add_argument("--save", metavar="JSON", help="write this run's figures to JSON")
    p.add_argument("--add", metavar="JSON", help="merge the figures a --save wrote earlier")
    args = p.parse_args(argv)
    if args.repeat < 1:
        p.error(f"--repeat must be >= 1, got {args.repeat}")
    versions = [v for v in args.versions.split(",") if v]
    if not versions or set(versions) - {"before", "after"}:
        p.error(f"--versions must be before, after or before,after; got {args.versions!r}")
    if args.lessons and args.all:
        p.error("give lesson prefixes or --all, not both")
    if args.all:
        return args, versions, [m.stem for m in sorted((ROOT / "lessons" / "masters").glob("*.ipynb"))]
    return args, versions, args.lessons or changed_lessons(args.before)


def main(argv: list[str] | None = None) -> int:
    args, versions, lessons = _arguments(argv)
    if not lessons:
        print(f"no lesson master differs from {args.before}: nothing to measure")
        return 0
    started = os.getloadavg()[0]
    print(f"{os.cpu_count()} CPUs; before = {args.before}, after = this checkout ({ROOT})")
    print(f"{'lesson':<34} {'version':<7} {'wall s':>8} {'CPU s':>8} {'load':>5}")
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-lessons-") as tmp_name:
        tmp = Path(tmp_name)
        trees = {v: (_unpack(args.before, tmp) if v == "before" else ROOT) for v in versions}
        results: dict[str, dict[str, tuple[float, float, float]]] = {}
        for prefix in lessons:
            prefix = prefix.split("-")[0]   # a whole name may have changed since --before
            name, best = _measure(prefix, trees, tmp, args.repeat)
            results[name] = best
            if args.save:
                _save(args.save, results, head=f"{args.versions} of {args.before}")
            _print(name, best, trees)
    ended = os.getloadavg()
    earlier = ""
    if args.add:
        saved = json.loads(Path(args.add).read_text(encoding="utf-8"))
        for name, by in saved["results"].items():
            results.setdefault(name, {}).update(
                {v: tuple(r) for v, r in by.items() if v not in results.get(name, {})})
        earlier = f"  Merged from {args.add}: {saved['head']}."
    shown = " ".join(lessons) if not args.all else "--all"
    head = (f"`python benchmarks/lessons.py {shown} --before {args.before} "
            f"--versions {args.versions}`, "
            f"{datetime.date.today().isoformat()}, {os.cpu_count()} CPUs, load average (1 min) "
            f"{started:.1f} at the start, {ended[0]:.1f} / {ended[1]:.1f} / {ended[2]:.1f} "
            f"(1/5/15 min) at the end.  CPU = user + system of the notebook's process and its "
            f"children (the kernel, its process pool); the machine was shared, so the wall times "
            f"are not an idle machine's.{earlier}")
    rows = _table(results) + (_recorded(set(results)) if args.rest else [])
    text = "\n".join([head, ""] + rows) + "\n"
    print("\n" + text, end="")
    if args.write:
        Path(args.write).write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
