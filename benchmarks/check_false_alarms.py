"""False alarms of the checker: every correct fixture of every problem on many seeds.

A false alarm is a correct filter that does not pass; "warnings" counts the checks with any
warning (for the calibration problem: the informational consistency tests, family-wise 1 % each).
For each problem the correct fixtures of tests/submissions are checked on SEEDS seeds at the
problem's default n_runs; the table gives the checks, the failures, and the largest distance to
the reference seen (units of the reference σ) against the tolerance, i.e. the margin an honest
filter keeps.

Usage: python benchmarks/check_false_alarms.py [--seeds N]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from gpsaccel import check

SUBS = Path(__file__).resolve().parents[1] / "tests" / "submissions"
CORRECT = {
    "calibration": [SUBS / n for n in ("correct_covariance.py", "correct_joseph.py",
                                       "correct_information.py", "correct_filterpy.py",
                                       "correct_gps_rate.py", "correct_lists.py")],
    "coop": sorted((SUBS / "coop").glob("correct_*.py")) + [SUBS / "coop" /
                                                             "honest_p_short_form.py"],
    "ship": sorted((SUBS / "ship").glob("correct_*.py")),
}


def _distances(report, problem: str) -> dict[str, tuple[float, float]]:
    """{filter: (max |Δx̂|/σ, max |ΔP|/σσ)} of one report."""
    d = report.details
    if problem == "calibration":
        return {"kalman_filter": (d["max_dx_sigma"], d["max_dP_sigma"])}
    keys = ("ship",) if problem == "ship" else ("ekf", "lkf")
    return {k: (d[k]["max_dx_sigma"], d[k]["max_dP_sigma"]) for k in keys if k in d}


def main(argv: list[str]) -> int:
    seeds = int(argv[argv.index("--seeds") + 1]) if "--seeds" in argv else 20
    print(f"{'problem':<12} {'checks':>6} {'false alarms':>12} {'warnings':>8}  s/check  largest "
          f"distance of a correct filter (|Δx̂|/σ, |ΔP|/σσ) per function; failures")
    for problem, files in CORRECT.items():
        fails, worst, t0, n, warned = [], {}, time.perf_counter(), 0, 0
        for seed in range(seeds):
            for f in files:
                report = check.submission(f, problem=problem, seed=seed)
                n += 1
                warned += any(f.severity == "warning" for f in report.findings)
                if not report.passed:
                    fails.append(f"{f.name}@{seed}:{','.join(report.codes)}")
                    continue
                for k, (a, b) in _distances(report, problem).items():
                    wa, wb = worst.get(k, (0.0, 0.0))
                    worst[k] = (max(wa, a), max(wb, b))
        dist = ", ".join(f"{k} ({a:.2g}, {b:.2g})" for k, (a, b) in worst.items())
        print(f"{problem:<12} {n:>6} {len(fails):>12} {warned:>8}  "
              f"{(time.perf_counter() - t0) / n:7.2f}  "
              f"{dist}; {'; '.join(fails) or 'no failures'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
