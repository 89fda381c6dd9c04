"""Peak memory and time of the Monte Carlo engine against the duration, side by side with the
engine that kept the full (2·n_gps)² matrix of residual products.

For each duration (30, 300, 3,600 s by default; n_gps = 5 Hz · duration + 1) and each engine, a
fresh subprocess imports gpsaccel, runs ``monte_carlo(CalibrationModel(duration=d), RUNS)`` in
the process (no pool) and reports its CPU time (the call's, not the imports') and its peak
resident set (VmHWM of /proc/self/status).  The floor, a process that imports the same and runs
nothing, is measured alike (``0`` runs), and the current engine's peak at the 30 s model for
1,000 to 100,000 runs (memory flat in the runs).  The baseline engine is the package as of
``--baseline`` (a git revision, default 08a64c0, the last commit before the linear-memory
engine), extracted with ``git archive`` into a temporary folder.  Each probe runs under an
address-space limit (``--limit-gib``, default 4) so that the old engine's 10 GB request fails as
a MemoryError instead of taking the shared machine's memory.

    python benchmarks/montecarlo_memory.py [--runs 2000] [--durations 30 300 3600]

Times are CPU seconds on whatever machine runs this (a busy machine stretches wall time, not
these); both engines run here, one after the other.  ``make bench`` publishes the figures
(benchmarks/_figures.py) that docs/comparing-filters.md quotes.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from _figures import publish

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
import json, resource, sys, time
limit = int(float(sys.argv[3]) * 2**30)
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
from gpsaccel import CalibrationModel, monte_carlo
model = CalibrationModel(duration=float(sys.argv[1]))
out = {"n_gps": model.n_gps}
t0 = time.process_time()
try:
    chunk = None if sys.argv[4] == "None" else int(sys.argv[4])
    if int(sys.argv[2]):
        mc = monte_carlo(model, int(sys.argv[2]), seed=0, progress=False, chunk_size=chunk)
        out["P_ave_end"] = float(mc.P_ave[-1, 0, 0])
    out["seconds"] = time.process_time() - t0
except MemoryError as exc:
    out["error"] = f"MemoryError {exc}"
with open("/proc/self/status") as f:
    out["peak_mib"] = int(next(l.split()[1] for l in f if l.startswith("VmHWM:"))) / 1024
print(json.dumps(out))
"""


def probe(path: Path, duration: float, runs: int, limit_gib: float, chunk: int | None = None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(path), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    res = subprocess.run([sys.executable, "-c", PROBE, str(duration), str(runs), str(limit_gib),
                          str(chunk)],
                         env=env, capture_output=True, text=True, cwd=path)
    if res.returncode != 0:
        last = (res.stderr.strip().splitlines() or ["?"])[-1]
        return {"error": last[:60]}
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--durations", type=float, nargs="+", default=[30.0, 300.0, 3600.0])
    parser.add_argument("--baseline", default="08a64c0")
    parser.add_argument("--limit-gib", type=float, default=4.0)
    parser.add_argument("--chunk-runs", type=int, default=500,
                        help="runs of the chunk_size table (30 s model)")
    parser.add_argument("--flat-runs", type=int, nargs="+", default=[1000, 10_000, 100_000],
                        help="runs of the peak-against-runs table (30 s model, current engine)")
    args = parser.parse_args()
    figures: dict[str, float] = {}
    with tempfile.TemporaryDirectory(prefix="gpsaccel-baseline-") as tmp:
        archive = subprocess.run(["git", "archive", args.baseline, "gpsaccel"], cwd=ROOT,
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        engines = {"before": Path(tmp), "now": ROOT}
        floor = probe(ROOT, 30.0, 0, args.limit_gib)
        figures["imports_mib"] = floor["peak_mib"]
        print(f"monte_carlo(CalibrationModel(duration=d), {args.runs:,} runs), in-process, one "
              f"fresh process per cell; peak = VmHWM, including the imports (a process that "
              f"imports the same and runs nothing: {floor['peak_mib']:.1f} MiB); CPU s of the "
              f"call; address space limited to {args.limit_gib:g} GiB; before = the engine "
              f"as of {args.baseline}\n")
        head = (f"{'duration':>9} {'n_gps':>6} | {'before: peak':>14} {'CPU':>8} | "
                f"{'now: peak':>11} {'CPU':>8} | {'peak ratio':>10}")
        print(head)
        print("-" * len(head))
        for d in args.durations:
            cells = {name: probe(path, d, args.runs, args.limit_gib)
                     for name, path in engines.items()}
            old, new = cells.values()

            def fmt(c, width):
                if "seconds" not in c:
                    return f"{'MemoryError' if 'Memory' in c.get('error', '') else 'failed':>{width}} {'':>8}"
                return f"{c['peak_mib']:{width - 4}.1f} MiB {c['seconds']:7.2f}s"

            ratio = (f"{old['peak_mib'] / new['peak_mib']:10.1f}"
                     if "seconds" in old and "seconds" in new else f"{'—':>10}")
            print(f"{d:8g}s {new.get('n_gps', old.get('n_gps', 0)):6d} | {fmt(old, 14)} | "
                  f"{fmt(new, 11)} | {ratio}")
            for name, c in cells.items():
                if "error" in c:
                    print(f"    {name}: {c['error']}")
                else:
                    figures[f"peak_mib/{name}/{d:g}"] = c["peak_mib"]
                    figures[f"cpu_s/{name}/{d:g}"] = c["seconds"]
            if "seconds" in old and "seconds" in new:
                assert abs(old["P_ave_end"] - new["P_ave_end"]) <= 1e-12 * abs(old["P_ave_end"])
        print("\nthe 30 s model, the current engine: peak against the number of runs\n")
        head = f"{'runs':>8} | {'peak':>10} | {'CPU':>8}"
        print(head)
        print("-" * len(head))
        for runs in args.flat_runs:
            c = probe(ROOT, 30.0, runs, args.limit_gib)
            figures[f"peak_mib/now/30/{runs}runs"] = c["peak_mib"]
            print(f"{runs:8,} | {c['peak_mib']:6.1f} MiB | {c['seconds']:7.2f}s")
        print(f"\nchunk_size: {args.chunk_runs:,} runs of the 30 s model, CPU s\n")
        head = f"{'chunk_size':>10} | {'before':>8} | {'now':>8}"
        print(head)
        print("-" * len(head))
        for chunk in (None, 100, 1):
            t = [probe(path, 30.0, args.chunk_runs, args.limit_gib, chunk)["seconds"]
                 for path in engines.values()]
            for name, seconds in zip(engines, t, strict=True):
                figures[f"cpu_s/{name}/chunk/{chunk or 'default'}"] = seconds
            print(f"{str(chunk or 'default'):>10} | {t[0]:8.2f} | {t[1]:8.2f}")
    publish(figures)


if __name__ == "__main__":
    main()
