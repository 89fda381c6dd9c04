r"""What is printed of a Monte Carlo result: the reports' numbers and the verdict table.

:func:`summary` gives the numbers the reports printed, each with its standard error; :func:`consistency`
turns every statistic's z-scores (:meth:`~.statistics.MonteCarloResult.z_scores`) into a pass/fail
row at a stated family-wise false-alarm rate.  Both are also methods of the result
(``result.summary()``, ``result.consistency()``), which is how the CLI and the lessons call them.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import STATE_NAMES, STATE_UNITS
from gpsaccel.kalman.consistency import (
    ConsistencyReport,
    chi2_bounds,
    fraction_inside,
    verdict_from_z,
)


class MonteCarloResult(Protocol):
    """What a verdict reads of :class:`~.statistics.MonteCarloResult`.  Written out here rather than
    imported, because the result imports this module to delegate ``summary()`` and
    ``consistency()`` to it: the two modules would import each other."""

    # read-only, as the result is a frozen dataclass
    @property
    def n_runs(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def truth(self) -> str: ...
    @property
    def t(self) -> np.ndarray: ...
    @property
    def e_ave(self) -> np.ndarray: ...
    @property
    def P_ave(self) -> np.ndarray: ...
    @property
    def P(self) -> np.ndarray: ...
    @property
    def orthogonality(self) -> np.ndarray: ...
    @property
    def residual_pairs(self) -> tuple[tuple[int, int], ...]: ...
    @property
    def residual_full(self) -> np.ndarray | None: ...
    @property
    def predicted_mean_error(self) -> np.ndarray: ...
    @property
    def e_ave_se(self) -> np.ndarray: ...
    @property
    def P_ave_se(self) -> np.ndarray: ...
    @property
    def orthogonality_se(self) -> np.ndarray: ...
    @property
    def max_lag(self) -> int: ...
    def residual_product(self, i: int, m: int) -> np.ndarray: ...
    def residual_product_se(self, i: int, m: int) -> np.ndarray: ...
    def z_scores(self) -> dict[str, np.ndarray]: ...


def summary(res: MonteCarloResult) -> str:
    """The numbers the reports printed, each with its standard error (what the CLI prints).

    P_ave − P for (δp, δp) at t = 0 (report 000 printed −0.013), the residual correlation
    r(t_end) r(t_end − T)ᵀ (report 000's pair), and, for a truth the error model does not
    describe exactly, the mean error theory predicts (:attr:`predicted_mean_error`) at its
    largest in standard errors of e_ave.
    """
    d0, se0 = res.P_ave[0, 0, 0] - res.P[0, 0, 0], res.P_ave_se[0, 0, 0]
    lines = [f"P_ave − P at t = 0 for (δp, δp): {d0:+.4f} m² (standard error {se0:.4f} m², "
             f"z = {d0 / se0:+.2f}; report 000 printed −0.013)"]
    rc, rc_se = res.residual_product(-1, -2), res.residual_product_se(-1, -2)
    lines.append(f"residual correlation r({res.t[-1]:g} s) r({res.t[-2]:g} s)ᵀ (report "
                 f"000's pair) ± its standard error:")
    for a in range(2):
        lines.append("  [" + ",  ".join(f"{rc[a, b]:+.2e} ± {rc_se[a, b]:.1e}"
                                        for b in range(2)) + "]")
    if np.any(res.predicted_mean_error):
        lines.append("the mean error theory predicts for this truth (the filter's error on "
                     "the Euler integration error alone), at its largest, in standard "
                     "errors of e_ave:")
        ratio = np.abs(res.predicted_mean_error) / res.e_ave_se
        for k, (name, unit) in enumerate(zip(STATE_NAMES, STATE_UNITS, strict=True)):
            i = int(np.argmax(ratio[:, k]))
            lines.append(f"  {name:>2}: {res.predicted_mean_error[i, k]:+.3g} {unit} at "
                         f"t = {res.t[i]:g} s = {ratio[i, k]:.1f} SE (e_ave there "
                         f"{res.e_ave[i, k]:+.3g})")
    return "\n".join(lines)


def consistency(res: MonteCarloResult, alpha: float = 0.01) -> ConsistencyReport:
    """Verdicts on every statistic, family-wise false-alarm rate ``alpha`` for the table.

    Rows: e_ave per state; P_ave − P per diagonal element (exact χ²) and off the diagonal;
    orthogonality (9 elements); residual whiteness (4 elements for every pair of epochs up to
    ``max_lag`` apart and every requested pair; every pair t_m < t_i when the full matrix was
    kept);
    ensemble NEES (χ²(3N)) and NIS (χ²(2N)).  Each row reports its largest |z| over time with
    its location and value; it fails when that exceeds the Bonferroni bound of its own tests
    at ``alpha / rows``.
    """
    z = res.z_scores()
    t, N = res.t, res.n_runs
    rows = 11
    a = _v.probability("alpha", alpha) / rows
    se_e, se_P, se_o = res.e_ave_se, res.P_ave_se, res.orthogonality_se
    verdicts = []
    for k, (s, u) in enumerate(zip(STATE_NAMES, STATE_UNITS, strict=True)):
        def mean_at(i: tuple, k: int = k, u: str = u) -> str:
            return (f"t = {t[i[0]]:g} s: e_ave = {res.e_ave[i[0], k]:.3g} {u} (SE "
                    f"{se_e[i[0], k]:.2g}, predicted {res.predicted_mean_error[i[0], k]:.3g})")

        verdicts.append(verdict_from_z(f"e_ave[{s}]", z["e_ave"][:, k], mean_at, a))
    dP = res.P_ave - res.P
    for k, s in enumerate(STATE_NAMES):
        def variance_at(i: tuple, k: int = k) -> str:
            return (f"t = {t[i[0]]:g} s: P_ave − P = {dP[i[0], k, k]:.3g} "
                    f"(P {res.P[i[0], k, k]:.3g}, SE {se_P[i[0], k, k]:.2g})")

        verdicts.append(verdict_from_z(f"P_ave−P[{s},{s}]", z["P_ave"][:, k, k],
                                       variance_at, a))
    off = z["P_ave"].copy()
    idx = np.arange(3)
    off[:, idx, idx] = np.nan
    off[:, 1, 0] = off[:, 2, 0] = off[:, 2, 1] = np.nan  # symmetric: count each pair once
    verdicts.append(verdict_from_z(
        "P_ave−P off-diagonal", off,
        lambda i: f"t = {t[i[0]]:g} s, ({STATE_NAMES[i[1]]},{STATE_NAMES[i[2]]}): "
                  f"{dP[i]:.3g} (SE {se_P[i]:.2g})",
        a))
    verdicts.append(verdict_from_z(
        "orthogonality", z["orthogonality"],
        lambda i: f"t = {t[i[0]]:g} s, ({STATE_NAMES[i[1]]},{STATE_NAMES[i[2]]}): "
                  f"{res.orthogonality[i]:.3g} (SE {se_o[i]:.2g})",
        a))
    if res.residual_full is not None:
        rc = res.residual_full
        verdicts.append(verdict_from_z(
            "residual whiteness", z["residual_correlation"],
            lambda i: f"r({t[i[0]]:g} s)[{'pv'[i[2]]}] r({t[i[1]]:g} s)[{'pv'[i[3]]}]: "
                      f"{rc[i]:.3g}",
            a))
    else:  # the lag band and the requested pairs, as one family of tests
        band, pairs = z["residual_lags"], z["residual_pairs"]
        n_band = t.size * (res.max_lag + 1)

        def where(idx):
            j, a_, b_ = idx[0] // 4, idx[0] % 4 // 2, idx[0] % 2
            if j < n_band:
                i, mm = j // (res.max_lag + 1), j // (res.max_lag + 1) - j % (res.max_lag + 1)
            else:
                i, mm = res.residual_pairs[j - n_band]
            val = res.residual_product(i, mm)[a_, b_]
            return f"r({t[i]:g} s)[{'pv'[a_]}] r({t[mm]:g} s)[{'pv'[b_]}]: {val:.3g}"

        verdicts.append(verdict_from_z(
            "residual whiteness", np.concatenate([band.reshape(-1), pairs.reshape(-1)]), where, a))
    for name, key, dof in (("NEES", "nees", 3), ("NIS", "nis", 2)):
        vals = getattr(res, key)
        bounds = chi2_bounds(dof, N, 0.05)
        inside = fraction_inside(vals, bounds)

        def chi2_at(i: tuple, vals: np.ndarray = vals, bounds: tuple = bounds,
                    inside: float = inside) -> str:
            return (f"t = {t[i[0]]:g} s: {vals[i[0]]:.4g}; {inside:.0%} of epochs inside "
                    f"the 95% bounds [{bounds[0]:.4g}, {bounds[1]:.4g}]")

        verdicts.append(verdict_from_z(f"{name} (χ²({dof}N)/N)", z[key], chi2_at, a))
    assert len(verdicts) == rows
    title = (f"Monte Carlo consistency: {N} runs, truth {res.truth}, seed {res.seed}, "
             f"{t.size} GPS epochs; residual whiteness over " +
             ("every pair of epochs" if res.residual_full is not None else
              f"lags ≤ {res.max_lag}" + (f" and {len(res.residual_pairs)} more pairs"
                                          if res.residual_pairs else "")))
    return ConsistencyReport(title, tuple(verdicts), float(alpha))

