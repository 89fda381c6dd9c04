"""How many realizations does the calibration checker need?  Detection against n_runs, and time.

The pass decision compares the student's (x̂, P) with the one optimal answer run by run, so a few
realizations should decide as well as 200; only the informational consistency statistics want
many.  For every calibration fixture in tests/submissions (correct forms and every mistake, the
sharper diagnoses included) and each n_runs, this checks on SEEDS seeds whether the report has
exactly the expected codes, and times the check.  Prints one table; ``--quick`` uses fewer sizes.

Usage: python benchmarks/check_runs.py [--quick]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from gpsaccel import check

HERE = Path(__file__).resolve().parents[1] / "tests" / "submissions"

EXPECTED = {
    "correct_covariance.py": [], "correct_information.py": [], "correct_joseph.py": [],
    "correct_filterpy.py": [], "correct_gps_rate.py": [], "correct_lists.py": [],
    "mutant_phi_sign.py": ["phi-sign"],
    "mutant_process_noise_interval.py": ["process-noise-interval"],
    "mutant_m0_order.py": ["m0-order"], "mutant_std_as_variance.py": ["std-as-variance"],
    "mutant_missing_propagation.py": ["missing-propagation"],
    "mutant_mean_not_propagated.py": ["mean-not-propagated"],
    "mutant_x0_total_state.py": ["x0-total-state"],
    "mutant_returns_a_priori.py": ["returns-a-priori"],
    "mutant_first_update_skipped.py": ["first-update-skipped"],
    "mutant_w_value.py": ["w-value"], "mutant_two_mistakes.py": ["phi-sign", "x0-total-state"],
    "report003.py": ["process-noise-interval", "std-as-variance"],
    "mutant_residual_index.py": ["gain-or-residual"], "mutant_diagonal_q.py": ["p-mismatch"],
    "mutant_float32.py": ["low-precision"], "mutant_p_scaled.py": ["p-scaled"],
    "mutant_epoch_shift.py": ["epoch-shift"],
    "mutant_last_update_missing.py": ["last-update-missing"],
    "mutant_aliased_output.py": ["aliased-output"],
    "mutant_global_m0.py": ["state-between-calls"],
    "mutant_state_between_calls.py": ["wrong-shape"],
    "mutant_p_update_skipped_at_0.py": ["first-update-skipped"],
}


def main(argv: list[str]) -> int:
    sizes = (2, 5, 20) if "--quick" in argv else (2, 3, 5, 10, 20, 50, 200)
    seeds = (0, 1) if "--quick" in argv else (0, 1, 2)
    print(f"{len(EXPECTED)} calibration fixtures x seeds {seeds}: exact expected codes?")
    print(f"{'n_runs':>6}  {'right':>9}  {'mean s/check':>12}  {'max s':>6}  missed")
    for n in sizes:
        right, times, missed = 0, [], []
        for seed in seeds:
            for name, codes in EXPECTED.items():
                t0 = time.perf_counter()
                report = check.submission(HERE / name, n_runs=n, seed=seed)
                times.append(time.perf_counter() - t0)
                if report.codes == codes:
                    right += 1
                else:
                    missed.append(f"{name}@{seed}:{','.join(report.codes) or 'passed'}")
        total = len(seeds) * len(EXPECTED)
        print(f"{n:>6}  {right:>4}/{total:<4}  {sum(times) / len(times):12.2f}  "
              f"{max(times):6.2f}  {'; '.join(missed) or '-'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
