"""The filter forms side by side: time of one 30-s calibration run (6000 predictions at 200 Hz,
151 GPS updates) for each built-in form, and for the exact reference (mpmath, GPS rate).

    python benchmarks/filter_forms.py [--repeat 5] [--digits 50]

All timed in one process, in turn, on the same realization; the best of ``--repeat`` runs is
kept.  CPU time of this process (a busy machine stretches wall time, not this) on whatever machine
runs this; the ratio to filterpy's Joseph form is the meaningful number, and ``make bench``
publishes it (benchmarks/_figures.py) for docs/comparing-filters.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _figures import publish

from gpsaccel import CalibrationModel, simulate
from gpsaccel.kalman.exact import exact_filter
from gpsaccel.kalman.factory import FORMS
from gpsaccel.kalman.multirate import run_form


def best_of(repeat: int, f) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        f()
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per filter (best kept)")
    parser.add_argument("--digits", type=int, default=50, help="digits of the exact reference")
    args = parser.parse_args()
    model = CalibrationModel()
    z = simulate(model, np.random.default_rng(0)).z
    times = {name: best_of(args.repeat, lambda name=name: run_form(name, model, z))
             for name in FORMS}
    times[f"exact (mpmath, {args.digits} digits)"] = best_of(
        max(1, args.repeat // 2), lambda: exact_filter(model, z, args.digits))
    base = times["joseph"]
    print(f"{'filter':<28} {'CPU ms/run':>10} {'x joseph':>9}")
    for name, t in times.items():
        print(f"{name:<28} {1e3 * t:10.1f} {t / base:9.2f}")
    publish({f"x_joseph/{name.split()[0]}": t / base for name, t in times.items()}
            | {f"cpu_ms/{name.split()[0]}": 1e3 * t for name, t in times.items()})


if __name__ == "__main__":
    main()
