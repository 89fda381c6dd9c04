"""A class of 100 by-hand 200 Hz calibration filters through ``gpsaccel check``, on this machine.

The class: 100 files copied from the by-hand fixtures of tests/submissions that step at 200 Hz
(covariance, Joseph and information forms, and mistakes of the catalogue), checked by
:func:`gpsaccel.classrun.check_many` with local processes (one per CPU), as the CLI does.
Prints the wall time of the whole class at the checker's default n_runs, and, side by side in
the same run, a 10-file slice at the default and at the former default of 200 runs (the ratio is
what fewer runs buys).

Usage: python benchmarks/check_class.py [--files N]
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from gpsaccel.check.problems.calibration import DEFAULT_RUNS
from gpsaccel.classrun import check_many

HERE = Path(__file__).resolve().parents[1] / "tests" / "submissions"
BY_HAND_200HZ = ["correct_covariance.py", "correct_joseph.py", "correct_information.py",
                 "mutant_phi_sign.py", "mutant_m0_order.py", "mutant_std_as_variance.py",
                 "mutant_x0_total_state.py", "mutant_first_update_skipped.py",
                 "mutant_w_value.py", "mutant_returns_a_priori.py"]


def make_class(folder: Path, n: int) -> list[Path]:
    paths = []
    for i in range(n):
        src = HERE / BY_HAND_200HZ[i % len(BY_HAND_200HZ)]
        dst = folder / f"student{i:03d}_{src.name}"
        shutil.copyfile(src, dst)
        paths.append(dst)
    return paths


def timed(paths: list[Path], n_runs: int) -> tuple[float, int]:
    t0 = time.perf_counter()
    results = check_many(paths, n_runs=n_runs, seed=0, timeout=120, executor="processes")
    return time.perf_counter() - t0, sum(r["passed"] for r in results)


def main(argv: list[str]) -> int:
    n = int(argv[argv.index("--files") + 1]) if "--files" in argv else 100
    with tempfile.TemporaryDirectory(prefix="gpsaccel-class-") as tmp:
        paths = make_class(Path(tmp), n)
        print(f"{os.cpu_count()} CPUs; {n} by-hand 200 Hz filters "
              f"({len(BY_HAND_200HZ)} kinds, 3 correct)")
        secs, passed = timed(paths, DEFAULT_RUNS)
        print(f"whole class, n_runs = {DEFAULT_RUNS} (default): {secs:6.1f} s wall "
              f"({secs / 60:.2f} min), {passed} passed")
        part = paths[:10]
        s_small, _ = timed(part, DEFAULT_RUNS)
        s_big, _ = timed(part, 200)
        print(f"10-file slice, side by side: n_runs = {DEFAULT_RUNS}: {s_small:6.1f} s; "
              f"n_runs = 200: {s_big:6.1f} s; ratio {s_big / s_small:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
