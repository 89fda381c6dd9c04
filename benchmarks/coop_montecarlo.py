"""Cooperative localization (report 002): CPU of lesson 11's Monte Carlo calls.

The calls lesson 11 makes at its full size (N = 50): a truth set, one EKF consistency test,
``tune_q`` over 6 candidates, ``repeated_sets`` 3 x (EKF Q = Qtrue, EKF tuned, UKF), 10 EKF sets,
and four single-run UKFs (α = 1, 0.5 on two runs).  Prints the process CPU (children included)
of each and the load average, and two checksums of the results (the sum of tune_q's NEES
fractions and of the UKF sets'), which must not move between versions.

    python benchmarks/coop_montecarlo.py

Run it on two versions back to back (e.g. two worktrees) at the same load: the ratio of their
CPU is the meaningful number.  Measured at load 6-7 on 2 cores (issue 31): before the one
filter 51.2 CPU s, after 35.3; checksums [3.759, 2.858] both.
"""

from __future__ import annotations

import json
import os

from gpsaccel.coop import filters as nl
from gpsaccel.coop.model import CoopModel
from gpsaccel.coop.montecarlo import consistency_test, repeated_sets, truth_runs, tune_q


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def main() -> None:
    m, N = CoopModel(), 50
    res: dict[str, object] = {"load before": os.getloadavg()[0]}

    def meas(name, fn):
        c = _cpu()
        value = fn()
        res[name] = round(_cpu() - c, 2)
        return value

    truth = meas("truth 50", lambda: truth_runs(m, N, seed=7))
    meas("ekf consistency 50", lambda: consistency_test(m, "ekf", m.Qtrue, truth=truth, keep=True))
    tq = meas("tune_q 6x50", lambda: tune_q(m, "ekf", grid=((1, 2, 4), (1, 2), (1,)), n_runs=N,
                                            seed=2024))
    sets = meas("repeated 9 sets (6 ekf 3 ukf)", lambda: [
        repeated_sets(m, "ekf", m.Qtrue, n_sets=3, n_runs=N, seed=11),
        repeated_sets(m, "ekf", n_sets=3, n_runs=N, seed=11),
        repeated_sets(m, "ukf", m.Qtrue, n_sets=3, n_runs=N, seed=11)])
    meas("repeated 10 ekf sets", lambda: repeated_sets(m, "ekf", n_sets=10, n_runs=N, seed=21))
    meas("run_ukf 2 runs x 2 alphas", lambda: [nl.run_ukf(m, truth.y[i], m.Qtrue, alpha=a)
                                               for a in (1.0, 0.5) for i in range(2)])
    res["total CPU s"] = round(sum(v for k, v in res.items() if k != "load before"), 2)
    res["load after"] = os.getloadavg()[0]
    res["checksums"] = [round(float(tq.nees_fraction.sum()), 6),
                        round(float(sum(c.nees_fraction for c in sets[2])), 6)]
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
