"""Statistics of filter consistency: NEES, NIS, chi-square bounds, z-scores, family-wise thresholds.

One module for every system in the package (calibration, ship, cooperative localization) and for
the homework checkers, so a bound means the same thing everywhere.

Notation
--------
For an error e with claimed covariance P (n states), the normalised estimation error squared is
``NEES = eᵀ P⁻¹ e``; for an innovation r = z − H x̄ with covariance S = H M Hᵀ + V (p components)
the normalised innovation squared is ``NIS = rᵀ S⁻¹ r``.  For a consistent filter NEES ~ χ²(n) and
NIS ~ χ²(p).  Averaged over N independent Monte Carlo runs, N·ε̄ ~ χ²(N·n), which gives the
two-sided (1 − α) acceptance interval of the course:

    r1 = χ²⁻¹(α/2; N·n) / N,    r2 = χ²⁻¹(1 − α/2; N·n) / N.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v


def chi2_bounds(dof: int, n_runs: int = 1, alpha: float = 0.05) -> tuple[float, float]:
    """Two-sided (1 − alpha) bounds for the N-run average of a χ²(dof) statistic.

    Returns ``(r1, r2) = (χ²⁻¹(α/2; N·dof) / N, χ²⁻¹(1 − α/2; N·dof) / N)``.
    """
    dof = _v.integer("dof", dof, minimum=1)
    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    alpha = _v.probability("alpha", alpha)
    k = n_runs * dof
    return (float(_chi2_ppf(alpha / 2, k) / n_runs),
            float(_chi2_ppf(1 - alpha / 2, k) / n_runs))


# scipy.stats' chi2 and norm are these scipy.special functions under an argument check
# (scipy.stats.chi2._ppf, ._cdf, ._sf; norm._ppf, ._isf): called directly, bit for bit the same
# numbers, without importing scipy.stats (the larger part of a check's start-up: benchmarks/imports.py;
# tests/kalman/test_consistency.py holds them equal)
def _chi2_ppf(q: np.ndarray | float, dof: np.ndarray | float) -> np.ndarray:
    from scipy import special

    return 2 * special.gammaincinv(np.asarray(dof) / 2, q)


def _norm_isf(q: np.ndarray | float) -> np.ndarray:
    from scipy import special

    return -special.ndtri(q)


def normalized_squared(v: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``vᵀ C⁻¹ v`` over leading axes: v (..., n), C (..., n, n) → (...).

    Solved through a Cholesky factor, never an explicit inverse.  Components of ``v`` that are NaN
    (not measured) are dropped together with their rows and columns of C, so the statistic then has
    fewer degrees of freedom (:func:`dof_of` counts them; a vector with none gives 0).  Input with
    any NaN is solved by LU, one stack per pattern of measured components (:func:`_by_pattern`).
    """
    v = np.asarray(v, dtype=float)
    C = np.asarray(C, dtype=float)
    if C.shape != v.shape + v.shape[-1:]:
        raise ValueError(f"C must have shape {v.shape + v.shape[-1:]} to match v, got {C.shape}")
    finite = np.isfinite(v)
    if finite.all():
        L = np.linalg.cholesky(C)
        y = np.linalg.solve(L, v[..., None])[..., 0]
        return np.einsum("...i,...i->...", y, y)
    return _by_pattern(v, C, finite)


