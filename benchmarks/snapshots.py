"""The cost of reading a notebook's answers early (issue 42 item 1,
:mod:`gpsaccel.assignments.snapshots`): one filled notebook of each homework graded three ways,
alternated, the median of ``--repeats`` R:

* "before": the reads after the last cell only, one call of the box each (as the grader made
  them before issue 42: every question's answer cell unknown, ``boxcalls.BATCH`` = 1);
* "early": the reads after each answer cell too, one call each;
* "now": the reads after each answer cell too, the reads of one function in a group stacked in
  one call (``boxcalls.BATCH``).

"box CPU" is the notebook's box (every cell, every read): the children's CPU around
``sandbox.run``; "grade CPU" is the whole :func:`~gpsaccel.assignments.scoring.grade_notebook`
(this process and its children: the parse, the answer cells' parse, the box, the file question's
box, the reference answers).  The filled notebooks are the masters' solutions as a student hands
them in (tests/assignments/conftest.py ``solved``), each with one exploratory last cell that
binds nothing a question reads (``x = 1``), so that the early groups are not the final one.

Usage: python benchmarks/snapshots.py [--repeats R]
"""

from __future__ import annotations

import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gpsaccel import registry  # noqa: E402
from gpsaccel import sandbox as sb  # noqa: E402
from gpsaccel.assignments import boxcalls, grading, scoring, snapshots  # noqa: E402
from tests.assignments.conftest import write_variant  # noqa: E402


def _cpu(who: int) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def _all_cpu() -> float:
    return _cpu(resource.RUSAGE_SELF) + _cpu(resource.RUSAGE_CHILDREN)


class _Measured:
    """``sandbox.run`` wrapped to add its children's CPU and its calls to a tally."""

    def __init__(self) -> None:
        self.box = 0.0
        self.calls = 0
        self.real = sb.run

    def __call__(self, sub, calls, *args, **kwargs):  # noqa: ANN001, ANN204
        c0 = _cpu(resource.RUSAGE_CHILDREN)
        try:
            return self.real(sub, calls, *args, **kwargs)
        finally:
            if calls and calls[0].function == "_gpsaccel_cell":  # the notebook's box
                self.box += _cpu(resource.RUSAGE_CHILDREN) - c0
                self.calls = len(calls)


#: The ways of grading compared: (early reads, reads per call).
WAYS = {"before": (False, 1), "early": (True, 1), "now": (True, boxcalls.BATCH)}


def _once(path: Path, name: str, way: str) -> tuple[float, float, int]:
    """(grade CPU, box CPU, the box's calls) of one grading, one of :data:`WAYS`."""
    early, batch = WAYS[way]
    measured = _Measured()
    real_answer_cells, real_batch = snapshots.answer_cells, boxcalls.BATCH
    sb.run = measured  # type: ignore[assignment]  # restored below
    boxcalls.BATCH = batch
    if not early:
        snapshots.answer_cells = lambda run, checks, questions: dict.fromkeys(questions)
    try:
        c0 = _all_cpu()
        scoring.grade_notebook(path, name, "student", seed=1, timeout=120)
        return _all_cpu() - c0, measured.box, measured.calls
    finally:
        sb.run = measured.real
        snapshots.answer_cells, boxcalls.BATCH = real_answer_cells, real_batch


def main(argv: list[str]) -> int:
    repeats = int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 3
    rows = []
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-snap-") as tmp:
        for name in registry.assignments():
            path = write_variant(name, Path(tmp) / name / f"{name}.ipynb", last_cell="x = 1")
            grading.warm(name)
            _once(path, name, "now")  # the first grading's imports, in no column
            samples: dict[str, list[tuple[float, float, int]]] = {w: [] for w in WAYS}
            for _ in range(repeats):
                for way in WAYS:
                    samples[way].append(_once(path, name, way))
            row = [name]
            for k in range(2):
                row += [f"{statistics.median(s[k] for s in samples[w]):.2f}" for w in WAYS]
            row += [" / ".join(str(samples[w][0][2]) for w in WAYS)]
            rows.append(row)
    load = os.getloadavg()
    print(f"load {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} (1/5/15 min) on {os.cpu_count()} "
          f"CPUs; medians of {repeats}, alternated; CPU = user + system, children included; "
          f"{time.strftime('%Y-%m-%d')}")
    print()
    print("| homework | grade CPU s before | early | now | box CPU s before | early | now "
          "| box calls before / early / now |")
    print("|---|---|---|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
