"""False alarms of the generic linear checker (check.Problem.linear) on the tracker problem.

For SEEDS seeds, the student-style tracker of tests/submissions/tracker/student.py is run, correct
and with each generic mistake, on the check's realizations, and the problem's verdict is formed
(:meth:`LinearProblem.evaluate`, the decision and the diagnosis, exactly as a check forms them;
the student's function is called in this process since the fixture is trusted, so the count is
the checker's, not the sandbox's).  Counted:

* false alarms: the correct filter fails (the decision compares with the one optimal answer to
  1e-6 σ, so the expected count is 0);
* misnamed mistakes: a mistake whose codes are not exactly its own;
* consistency warnings on the correct filter (information only; two tests at family-wise
  alpha = 0.01 each, so at most 2 % expected).

Usage: python benchmarks/linear_false_alarms.py [SEEDS] [N_RUNS]   (default 100 seeds, 10 runs)
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

from gpsaccel.check.problems.tracker import TRACKER
from gpsaccel.check.report import Report

HERE = Path(__file__).resolve().parents[1] / "tests"
sys.path.insert(0, str(HERE.parent))  # the tests as a package: their modules import each other
from tests.check.test_linear import GENERIC  # noqa: E402 - the tests' table of mistakes, codes

STUDENT = HERE / "submissions" / "tracker" / "student.py"


def _student(mistake: str | None):
    spec = importlib.util.spec_from_file_location("student", STUDENT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.MISTAKE = mistake
    return module.kalman_filter


def verdict(mistake: str | None, n_runs: int, seed: int) -> Report:
    f = _student(mistake)
    cases = TRACKER.cases(n_runs, seed)
    results = []
    for z in cases.z:
        x, P = f(z)
        results.append({"x_hat": np.asarray(x, dtype=float), "P": np.asarray(P, dtype=float)})
    dtype = {"dtype": str(np.asarray(f(cases.z[0])[0]).dtype)}
    report = Report(str(mistake))
    # (no forget(): the fixture is trusted, so the catalogue's candidates are kept across checks)
    TRACKER.evaluate(report, cases, TRACKER.functions[0], results, {"x_hat": dtype, "P": dtype})
    return report


def main(seeds: int = 100, n_runs: int = 10) -> None:
    t0 = time.perf_counter()
    failed = warned = 0
    misnamed: dict[str, int] = {}
    for seed in range(seeds):
        r = verdict(None, n_runs, seed)
        failed += not r.passed
        warned += any(f.code == "inconsistent" for f in r.findings)
        for mistake, codes in GENERIC.items():
            if verdict(mistake, n_runs, seed).codes != codes:
                misnamed[mistake] = misnamed.get(mistake, 0) + 1
        print(f"seed {seed}: failed {failed}, warned {warned}, misnamed "
              f"{sum(misnamed.values())}", file=sys.stderr, flush=True)
    print(f"tracker, {seeds} seeds x {n_runs} runs, {len(GENERIC)} generic mistakes "
          f"({time.perf_counter() - t0:.0f} s)")
    print(f"  correct filter failed:            {failed} of {seeds}")
    print(f"  correct filter consistency warned: {warned} of {seeds} (information only)")
    print(f"  mistakes misnamed:                {sum(misnamed.values())} of "
          f"{seeds * len(GENERIC)} {misnamed or ''}")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
