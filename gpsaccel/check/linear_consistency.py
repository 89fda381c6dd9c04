"""The information half of the linear checker (:mod:`gpsaccel.check.linear`): consistency over
the runs with the student's own P, reported and never deciding ``passed``.

The error e = x_true − x̂ of each run is judged against the student's P: the mean error ē/σ
over the runs and the average NEES, each a Bonferroni family at ``alpha``
(:func:`gpsaccel.kalman.consistency.verdict_from_z`), then the share of times the NEES is inside
its 95 % χ² bounds and the RMS error relative to the optimal filter's.  A right filter fails a
test at rate ``alpha``: a warning says whether this one matches the optimal filter (a false
alarm) or departs from it (the departure's effect), never a mistake it lacks.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gpsaccel.check.linear_diagnosis import Answer, Cases
from gpsaccel.check.report import Report
from gpsaccel.kalman.consistency import (
    Verdict,
    chi2_bounds,
    format_verdicts,
    nees,
    verdict_from_z,
    z_ensemble_normalized_squared,
    z_sample_mean,
)

#: Largest error or covariance element the consistency statistics are formed from: they square
#: and sum them over runs and times (1e150² is still finite); a filter that ran away further is
#: judged by the comparison alone.
RUNAWAY = 1e150

#: The end of an ``inconsistent`` warning: what it is, for a filter that matches the optimal one
#: (a false alarm of the test) and for one that departs from it (the departure's effect).
_FALSE_ALARM = ("Your x̂ and P match the optimal filter, so this is one of those false alarms: "
                "information, not a mistake.")
_WHAT_IT_DOES = ("Your x̂ and P depart from the optimal filter (above): that departure is the "
                 "likely cause.")


def _positive(P: np.ndarray) -> np.ndarray:
    """(...) bool: each matrix of P (..., n, n) finite and positive definite (its symmetric
    part's smallest eigenvalue > 0), each scaled by its largest element first so that a P of a
    filter that ran away (1e308) is judged too."""
    ok = np.isfinite(P).all(axis=(-1, -2))
    S = P[ok] / 2 + np.swapaxes(P[ok], -1, -2) / 2
    scale = np.abs(S).max(axis=(-1, -2), keepdims=True)
    scale[scale == 0] = 1.0
    ok[ok] = np.linalg.eigvalsh(S / scale).min(axis=-1) > 0
    return ok


def consistency(report: Report, cases: Cases, ans: Answer, x: np.ndarray, P: np.ndarray, *,
                t: np.ndarray, states: tuple[str, ...], alpha: float,
                text: Callable[..., str]) -> None:
    """Add the consistency of the student's (x̂, P) (N, k, n) and (N, k, n, n) over the runs to
    ``report`` (module docstring): its table, ``details["consistency"]`` and the ``inconsistent``
    or ``consistent`` findings; a ``p-not-positive-definite`` warning instead where P is not a
    covariance.  ``t`` and ``states`` say where, ``text(key)`` is the problem's wording."""
    N, n = x.shape[0], x.shape[-1]
    e = cases.x_true - x                               # (N, k, n)
    sym = np.abs(P - np.swapaxes(P, -1, -2)).max(axis=(-1, -2)) <= 1e-9 * np.abs(P).max(
        axis=(-1, -2))
    bad = ~sym | ~_positive(P)
    if bad.any():
        times = np.flatnonzero(bad.any(axis=0))
        report.add("p-not-positive-definite", severity="warning", text="Your P is not a "
                   "covariance at {n} times (first t = {t:g} s): it is not symmetric "
                   "positive definite, so NEES cannot be formed. {advice}",
                   where=f"t = {t[times[0]]:g} s",
                   observed={"n": times.size, "t": float(t[times[0]]),
                             "advice": text("p-not-positive-definite.joseph-sign"
                                            if "joseph-sign" in report.codes else
                                            "p-not-positive-definite.advice")})
        return
    if not max(np.abs(e).max(), np.abs(P).max()) < RUNAWAY:  # squares would overflow
        report.tables.append("consistency: not computed, your x̂ or P runs beyond what "
                             f"floating point can square and sum (up to "
                             f"{max(np.abs(x).max(), np.abs(P).max()):.3g}).")
        return
    var = np.diagonal(P, axis1=-2, axis2=-1)
    z_mean = z_sample_mean(e.mean(axis=0), var.mean(axis=0), N)
    v_mean = verdict_from_z("mean error ē/σ", z_mean,
                            lambda idx: f"t = {t[idx[0]]:g} s, {states[idx[1]]}", alpha)
    eps = nees(e, (P + np.swapaxes(P, -1, -2)) / 2).mean(axis=0)
    z_nees = z_ensemble_normalized_squared(eps, n, N)
    v_nees = verdict_from_z("NEES (average)", z_nees, lambda idx: f"t = {t[idx[0]]:g} s",
                            alpha)
    lo, hi = chi2_bounds(n, N, 0.05)
    inside = float(np.mean((eps >= lo) & (eps <= hi)))
    rms = np.sqrt(np.mean(e**2, axis=0))
    rms_ref = np.sqrt(np.mean((cases.x_true - ans.x_ref) ** 2, axis=0))
    ratio = rms.mean(axis=0) / rms_ref.mean(axis=0)
    report.details["consistency"] = {
        "alpha": alpha, "n_runs": N,
        "mean_error_max_abs_z": v_mean.max_abs_z, "mean_error_bound": v_mean.threshold,
        "nees_max_abs_z": v_nees.max_abs_z, "nees_bound": v_nees.threshold,
        "nees_fraction_inside_95": inside,
        "nees_average_first_last": [float(eps[0]), float(eps[-1])],
        "rms_ratio_to_optimal": [float(r) for r in ratio],
    }
    report.tables.append(
        f"consistency over {N} runs, with your P (family-wise false-alarm rate {alpha:g} "
        f"each):\n" + format_verdicts([v_mean, v_nees])
        + f"\nNEES inside its 95% bounds [{lo:.3f}, {hi:.3f}] at {100 * inside:.0f}% of the "
          f"{t.size} times (expected ≈ 95%)."
        + "\nRMS error over time relative to the optimal filter: "
        + ", ".join(f"{s} {r:.3g}" for s, r in zip(states, ratio, strict=True)))
    i_mean = np.unravel_index(int(np.nanargmax(np.abs(z_mean))), z_mean.shape)
    i_nees = int(np.nanargmax(np.abs(z_nees)))
    texts: tuple[tuple[Verdict, str, float, dict], ...] = (
        (v_mean, "Your errors do not average to zero: at {where} the mean error over {N} runs "
                 "is {value:.3g}, {z:.3g} times its standard error √(P/N)",
         float(e.mean(axis=0)[i_mean]), {}),
        (v_nees, "Your P does not describe your actual errors: at {where} the average NEES "
                 "over {N} runs is {value:.4g}, outside its 95% bounds (|z| = {z:.3g})",
         float(eps[i_nees]), {"nees_bounds": (float(lo), float(hi))}))
    # a right filter fails at rate alpha: say which this is, never blame a mistake it lacks
    why = (_FALSE_ALARM if any(f.code == "matches-optimal" for f in report.findings) else
           _WHAT_IT_DOES)
    for v, what, value, bounds in texts:
        if not v.passed:
            report.add("inconsistent", severity="warning", text=what + "; the test fails "
                       "beyond |z| = {bound:.3g} (family-wise false-alarm rate {alpha:g} "
                       "over {n_tests} tests: a right filter fails it that often). " + why,
                       where=v.where, observed={
                           "N": N, "value": value, "z": v.max_abs_z, "bound": v.threshold,
                           "alpha": alpha, "n_tests": v.n_tests}, expected=bounds)
    if v_mean.passed and v_nees.passed:
        report.add("consistent", severity="note", text="Over {N} runs your errors average "
                   "to zero and match your P (mean-error and NEES tests at family-wise "
                   "α = {alpha:g}).", observed={"N": N, "alpha": alpha})