def _by_pattern(v: np.ndarray, C: np.ndarray, finite: np.ndarray) -> np.ndarray:
    """``vᵀ C⁻¹ v`` of vectors with NaN components: one stacked solve per pattern of finite ones.

    Equal bit for bit to solving each vector alone, ``v[m] @ solve(C[m, m], v[m])``, the loop
    this replaced and from which the lessons' tagged NIS fractions were printed: the stacked solve
    is the same LAPACK call (LU) per matrix, and ``(1, p) @ (p, 1)`` on contiguous rows the same
    dot (tests/kalman/test_consistency.py holds it to that).  Why: a filter's residual log has a
    NaN row 0, so every step of every run took that loop, one small solve and its Python call per
    vector; stacked, it is one call per pattern (a coop consistency test's CPU:
    benchmarks/coop_montecarlo.py).
    """
    out = np.zeros(v.shape[:-1])                  # a vector with nothing finite: 0 with 0 dof
    flat_v, flat_C = v.reshape(-1, v.shape[-1]), C.reshape(-1, *C.shape[-2:])
    flat_out = out.reshape(-1)
    flat_f = finite.reshape(flat_v.shape)
    n = flat_f.shape[-1]
    if n < 63:   # a pattern as one integer: 10x cheaper than np.unique over rows
        key = flat_f @ (1 << np.arange(n, dtype=np.int64))
    else:
        key = np.unique(flat_f, axis=0, return_inverse=True)[1].ravel()
    inverse = np.unique(key, return_inverse=True)[1].ravel()
    for i in range(int(inverse.max(initial=-1)) + 1):
        rows = np.flatnonzero(inverse == i)
        m = flat_f[rows[0]]
        if not m.any():
            continue
        vm = np.ascontiguousarray(flat_v[rows][:, m])
        x = np.ascontiguousarray(np.linalg.solve(flat_C[rows][:, m][:, :, m], vm[..., None])[..., 0])
        flat_out[rows] = (vm[:, None, :] @ x[:, :, None])[:, 0, 0]
    return out


def dof_of(v: np.ndarray) -> np.ndarray:
    """Degrees of freedom of :func:`normalized_squared` for each vector: its finite components."""
    return np.isfinite(np.asarray(v, dtype=float)).sum(axis=-1)


