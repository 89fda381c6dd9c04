r"""The calibration homework's own checks (question 3: Monte Carlo NEES at 30 s).

Questions 1 and 2 are graded by :mod:`gpsaccel.check` (the matrix and whole-filter checkers).
Question 3 asks for the ensemble-average NEES at t = 30 s over N runs of the course filter and the
two-sided 95 % bounds it should lie within::

    ε̄ = (1/N) Σᵢ eᵢᵀ Pᵢ⁻¹ eᵢ,     N ε̄ ~ χ²(3N)  →  [r1, r2] = χ²⁻¹_{3N}(0.025, 0.975) / N

:func:`calibration_ensemble` rebuilds the ensemble the notebook gives the student (same seed), so a
hidden test does not trust the student's arrays; :func:`check_nees_answer` compares the answers
and names the typical mistakes under stable codes.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from gpsaccel import registry
from gpsaccel.check.report import Report

#: Relative tolerance of the NEES answer (it is a deterministic function of the seeded ensemble).
RTOL = 1e-6


def calibration_ensemble(n_runs: int = 50, seed: int = 2026
                         ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """The notebook's ensemble: (N, x_true (N, n_gps, 3), x_hat (N, n_gps, 3), P (N, n_gps, 3, 3)).

    ``n_runs`` realizations of report 000's problem from ``numpy.random.default_rng(seed)``, each
    filtered by the package's multirate filter (:func:`gpsaccel.run_multirate`).  Computed once
    per process and seed; every call returns fresh copies (a notebook may change its arrays).
    """
    N, x_true, x_hat, P = _ensemble(int(n_runs), int(seed))
    return N, x_true.copy(), x_hat.copy(), P.copy()


@lru_cache(maxsize=2)
def _ensemble(n_runs: int, seed: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    from gpsaccel.calibration.model import CalibrationModel
    from gpsaccel.calibration.simulation import simulate
    from gpsaccel.kalman.multirate import run_multirate

    model = CalibrationModel()
    rng = np.random.default_rng(seed)
    runs = [simulate(model, rng) for _ in range(n_runs)]
    results = [run_multirate(model, r.z) for r in runs]
    return (n_runs, np.stack([r.x_gps for r in runs]), np.stack([r.x_hat for r in results]),
            np.stack([r.P for r in results]))


def nees_reference(x_true: np.ndarray, x_hat: np.ndarray, P: np.ndarray, k: int = -1
                   ) -> tuple[float, tuple[float, float]]:
    """(ε̄ at GPS index ``k``, its two-sided 95 % bounds) for the ensemble."""
    N, n = x_true.shape[0], x_true.shape[-1]
    e = x_true[:, k] - x_hat[:, k]
    eps = float(np.mean(np.einsum("ri,ri->r", e, np.linalg.solve(P[:, k], e[..., None])[..., 0])))
    from scipy import stats  # here: the registry imports this module to list the homework

    lo, hi = stats.chi2.ppf([0.025, 0.975], n * N) / N
    return eps, (float(lo), float(hi))


def _number(report: Report, name: str, value: object, part: str = "") -> float | None:
    if value is None:  # np.asarray(None, dtype=float) is nan: a missing return would read "= nan"
        report.add("not-a-number", text="{where} is None: the function must return one number "
                   "(end it with a return statement).", where=name, observed={"value": "None"},
                   part=part)
        return None
    try:
        out = float(np.asarray(value, dtype=float).reshape(()))
    except (TypeError, ValueError):
        report.add("not-a-number", text="{where} must be one number; got {type} {value}.",
                   where=name, observed={"type": type(value).__name__,
                                         "value": str(value)[:80]}, part=part)
        return None
    if not math.isfinite(out):
        report.add("not-a-number", text="{where} = {value}: it must be a finite number.",
                   where=name, observed={"value": out}, part=part)
        return None
    return out


#: The parts of question 3 (partial credit): the average NEES and its bounds.
NEES_PARTS = ("average_nees", "nees_bounds")


def nees_answer(nees_30: object, nees_bounds: object, N: int, x_true: np.ndarray,
                x_hat: np.ndarray, P: np.ndarray) -> Report:
    """Check ``nees_30`` and ``nees_bounds = (r1, r2)`` against the ensemble; never raises.
    Each finding names its part (:data:`NEES_PARTS`); the reference ε̄ and bounds are its
    expected values (the instructor's), never in the student's text."""
    report = Report("question 3: NEES at 30 s")
    eps, (lo, hi) = nees_reference(x_true, x_hat, P)
    n = x_true.shape[-1]
    avg, bnd = NEES_PARTS
    value = _number(report, "nees_30", nees_30, avg)
    if value is not None and not math.isclose(value, eps, rel_tol=RTOL):
        e = x_true[:, -1] - x_hat[:, -1]
        with_P = float(np.mean(np.einsum("ri,rij,rj->r", e, P[:, -1], e)))
        sd = np.sqrt(np.diagonal(P[:, -1], axis1=1, axis2=2))
        mine = {"value": value, "N": N, "n": n}
        if math.isclose(value, N * eps, rel_tol=RTOL):
            text = ("nees_30 = {value:.6g} is the sum over the {N} runs, N·ε̄; the question asks "
                    "for the ensemble average ε̄.")
            code = "nees-sum"
        elif math.isclose(value, with_P, rel_tol=RTOL):
            text = ("nees_30 = {value:.6g} is eᵀ P e; the NEES weighs the error by the inverse "
                    "covariance, eᵀ P⁻¹ e (np.linalg.solve(P, e)).")
            code = "nees-not-inverted"
        elif math.isclose(value, float(np.mean(np.sum((e / sd) ** 2, axis=1))), rel_tol=RTOL):
            text = ("nees_30 = {value:.6g} uses only the variances (Σ eᵢ²/Pᵢᵢ); the NEES is "
                    "eᵀ P⁻¹ e with the whole P (its correlations).")
            code = "nees-diagonal"
        elif math.isclose(value, eps / n, rel_tol=RTOL):
            text = ("nees_30 = {value:.6g} is divided by the {n} states; the NEES is eᵀ P⁻¹ e, "
                    "of mean {n} for a consistent filter.")
            code = "nees-per-state"
        else:
            text = ("nees_30 = {value:.6g} is not the ensemble-average NEES at t = 30 s (the "
                    "last GPS time). Use e = x_true[:, -1] − x_hat[:, -1] and P[:, -1], and "
                    "average eᵀ P⁻¹ e over the runs.")
            code = "nees-value"
        report.add(code, text=text, where="nees_30", observed=mine, expected={"ε̄": eps},
                   part=avg)
    try:
        bounds = [float(b) for b in np.asarray(nees_bounds, dtype=float).reshape(-1)]
    except (TypeError, ValueError):
        bounds = []
    if len(bounds) != 2:
        report.add("nees-bounds", text="nees_bounds must be two numbers (r1, r2); got "
                   "{value}.", where="nees_bounds",
                   observed={"value": str(nees_bounds)[:80]}, part=bnd)
    elif not all(math.isclose(b, w, rel_tol=1e-4) for b, w in zip(bounds, (lo, hi), strict=True)):
        from scipy import stats

        one = stats.chi2.ppf([0.025, 0.975], n)
        mine = {"r1": bounds[0], "r2": bounds[1], "N": N}
        if all(math.isclose(b, w, rel_tol=1e-4) for b, w in zip(bounds, one, strict=True)):
            # the student's text states no distribution and no degrees of freedom: that is
            # the answer (tests/check/test_findings_data.py); the instructor's says it
            report.add("nees-bounds-one-run", f"N·ε̄ ~ χ²({n}·N): divide the χ² quantiles of "
                       f"{n}·{N} degrees of freedom by N = {N}.", text="nees_bounds = ({r1:.4g}, "
                       "{r2:.4g}) are the 95 % bounds of a single run's NEES. The average of "
                       "N = {N} runs is much tighter: work out the distribution of the sum of "
                       "the N runs' NEES, then scale its two-sided 95 % bounds to the average.",
                       where="nees_bounds", observed=mine, expected={"bounds": (lo, hi)},
                       part=bnd)
        else:
            report.add("nees-bounds", f"N·ε̄ ~ χ²({n}·N) with N = {N}.", text="nees_bounds = "
                       "({r1:.4g}, {r2:.4g}) are not the two-sided 95 % bounds of the average "
                       "of N = {N} runs' NEES: work out the distribution of the sum of the N "
                       "runs' NEES, then scale its bounds to the average.",
                       where="nees_bounds", observed=mine, expected={"bounds": (lo, hi)},
                       part=bnd)
    if report.passed:
        inside = lo <= eps <= hi
        report.add("ok", severity="note", text="ε̄(30 s) = {eps:.4g}, bounds ({lo:.4g}, "
                   "{hi:.4g}): {verdict}", observed={  # both right: the student's own numbers
                       "eps": eps, "lo": lo, "hi": hi, "verdict": "inside, the filter is "
                       "consistent at 30 s." if inside else "outside (it happens 5 % of the time "
                       "for a consistent filter)."})
    report.sort()
    return report


def check_nees_answer(nees_30: object, nees_bounds: object, N: int, x_true: np.ndarray,
                      x_hat: np.ndarray, P: np.ndarray) -> Report:
    """:func:`nees_answer` for a test cell: AssertionError with the findings when it fails."""
    report = nees_answer(nees_30, nees_bounds, N, x_true, x_hat, P)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report


def rate_model(rate_hz: int):
    """Report 000's problem with the accelerometer at ``rate_hz`` (the GPS stays at 5 Hz)."""
    from gpsaccel.calibration.model import CalibrationModel

    return CalibrationModel(dt=1.0 / rate_hz, gps_every=rate_hz // 5)


def nees_data(rng: np.random.Generator, n_runs: int, n_times: int = 4
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fresh (x_true, x_hat, P) for question 3: random covariances P (SPD, correlated) and errors
    e ~ N(0, P), so the ensemble is consistent; nothing here comes from a filter."""
    L = rng.standard_normal((n_runs, n_times, 3, 3)) * rng.uniform(0.1, 3.0, (1, 1, 3, 1))
    P = L @ np.swapaxes(L, -1, -2) + 0.05 * np.eye(3)
    e = np.einsum("rtij,rtj->rti", np.linalg.cholesky(P), rng.standard_normal((n_runs, n_times,
                                                                              3)))
    x_true = rng.standard_normal((n_runs, n_times, 3)) * 10
    return x_true, x_true - e, P


# the homework, for `gpsaccel assignment` / `gpsaccel grade` (its master: assignments/calibration/)
registry.add_assignment("calibration", __name__, system="calibration", problem="calibration",
                        title="Calibrating an accelerometer with GPS (report 000)")
