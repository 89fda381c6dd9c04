"""Why the coop Monte Carlo filters its runs in calls of up to ``_CHUNK_RUNS``: the CPU of one
100-second EKF run against the number of runs a call holds.

``gpsaccel.coop.montecarlo`` stacks runs into few filter calls because each step of a call has a
cost of its own (Python and numpy dispatch), shared by every run in it; the output grows with the
runs (the call's memory), so the size is where the per-run CPU has flattened.  Each size filters
the same truth set (``truth_runs``, seed 0) ``--repeats`` times, the sizes alternating; the table
gives the median process CPU (user + system) per run.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import sys

import _cpu
import _figures

from gpsaccel.coop import montecarlo as mc
from gpsaccel.coop.model import CoopModel

SIZES = (25, 50, 100, 200)


def _cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200, help="runs filtered per measurement")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    for name in ("runs", "repeats"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be a positive integer, got {getattr(args, name)}")
    model = CoopModel()
    truth = mc.truth_runs(model, args.runs, 0)
    Q = mc.tuned_q("ekf", model)
    start = _cpu.load()
    per_run: dict[int, list[float]] = {n: [] for n in SIZES}
    default = mc._CHUNK_RUNS
    try:
        for _ in range(args.repeats):
            for n in SIZES:
                mc._CHUNK_RUNS = n
                t0 = _cpu_s()
                mc.consistency_test(model, "ekf", Q, truth=truth)
                per_run[n].append((_cpu_s() - t0) / args.runs)
    finally:
        mc._CHUNK_RUNS = default
    print(f"start: {start}")
    print(f"end: {_cpu.load()}; {args.runs} EKF runs of {model.t[-1]:g} s a measurement, medians "
          f"of {args.repeats}, process CPU (user + system); the package's size: {default}\n")
    print("| runs a call | CPU ms a run |")
    print("|---|---|")
    for n in SIZES:
        print(f"| {n} | {1e3 * statistics.median(per_run[n]):.1f} |")
    _figures.publish({f"cpu_ms/run/{n}": 1e3 * statistics.median(per_run[n]) for n in SIZES})
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
