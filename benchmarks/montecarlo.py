"""Monte Carlo engine against the reports' way: filterpy once per realization, side by side.

In one run, for both truths:

(a) the plain filterpy loop, one realization at a time, on a sample of realizations: a
    ``KalmanFilter`` from ``model.kalman_filter()``, 6,000 ``predict()`` and 151 ``update()``
    calls per run (the filter alone, measurements drawn beforehand), and the same with the
    simulation of the realization (``gpsaccel.simulate``) included, as the reports' MATLAB did;
(b) ``gpsaccel.monte_carlo`` for 10,000 runs (in this process, no progress bar), and with a
    2-process pool;

and prints the time per realization (wall clock and CPU time) and the ratio (a)/(b).  Then the
peak resident memory (VmHWM) of fresh subprocesses that import gpsaccel only, run 10,000 and
200,000 realizations.

    python benchmarks/montecarlo.py [--sample 30] [--runs 10000] [--big 200000]

Timings are wall-clock on whatever machine runs this; the ratio is the meaningful number, and
both sides run here, one after the other, on the same interpreter.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import subprocess
import sys
import time

import numpy as np

from gpsaccel import CalibrationModel, monte_carlo, simulate

# Peak resident set of the probe process itself: VmHWM of /proc/self/status (ru_maxrss would
# report the parent's peak too, since Linux carries it across fork + exec).
MEMORY_PROBE = """
import sys
from gpsaccel import CalibrationModel, monte_carlo
n = int(sys.argv[1])
if n:
    mc = monte_carlo(CalibrationModel(), n, seed=0, truth=sys.argv[2], progress=False)
    assert mc.n_runs == n
with open("/proc/self/status") as f:
    print(next(line.split()[1] for line in f if line.startswith("VmHWM:")))  # KiB
"""


def filterpy_loop(model: CalibrationModel, z: np.ndarray) -> np.ndarray:
    """The plain filterpy loop of one realization: predict at 200 Hz, update at every GPS fix."""
    kf = model.kalman_filter()
    x_hat = np.empty((model.n_gps, 3))
    kf.update(z[0].reshape(2, 1))
    x_hat[0] = kf.x[:, 0]
    for i in range(1, model.n_gps):
        for _ in range(model.gps_every):
            kf.predict()
        kf.update(z[i].reshape(2, 1))
        x_hat[i] = kf.x[:, 0]
    return x_hat


def time_filterpy(model: CalibrationModel, truth: str, sample: int) -> dict[str, float]:
    """Wall and CPU seconds per realization: the filter alone, and simulate + filter."""
    rng = np.random.default_rng(123)
    t = dict.fromkeys(("sim_wall", "sim_cpu", "wall", "cpu"), 0.0)
    for _ in range(sample):
        w0, c0 = time.perf_counter(), time.process_time()
        run = simulate(model, rng, truth)
        w1, c1 = time.perf_counter(), time.process_time()
        filterpy_loop(model, run.z)
        w2, c2 = time.perf_counter(), time.process_time()
        t["sim_wall"] += w1 - w0
        t["sim_cpu"] += c1 - c0
        t["wall"] += w2 - w1
        t["cpu"] += c2 - c1
    out = {k: v / sample for k, v in t.items()}
    out["sim_wall"] += out["wall"]
    out["sim_cpu"] += out["cpu"]
    return out


def time_engine(model: CalibrationModel, truth: str, runs: int,
                executor=None) -> dict[str, float]:
    """Wall and CPU (this process) seconds per realization of monte_carlo, best of 2 calls."""
    best = {"wall": np.inf, "cpu": np.inf}
    for _ in range(2):
        w0, c0 = time.perf_counter(), time.process_time()
        monte_carlo(model, runs, seed=0, truth=truth, executor=executor, progress=False)
        best["wall"] = min(best["wall"], (time.perf_counter() - w0) / runs)
        best["cpu"] = min(best["cpu"], (time.process_time() - c0) / runs)
    return best


def peak_memory_mib(runs: int, truth: str) -> float:
    out = subprocess.run([sys.executable, "-c", MEMORY_PROBE, str(runs), truth],
                         capture_output=True, text=True, check=True)
    return int(out.stdout.strip()) / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=int, default=30,
                        help="realizations for the filterpy loop (default 30)")
    parser.add_argument("--runs", type=int, default=10_000, help="monte_carlo runs (10000)")
    parser.add_argument("--big", type=int, default=200_000, help="runs for the memory probe")
    args = parser.parse_args()
    model = CalibrationModel()

    print(f"time per realization: filterpy loop on {args.sample} realizations vs "
          f"monte_carlo({args.runs:,}); {model.n_steps} predictions and {model.n_gps} updates "
          f"per realization; wall clock and CPU time of this process (the machine is shared, so "
          f"CPU time is the steadier figure)")
    head = (f"{'truth':<12} {'clock':<5} {'filterpy':>10} {'sim+filterpy':>13} "
            f"{'monte_carlo':>12} {'ratio':>7} {'ratio(sim)':>10}")
    print(head)
    print("-" * len(head))
    rows = {}
    for truth in ("error-model", "kinematic"):
        fp = time_filterpy(model, truth, args.sample)
        mc = time_engine(model, truth, args.runs)
        rows[truth] = fp, mc
        for clock, key, sim in (("wall", "wall", "sim_wall"), ("CPU", "cpu", "sim_cpu")):
            print(f"{truth:<12} {clock:<5} {fp[key] * 1e3:7.2f} ms {fp[sim] * 1e3:10.2f} ms "
                  f"{mc[key] * 1e6:9.1f} µs {fp[key] / mc[key]:6.0f}x {fp[sim] / mc[key]:9.0f}x")
    print("ratio = filterpy loop per realization / monte_carlo per realization (target >= 300x)")

    print(f"\nmonte_carlo({args.runs:,}) on a 2-process pool (wall clock; the pool's start-up "
          f"included)")
    for truth in ("error-model", "kinematic"):
        with cf.ProcessPoolExecutor(max_workers=2) as pool:
            mc2 = time_engine(model, truth, args.runs, executor=pool)
        fp, mc = rows[truth]
        print(f"{truth:<12} {mc2['wall'] * 1e6:7.1f} µs per realization "
              f"(in-process {mc['wall'] * 1e6:.1f} µs; filterpy / pool = "
              f"{fp['wall'] / mc2['wall']:.0f}x)")

    print("\npeak resident memory (VmHWM of a fresh process)")
    print(f"{'runs':>11} {'truth':<12} {'peak MiB':>9}")
    for runs, truth in ((0, "-"), (args.runs, "error-model"), (args.big, "error-model"),
                        (args.big, "kinematic")):
        t0 = time.perf_counter()
        mib = peak_memory_mib(runs, truth if runs else "error-model")
        label = "import only" if runs == 0 else f"{runs:,}"
        print(f"{label:>11} {truth:<12} {mib:9.1f}   ({time.perf_counter() - t0:.1f} s)")
    print("target: 200,000 runs under 1 GB (1024 MiB)")


if __name__ == "__main__":
    main()
