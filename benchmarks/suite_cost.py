"""What the test suite costs, per folder: CPU of pytest and every process it started (children
included: xdist workers, kernels, boxes, otter), wall time, and what ran.

One pytest per folder of ``tests/`` (the top-level test files together as ``tests/*.py``), one after
the other, so a folder's figure is its own.  Not part of ``make bench``: it runs the suite, which
the machine may share (benchmarks/run.py leaves it out).  Examples::

    python benchmarks/suite_cost.py                       # every folder, as `make test-all` would
    python benchmarks/suite_cost.py -m "not slow"         # as `make test` would
    python benchmarks/suite_cost.py tests/kalman -m "not slow"
    python benchmarks/suite_cost.py -n 2 --out docs/benchmarks/suite_cost.txt
    python benchmarks/suite_cost.py -n 2 --root /tmp/main --root /tmp/branch  # before, after

As on a fresh clone, the suite's disk cache (tests/conftest.py ``disk_cache``: executed lessons,
``otter assign``) starts empty: a new folder per checkout for the whole run, shared by its folders
as one ``make test-all`` shares it (``--keep-cache`` uses the checkout's own).  The sum over folders
is a little more than one ``make test-all``: each folder's pytest starts and collects on its own.
With ``-n``, the workers share the work as the checkout's ``make test`` does (its Makefile's
``--dist``).
``--durations N`` keeps pytest's N slowest items per folder in ``--log``.

The table is Markdown; ``--out`` also writes it to a file under a line naming the date, Python and
load (the load is printed at the start and at the end: CPU seconds are what to compare).
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import shlex
import sys
import tempfile
from pathlib import Path

import _cpu

ROOT = Path(__file__).resolve().parents[1]


def groups(paths: list[str], root: Path = ROOT) -> list[tuple[str, list[str]]]:
    """(label, pytest arguments) per folder; every folder of tests/ and its top-level files when
    ``paths`` is empty."""
    if paths:
        return [(p, [p]) for p in paths]
    tests = root / "tests"
    out = []
    top = sorted(str(p.relative_to(root)) for p in tests.glob("test_*.py"))
    if top:
        out.append(("tests/*.py", top))
    for folder in sorted(p for p in tests.iterdir() if p.is_dir()):
        if any(folder.rglob("test_*.py")):
            rel = str(folder.relative_to(root))
            out.append((rel + "/", [rel]))
    return out


def outcome(stdout: str) -> str:
    """pytest's closing counts ("12 passed, 1 skipped"), or its last line."""
    lines = [line for line in stdout.strip().splitlines() if line.strip()]
    for line in reversed(lines):
        found = re.findall(r"(\d+) (passed|failed|skipped|deselected|errors?|xfailed|xpassed)",
                           line)
        if found:
            return ", ".join(f"{n} {what}" for n, what in found)
    return lines[-1][:80] if lines else ""


def _dist(root: Path) -> list[str]:
    """How ``make test`` of ``root`` shares the tests between its workers (its Makefile's XDIST),
    ``--dist loadscope`` if it does not say."""
    makefile = root / "Makefile"
    text = makefile.read_text(encoding="utf-8") if makefile.exists() else ""
    found = re.search(r"^XDIST\s*=.*?-n \$\(JOBS\) ([^)]*)\)", text, re.M)
    return found.group(1).split() if found else ["--dist", "loadscope"]


def _pytest(root: Path, targets: list[str], args: argparse.Namespace) -> list[str]:
    """The pytest command line of one folder in ``root`` (its own .venv's Python when it has one)."""
    python = root / ".venv" / "bin" / "python"
    cmd = [str(python if python.exists() else sys.executable), "-m", "pytest", "-q",
           "-p", "no:cacheprovider", *targets]
    if args.marks:
        cmd += ["-m", args.marks]
    if args.workers:
        cmd += ["-n", args.workers, *_dist(root)]
    if args.durations:
        cmd += [f"--durations={args.durations}"]
    return cmd