def nees(errors: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared ``eᵀ P⁻¹ e``; errors (..., n), P (..., n, n)."""
    return normalized_squared(errors, P)


def nis(residuals: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Normalised innovation squared ``rᵀ S⁻¹ r``; residuals (..., p), S (..., p, p).

    NaN components (not measured) are left out, see :func:`normalized_squared`.
    """
    return normalized_squared(residuals, S)


def sigma_distance(x: np.ndarray, P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray,
                   sd: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(dx, dP): how far (x, P) are from (x_ref, P_ref) in units of σ, elementwise.

    ``dx = |x − x_ref| / σ_i`` and ``dP = |P − P_ref|_ij / (σ_i σ_j)`` with σ = √diag P_ref (or
    ``sd``), the one meaning of "two filters agree" whatever the units of the states.  x (..., n),
    P (..., n, n), broadcasting over leading axes.
    """
    if sd is None:
        sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    return np.abs(np.asarray(x) - x_ref) / sd, covariance_distance(P, P_ref, sd)


def covariance_distance(P: np.ndarray, P_ref: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """|P − P_ref|_ij / (σ_i σ_j) elementwise, σ = ``sd`` (..., n): the P part of
    :func:`sigma_distance`."""
    return np.abs(np.asarray(P) - P_ref) / (sd[..., :, None] * sd[..., None, :])


def fraction_inside(values: np.ndarray, bounds: tuple[float, float]) -> float:
    """Fraction of ``values`` inside the closed interval ``bounds`` (NaN counts as outside)."""
    values = np.asarray(values, dtype=float)
    lo, hi = bounds
    return float(np.mean((values >= lo) & (values <= hi)))


def z_threshold(alpha: float, n_tests: int) -> float:
    """|z| beyond which a two-sided test fails, Bonferroni-corrected for ``n_tests`` tests.

    The family-wise false-alarm rate of the ``n_tests`` tests together is then at most ``alpha``.
    """
    alpha = _v.probability("alpha", alpha)
    n_tests = _v.integer("n_tests", n_tests, minimum=1)
    return float(_norm_isf(alpha / (2 * n_tests)))


@dataclass(frozen=True)
class Verdict:
    """One line of a consistency report: the worst |z| of a statistic over time and its verdict.

    Attributes
    ----------
    name : what was tested, e.g. ``"e_ave[δv]"``.
    max_abs_z : largest |z-score| over the tested times (sampling-error units).
    where : a human-readable location of that largest value (time in s, element).
    threshold : the |z| beyond which the test fails (family-wise alpha over n_tests).
    n_tests : how many individual z-scores the family holds.
    alpha : the family-wise false-alarm rate.
    """

    name: str
    max_abs_z: float
    where: str
    threshold: float
    n_tests: int
    alpha: float

    @property
    def passed(self) -> bool:
        return bool(self.max_abs_z <= self.threshold)


def verdict_from_z(name: str, z: np.ndarray, labels: Callable[[tuple], str],
                   alpha: float = 0.01) -> Verdict:
    """Build a :class:`Verdict` from an array of z-scores.

    ``labels(index_tuple) -> str`` turns the location of the largest |z| into text.  NaN z-scores
    (a statistic with zero theoretical spread, e.g. an unobservable element) are skipped; an
    infinite z-score is a test like any other (it fails).
    """
    z = np.asarray(z, dtype=float)
    valid = ~np.isnan(z)
    n = int(valid.sum())
    if n == 0:
        raise ValueError(f"z for {name!r} has no element that is not NaN")
    absz = np.where(valid, np.abs(z), -1.0)
    idx = np.unravel_index(int(np.argmax(absz)), z.shape)
    return Verdict(name, float(absz[idx]), labels(idx), z_threshold(alpha, n), n, alpha)


def format_verdicts(verdicts: list[Verdict]) -> str:
    """A fixed-width table of verdicts, one per line, as the CLI prints it."""
    width = max([len(v.name) for v in verdicts] + [9])
    head = f"{'statistic':<{width}}  {'max|z|':>8}  {'bound':>6}  {'tests':>6}  {'verdict':<7}  where"
    lines = [head, "-" * len(head)]
    for v in verdicts:
        lines.append(
            f"{v.name:<{width}}  {v.max_abs_z:8.2f}  {v.threshold:6.2f}  {v.n_tests:6d}  "
            f"{'pass' if v.passed else 'FAIL':<7}  {v.where}"
        )
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# z-scores of ensemble statistics: how far a Monte Carlo statistic is from its theoretical value,
# in units of its own sampling error.  Where the sampling distribution is known exactly (a sample
# mean of Gaussians, a sample variance, an ensemble NEES/NIS) the z-score is the exact probability
# integral transform z = Φ⁻¹(F(x)), so |z| > z_threshold(α, n) has false-alarm rate α exactly
# (Bonferroni); where it is not (a sample covariance off the diagonal, a cross moment) the
# z-score divides by the exact standard deviation and relies on the central limit theorem.
# --------------------------------------------------------------------------------------------


def z_from_chi2(x: np.ndarray, dof: np.ndarray | int) -> np.ndarray:
    """Standard-normal z-score of a χ²(dof) statistic ``x``: z = Φ⁻¹(F_χ²(x; dof)).

    Exact (not the √(2·dof) normal approximation): z ~ N(0, 1) when x ~ χ²(dof).  Both tails
    are computed from their own side (``sf`` above the median, ``cdf`` below) so z stays accurate
    far out, where 1 − F would round to 0.

    Beyond |z| ≈ 37 the tail probability underflows; there the Wilson–Hilferty transform
    z ≈ ((x/k)^(1/3) − 1 + 2/(9k)) / √(2/(9k)) takes over, so a grossly inconsistent statistic
    gets a large finite z (and still fails) rather than ±inf (x = 0 gives −inf).
    """
    x = np.asarray(x, dtype=float)
    dof = np.asarray(dof, dtype=float)
    from scipy import special

    upper = x > _chi2_ppf(0.5, dof)                      # the median
    below = np.maximum(x, 0.0)                           # F = 0 below the support (not NaN)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(upper, _norm_isf(special.chdtrc(dof, x)),      # Φ⁻¹ of each tail
                     special.ndtri(special.chdtr(dof, below)))
        c = 2.0 / (9.0 * dof)
        wilson_hilferty = (np.cbrt(x / dof) - 1.0 + c) / np.sqrt(c)
    return np.where(np.isinf(z) & (x > 0), wilson_hilferty, z)  # x = 0 stays at −inf


def z_sample_mean(mean: np.ndarray, variance: np.ndarray, n_runs: int,
                  expected: np.ndarray | float = 0.0) -> np.ndarray:
    """z of a sample mean of ``n_runs`` draws: (mean − expected) / √(variance / N).

    Exact N(0, 1) when the draws are Gaussian with that ``variance``.  Where ``variance`` is 0
    (a quantity that cannot vary) the z-score is NaN, which :func:`verdict_from_z` skips.
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    se = np.sqrt(np.asarray(variance, dtype=float) / n_runs)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(se > 0, (np.asarray(mean, dtype=float) - expected) / se, np.nan)


def z_sample_variance(s2: np.ndarray, variance: np.ndarray, n_runs: int) -> np.ndarray:
    """z of an unbiased sample variance s² (N − 1 divisor) of N Gaussian draws of ``variance``.

    (N − 1) s² / σ² ~ χ²(N − 1) exactly, so z = :func:`z_from_chi2` of it.  NaN where σ² = 0.
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    variance = np.asarray(variance, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (n_runs - 1) * np.asarray(s2, dtype=float) / variance
    return np.where(variance > 0, z_from_chi2(np.nan_to_num(x), n_runs - 1), np.nan)


def sample_covariance_se(C: np.ndarray, n_runs: int) -> np.ndarray:
    """Standard error of each element of an unbiased sample covariance of N Gaussian vectors.

    For true covariance C (..., n, n): Var(Ĉ_ab) = (C_ab² + C_aa C_bb) / (N − 1), exactly.
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    C = np.asarray(C, dtype=float)
    d = np.diagonal(C, axis1=-2, axis2=-1)
    return np.sqrt((C**2 + d[..., :, None] * d[..., None, :]) / (n_runs - 1))


def z_sample_covariance(C_hat: np.ndarray, C: np.ndarray, n_runs: int) -> np.ndarray:
    """z of every element of an unbiased sample covariance Ĉ (..., n, n) of N Gaussian vectors
    against the true covariance C.  Exact N(0, 1) for any N ≥ 2 when C is the truth.

    Diagonal: (N − 1) Ĉ_aa / C_aa ~ χ²(N − 1) (:func:`z_sample_variance`).  Element (a, b) off the
    diagonal, conditionally on the draws of component b: e_a = μ_a + β (e_b − μ_b) + ε with
    β = C_ab / C_bb and ε ~ N(0, C_aa − C_ab²/C_bb) independent of e_b, so
    (N − 1)(Ĉ_ab − β Ĉ_bb) ~ N(0, (C_aa − C_ab²/C_bb)(N − 1) Ĉ_bb) exactly, and

        z_ab = √(N − 1) (Ĉ_ab − β Ĉ_bb) / √((C_aa − C_ab²/C_bb) Ĉ_bb).

    This tests the regression of a on b, whose sampling distribution is exact; the plain
    (Ĉ_ab − C_ab) / :func:`sample_covariance_se` is only normal for large N.  z_ab and z_ba
    condition on different components: count one of each pair.  NaN where there is no spread
    (C_bb = 0, Ĉ_bb = 0 or C_aa − C_ab²/C_bb = 0).
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    C_hat = np.asarray(C_hat, dtype=float)
    C = np.asarray(C, dtype=float)
    d = np.diagonal(C, axis1=-2, axis2=-1)
    d_hat = np.diagonal(C_hat, axis1=-2, axis2=-1)
    C_bb = d[..., None, :]
    C_hat_bb = d_hat[..., None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = C / C_bb
        resid_var = d[..., :, None] - C * beta
        z = np.sqrt(n_runs - 1) * (C_hat - beta * C_hat_bb) / np.sqrt(resid_var * C_hat_bb)
    z = np.where((C_bb > 0) & (C_hat_bb > 0) & (resid_var > 0), z, np.nan)
    n = C.shape[-1]
    idx = np.arange(n)
    z[..., idx, idx] = z_sample_variance(C_hat[..., idx, idx], C[..., idx, idx], n_runs)
    return z


def z_cross_products(sum_ab: np.ndarray, var_a: np.ndarray, sum_bb: np.ndarray) -> np.ndarray:
    """Exact z of Σ_l a_l b_l when the a_l are independent N(0, var_a), independent of the b_l.

    Conditionally on the b_l, Σ a_l b_l ~ N(0, var_a Σ b_l²), so z = Σ a_l b_l / √(var_a Σ b_l²)
    is N(0, 1) for any N and any distribution of the b_l (centred or not).  Used for the
    independence of residuals (b: the earlier residual) and for orthogonality (a: the error,
    b: the centred estimate).  NaN where var_a Σ b_l² = 0.
    """
    den = np.asarray(var_a, dtype=float) * np.asarray(sum_bb, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, np.asarray(sum_ab, dtype=float) / np.sqrt(den), np.nan)


def cross_moment_se(var_a: np.ndarray, var_b: np.ndarray, n_runs: int,
                    centered: bool = False) -> np.ndarray:
    """Standard error of the ensemble mean of a·b for independent zero-mean a, b.

    Uncentered, (1/N) Σ a_l b_l: √(var_a var_b / N).  Centered on the sample mean of ``a``,
    (1/N) Σ (a_l − ā) b_l (the reports' orthogonality check): √((N − 1) var_a var_b) / N.
    Both exact.  ``var_a`` and ``var_b`` broadcast against each other.
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    prod = np.asarray(var_a, dtype=float) * np.asarray(var_b, dtype=float)
    return np.sqrt((n_runs - 1) * prod) / n_runs if centered else np.sqrt(prod / n_runs)


def z_ensemble_normalized_squared(mean_stat: np.ndarray, dof: int, n_runs: int) -> np.ndarray:
    """z of an N-run ensemble average of a χ²(dof) statistic (NEES with dof = n, NIS with p).

    N·ε̄ ~ χ²(N·dof) exactly; z = :func:`z_from_chi2`.  At ε̄ = :func:`chi2_bounds` (r1 or r2)
    for a given α, z = ∓Φ⁻¹(1 − α/2): the course's bounds and this z-score are one test.
    """
    dof = _v.integer("dof", dof, minimum=1)
    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    return z_from_chi2(n_runs * np.asarray(mean_stat, dtype=float), n_runs * dof)


@dataclass(frozen=True)
class ConsistencyReport:
    """Verdicts of several families of tests, with one family-wise false-alarm rate for all.

    Each of the ``len(verdicts)`` rows was tested at ``alpha / len(verdicts)`` (Bonferroni over
    its own tests inside the row), so a consistent filter fails *some* row with probability at
    most ``alpha``.  ``str(report)`` is the table the CLI prints.
    """

    title: str
    verdicts: tuple[Verdict, ...]
    alpha: float

    @property
    def passed(self) -> bool:
        """True when every row passed."""
        return all(v.passed for v in self.verdicts)

    @property
    def failed(self) -> list[Verdict]:
        """The rows that failed."""
        return [v for v in self.verdicts if not v.passed]

    def __getitem__(self, name: str) -> Verdict:
        for v in self.verdicts:
            if v.name == name:
                return v
        raise KeyError(f"no verdict named {name!r}; have {[v.name for v in self.verdicts]}")

    def __str__(self) -> str:
        n = len(self.verdicts)
        head = (f"{self.title}\nfamily-wise false-alarm rate {self.alpha:g} for the whole table "
                f"({n} rows, each at {self.alpha / n:.3g}, Bonferroni over its tests)")
        verdict = "all statistics within their sampling error" if self.passed else \
            f"{len(self.failed)} of {n} rows FAIL: " + ", ".join(v.name for v in self.failed)
        return f"{head}\n{format_verdicts(list(self.verdicts))}\n{verdict}"
