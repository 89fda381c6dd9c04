"""Cooperative localization (report 002): the one filter one run at a time against many at once.

In one run, for the LKF, the EKF and the UKF with their tuned Q: ``run_lkf`` / ``run_ekf`` /
``run_ukf`` (one 100-second run at a time; since issue 31 the same vectorised filter on one log,
filterpy's objects being the tests' oracle) on a sample of truth runs, and ``run_batch`` on
``--runs`` runs at once; prints the time per 100-second run of each, their ratio, and the largest
difference of the estimates (the same filter: 0).

    python benchmarks/coop_filters.py [--sample 5] [--runs 50]

Wall-clock timings on whatever machine runs this; the ratio is the meaningful number.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gpsaccel.coop.filters import METHODS, run_batch, run_filter
from gpsaccel.coop.model import CoopModel, state_residual


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=int, default=5, help="filterpy runs to time")
    parser.add_argument("--runs", type=int, default=50, help="runs of the vectorised filter")
    args = parser.parse_args()
    model = CoopModel()
    truth = model.simulate(np.random.default_rng(0), args.runs)
    print(f"{'filter':<6} {'filterpy s/run':>15} {'vectorised s/run':>17} {'ratio':>7} "
          f"{'max |Δx̂|':>10}")
    for method in METHODS:
        t0 = time.perf_counter()
        singles = [run_filter(method, model, truth.y[i]) for i in range(args.sample)]
        t_one = (time.perf_counter() - t0) / args.sample
        t0 = time.perf_counter()
        batch = run_batch(method, model, truth.y)
        t_batch = (time.perf_counter() - t0) / args.runs
        diff = max(np.abs(state_residual(s.x_hat, batch.x_hat[i])).max()
                   for i, s in enumerate(singles))
        print(f"{method.upper():<6} {t_one:15.4f} {t_batch:17.5f} {t_one / t_batch:7.1f} "
              f"{diff:10.1e}")


if __name__ == "__main__":
    main()
