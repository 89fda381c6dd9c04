"""The ship's Monte Carlo: one filter run per realization against one gain sequence for all.

For each of the ship's filters (report 004), on the same ensemble, side by side in one run:

(a) ``run_multirate`` (filterpy) or ``run_zeroed_gain`` called once per realization, on a sample
    of realizations (time per run, scaled to the ensemble);
(b) one filter run for the gains, then ``apply_gains`` moving the whole ensemble as arrays;

and prints the seconds for the ensemble and the ratio (a)/(b), plus the largest difference of the
estimates between (a) and (b) on the sample (they must agree to rounding).

    python benchmarks/ship_ensemble.py [--runs 200] [--sample 10]

Timings are wall-clock on whatever machine runs this; the ratio is the meaningful number.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gpsaccel.kalman.gain_sequence import apply_gains
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.simulation import simulate_ensemble
from gpsaccel.ship.zeroed_gain import run_zeroed_gain


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--sample", type=int, default=10)
    args = parser.parse_args()
    model = ShipModel()
    ens = simulate_ensemble(model, args.runs, np.random.default_rng(0))
    filters = {
        "monorate (filterpy)": (model.schedule(multirate=False),
                                lambda z, s: run_multirate(model, z, schedule=s, u=ens.u)),
        "multirate (filterpy)": (model.schedule(multirate=True),
                                 lambda z, s: run_multirate(model, z, schedule=s, u=ens.u)),
        "zeroed gain (Joseph)": (model.schedule(multirate=True),
                                 lambda z, s: run_zeroed_gain(model, z, schedule=s, u=ens.u)),
    }
    print(f"ship ensemble: {args.runs} runs x {model.n_steps} steps; per-run loop timed on "
          f"{args.sample} runs and scaled")
    head = f"{'filter':<22} {'(a) loop, s':>12} {'(b) gains, s':>13} {'ratio a/b':>10} {'max|dx|':>9}"
    print(head)
    print("-" * len(head))
    for name, (sched, run) in filters.items():
        z = ens.measurements(sched)
        t0 = time.perf_counter()
        singles = [run(z[r], sched).x_hat for r in range(args.sample)]
        loop = (time.perf_counter() - t0) / args.sample * args.runs
        t0 = time.perf_counter()
        first = run(z[0], sched)
        est = apply_gains(model.Phi, model.H, model.x0, sched, first.K, z, B=model.B, u=ens.u)
        gains = time.perf_counter() - t0
        dx = max(np.abs(est.x_hat[r] - singles[r]).max() for r in range(args.sample))
        print(f"{name:<22} {loop:12.2f} {gains:13.3f} {loop / gains:10.1f} {dx:9.1e}")


if __name__ == "__main__":
    main()