def _environments(roots: list[Path], keep_cache: bool, folder: Path) -> list[dict[str, str]]:
    """One environment per checkout; unless ``keep_cache``, each with an empty disk cache of its
    own under ``folder`` (a fresh clone's: nothing executed yet, nothing shared between them)."""
    envs = []
    for k, _ in enumerate(roots):
        env = dict(os.environ, MPLBACKEND="Agg")
        if not keep_cache:
            env["GPSACCEL_TEST_CACHE"] = str(folder / f"cache-{k}")
        envs.append(env)
    return envs


def _header(roots: list[Path]) -> list[str]:
    names = [r.name for r in roots]
    if len(roots) == 1:
        return ["| folder | tests | CPU s | wall s | exit | load at start |",
                "|---|---|---|---|---|---|"]
    head = (["folder"] + [f"tests ({n})" for n in names] + [f"CPU s ({n})" for n in names]
            + [f"wall s ({n})" for n in names] + ["exit", "load at start"])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="*", help="folders or files (default: every folder)")
    parser.add_argument("-m", dest="marks", default=None, help="pytest's -m (e.g. 'not slow')")
    parser.add_argument("-n", dest="workers", default=None,
                        help="pytest-xdist workers per folder (default: none, serial)")
    parser.add_argument("--out", type=Path, default=None, help="also write the table here")
    parser.add_argument("--root", type=Path, action="append", default=None,
                        help="a checkout to measure, with its own .venv (default: this one); "
                             "given twice (before, after), each folder runs in one then the "
                             "other, so both see the same load")
    parser.add_argument("--keep-cache", action="store_true",
                        help="use the checkouts' disk caches as they are (default: empty ones)")
    parser.add_argument("--durations", type=int, default=0, help="pytest's --durations per folder")
    parser.add_argument("--log", type=Path, default=None, help="append every pytest's output here")
    parser.add_argument("--only", nargs="+", default=None,
                        help="only these rows of the default folders (e.g. 'tests/*.py' tests/figures/)")
    args = parser.parse_args(argv)
    roots = [r.resolve() for r in (args.root or [ROOT])]
    work = tempfile.TemporaryDirectory(prefix="suite-cost-")
    envs = _environments(roots, args.keep_cache, Path(work.name))
    start = _cpu.load()
    print(f"start: {start}", flush=True)
    lines = _header(roots)
    totals = [[0.0, 0.0] for _ in roots]
    failed = False
    for label, targets in groups(args.paths, roots[0]):
        if args.only and label not in args.only:
            continue
        load = _cpu.load().split(" (")[0]
        samples = []
        for k, root in enumerate(roots):
            s = _cpu.run(_pytest(root, targets, args), cwd=str(root), env=envs[k])
            samples.append(s)
            totals[k][0] += s.cpu
            totals[k][1] += s.wall
            failed |= s.returncode not in (0, 5)  # 5: nothing selected in that folder
            if args.log is not None:
                with args.log.open("a", encoding="utf-8") as log:
                    log.write(f"\n===== {label} in {root}: CPU {s.cpu:.1f} s, wall {s.wall:.1f} s,"
                              f" exit {s.returncode}\n{s.stdout}")
        cells = ([outcome(s.stdout) for s in samples] + [f"{s.cpu:.1f}" for s in samples]
                 + [f"{s.wall:.1f}" for s in samples]
                 + [" / ".join(str(s.returncode) for s in samples), load])
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)
    blank = [""] * len(roots)
    lines.append("| total | " + " | ".join(blank + [f"{c:.1f}" for c, _ in totals]
                                           + [f"{w:.1f}" for _, w in totals] + ["", ""]) + " |")
    end = _cpu.load()
    work.cleanup()
    what = (f"`python benchmarks/suite_cost.py {shlex.join(argv if argv is not None else sys.argv[1:])}`"
            f", {datetime.date.today().isoformat()}, Python {platform.python_version()}; "
            f"start: {start}; end: {end}; CPU = user + system of pytest and its children")
    text = what + "\n\n" + "\n".join(lines) + "\n"
    print("\n" + text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
