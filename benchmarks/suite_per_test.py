"""What each test costs in one whole ``make test-all`` run: a pytest plugin that records the CPU of
every test item, and a table of two such runs side by side, per folder and per file.

Where ``benchmarks/suite_cost.py`` runs one pytest per folder (each folder's figure its own, but
each paying its own start-up and without the other folders' shared disk cache), this measures the
one run CI makes, with its two workers and its schedule, and splits it by test::

    cd CLONE && PYTHONPATH=/path/to/benchmarks CPU_PER_TEST=/tmp/after/cpu \\
        make test-all PYTEST_ARGS="-p suite_per_test"              # or make test
    python benchmarks/suite_per_test.py /tmp/before /tmp/after      # the Markdown table

A test item's CPU is user + system of its worker process and of the children the worker waited
for (``getrusage`` SELF + CHILDREN) from the start of its setup to the end of its teardown, so a
module fixture's cost falls on the first test that needs it.  The per-test sum is a little less
than the run's ``time`` (the controller, collection and the workers' start-up are not in an
item).  Nothing here is asserted: timings belong in benchmarks/, not in tests.
"""

from __future__ import annotations

import collections
import glob
import json
import os
import resource
import sys
import time

import pytest

_OUT = "CPU_PER_TEST"


def _cpu() -> float:
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """One JSON line per test item (node id, CPU s, wall s) into ``$CPU_PER_TEST.<worker>.jsonl``."""
    prefix = os.environ.get(_OUT)
    c0, w0 = _cpu(), time.perf_counter()
    yield
    if prefix:
        row = {"id": item.nodeid, "cpu": _cpu() - c0, "wall": time.perf_counter() - w0}
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        with open(f"{prefix}.{worker}.jsonl", "a", encoding="utf-8") as f:
            f.write(json.dumps(row) + "\n")


def load(folder: str) -> list[dict]:
    """The rows a run wrote into ``folder`` (its ``cpu.*.jsonl`` files)."""
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "cpu.*.jsonl"))):
        with open(path, encoding="utf-8") as f:
            rows += [json.loads(line) for line in f]
    if not rows:
        raise SystemExit(f"no cpu.*.jsonl in {folder}: run pytest with -p suite_per_test and "
                         f"{_OUT}={folder}/cpu first")
    return rows


def _folder(nodeid: str) -> str:
    path = nodeid.split("::")[0]
    return "/".join(path.split("/")[:2]) + "/" if path.count("/") > 1 else "tests/*.py"


def table(before: list[dict], after: list[dict]) -> str:
    """Markdown: tests and CPU s per folder, before and after, and the whole run's per-test sum."""
    sums: dict[str, dict[str, list[float]]] = collections.defaultdict(
        lambda: {"before": [0, 0.0], "after": [0, 0.0]})
    for side, rows in (("before", before), ("after", after)):
        for r in rows:
            s = sums[_folder(r["id"])][side]
            s[0] += 1
            s[1] += r["cpu"]
    lines = ["| folder | tests before | tests after | CPU s before | CPU s after | after/before |",
             "|---|---|---|---|---|---|"]
    for name in sorted(sums, key=lambda k: -sums[k]["before"][1]):
        (nb, cb), (na, ca) = sums[name]["before"], sums[name]["after"]
        ratio = f"{ca / cb:.2f}" if cb else ""
        lines.append(f"| {name} | {nb} | {na} | {cb:.1f} | {ca:.1f} | {ratio} |")
    tb, ta = sum(r["cpu"] for r in before), sum(r["cpu"] for r in after)
    lines.append(f"| **all (per-test sum)** | {len(before)} | {len(after)} | {tb:.1f} | {ta:.1f} "
                 f"| {ta / tb:.2f} |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: python benchmarks/suite_per_test.py BEFORE_DIR AFTER_DIR", file=sys.stderr)
        return 2
    print(table(load(argv[0]), load(argv[1])))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
