r"""The exact answer: any linear filter in high-precision arithmetic (mpmath).

Every filter form of :mod:`gpsaccel.kalman.forms` computes the same x̂ and P in exact arithmetic;
in float64 they differ by rounding, and by how much depends on the form and on the conditioning
of the problem.  To measure that, this module runs the filter once more with ``digits``
significant decimal digits (50 by default), on the same float64 inputs taken as exact numbers
(Φ, Γ, W, H, V, M0 and z are binary fractions, converted to mpmath without rounding).  The model
is any linear one with Φ, Γ, W, H, V, M0, x0 and a ``schedule()``: report 000's
:class:`~gpsaccel.CalibrationModel`, an instructor's
:class:`~gpsaccel.kalman.epochs.LinearModel` (the tracker), ...

It runs at the update epochs only, which makes it cheap: between two epochs ``n`` fast steps
(40 accelerometer steps between GPS fixes in report 000) compose exactly into one step::

    Φₙ = Φⁿ,        Qₙ = Σ_{j<n} Φʲ Γ W Γᵀ Φʲᵀ        (by the recursion Qₙ = Φ Qₙ₋₁ Φᵀ + Γ W Γᵀ)

    x̄_i = Φₙ x̂_{i−1},        M_i = Φₙ P_{i−1} Φₙᵀ + Qₙ                       (M_0 = M0, x̄_0 = x0)
    S_i = H M_i Hᵀ + V,       K_i = M_i Hᵀ S_i⁻¹
    x̂_i = x̄_i + K_i (z_i − H x̄_i),   P_i = M_i − K_i S_i K_iᵀ

which is the fast-rate filter's answer at the epochs, not an approximation of it.  In exact
arithmetic every update formula is the same one; with 50 digits the rounding left is ~10⁻⁵⁰
relative, times the condition numbers met (at most ~10²⁵ in the sweeps of
:mod:`gpsaccel.calibration.compare`), far below float64's 10⁻¹⁶.

The result is handed back in float64 as an unevaluated sum ``hi + lo`` (double-double): ``hi`` is
the exact value rounded to float64 and ``lo`` the remainder, so that a float64 filter's error
``(x − hi) − lo`` is computed to a relative accuracy of 10⁻¹⁶ of the error itself, not of x
(:func:`errors`).  NaN in ``z`` means "not measured", as in the multirate driver.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import mpmath
import numpy as np
from mpmath.libmp import from_float, mpf_add, mpf_mul, mpf_shift, mpf_sub, mpf_sum, to_float

from gpsaccel import _validation as _v

#: Significant decimal digits of the reference unless asked otherwise.
DIGITS = 50


@dataclass(frozen=True, eq=False)
class ExactResult:
    """The exact filter at the update epochs, as float64 double-doubles.

    x_hat, x_hat_lo : (n_epochs, n) x̂ rounded to float64, and the remainder x̂ − x_hat.
    P, P_lo : (n_epochs, n, n) P rounded to float64, and the remainder.
    M : (n_epochs, n, n) the a priori covariances, rounded to float64.
    digits : decimal digits used.  seconds : wall-clock time of the computation.
    """

    x_hat: np.ndarray
    x_hat_lo: np.ndarray
    P: np.ndarray
    P_lo: np.ndarray
    M: np.ndarray
    digits: int
    seconds: float

    @property
    def sigma(self) -> np.ndarray:
        """(n_epochs, n) exact a posteriori standard deviations √diag P (float64)."""
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2))

    def condition_number(self) -> float:
        """The largest 2-norm condition number of P over the epochs, cond(P) = λmax / λmin."""
        return float(np.linalg.cond(self.P).max())


def _mp_matrix(ctx: mpmath.ctx_mp.MPContext, a: np.ndarray) -> mpmath.matrix:
    """A float64 array as an mpmath matrix, exactly (every float64 is a binary fraction)."""
    a = np.atleast_2d(np.asarray(a, dtype=float))
    return ctx.matrix([[ctx.mpf(float(v)) for v in row] for row in a])


def _split(pr: tuple[int, str], m: list[list[tuple]], shape: tuple[int, ...]
           ) -> tuple[np.ndarray, np.ndarray]:
    """(hi, lo) float64 arrays with hi + lo = m to ~2⁻¹⁰⁶ relative."""
    prec, rnd = pr
    values = [v for row in m for v in row]
    hi = [to_float(v, rnd=rnd) for v in values]
    lo = [to_float(mpf_sub(v, from_float(h), prec, rnd), rnd=rnd)
          for v, h in zip(values, hi, strict=True)]
    return np.array(hi, dtype=float).reshape(shape), np.array(lo, dtype=float).reshape(shape)


def epoch_transition_exact(ctx: mpmath.ctx_mp.MPContext, Phi: np.ndarray, Q1: mpmath.matrix,
                           steps: int) -> tuple[mpmath.matrix, mpmath.matrix]:
    """(Φⁿ, Qₙ) of n = ``steps`` fast steps in the precision of ``ctx`` (see the module docstring)."""
    n = Phi.shape[0]
    Phi_mp = _mp_matrix(ctx, Phi)
    F, Qn = ctx.eye(n), ctx.zeros(n, n)
    for _ in range(steps):
        F = Phi_mp * F
        Qn = Phi_mp * Qn * Phi_mp.T + Q1
    return F, Qn


# The recursion below works on mpmath's raw numbers (mpf tuples), a matrix a list of rows, with
# the operations mpmath's matrices do and the same roundings: a product element is ``fdot``'s
# exact sum of exact products rounded once, a sum or difference is rounded once, halving is exact.
# Same numbers to the last digit, without mpmath.matrix's per-element bookkeeping, which was
# three quarters of the exact answer's time (and the exact answer a sixth of a sweep point's).
# ``pr`` is (precision in bits, rounding mode), the context's.


def _raw(m: mpmath.matrix) -> list[list[tuple]]:
    return [[m[i, j]._mpf_ for j in range(m.cols)] for i in range(m.rows)]


def _mul(a: list[list[tuple]], b: list[list[tuple]], pr: tuple[int, str]) -> list[list[tuple]]:
    (prec, rnd), cols = pr, list(zip(*b, strict=True))
    return [[mpf_sum([mpf_mul(x, y) for x, y in zip(row, col, strict=True)], prec, rnd)
             for col in cols] for row in a]


def _add(a: list[list[tuple]], b: list[list[tuple]], pr: tuple[int, str],
         op=mpf_add) -> list[list[tuple]]:
    prec, rnd = pr
    return [[op(x, y, prec, rnd) for x, y in zip(ra, rb, strict=True)]
            for ra, rb in zip(a, b, strict=True)]


def _t(a: list[list[tuple]]) -> list[list[tuple]]:
    return [list(col) for col in zip(*a, strict=True)]


def exact_filter(model, z: np.ndarray, digits: int = DIGITS) -> ExactResult:
    """The filter of ``model`` on measurements ``z`` (n_epochs, p), in ``digits`` decimal digits.

    ``model`` is any linear model with ``Phi``, ``Gamma``, ``W``, ``H``, ``V``, ``M0``, ``x0`` and
    ``schedule()`` (a :class:`~gpsaccel.CalibrationModel`, a
    :class:`~gpsaccel.kalman.epochs.LinearModel`); the process noise of one step is taken as
    Γ W Γᵀ computed exactly from Γ and W.
    """
    digits = _v.integer("digits", digits, minimum=20)
    t0 = time.perf_counter()
    schedule = model.schedule()
    H_f, V_f = np.asarray(model.H, dtype=float), np.asarray(model.V, dtype=float)
    p, n = H_f.shape
    z = _v.finite_array("z", z, (schedule.n_epochs, p), allow_nan=True)
    used = schedule.mask & np.isfinite(z)

    ctx = mpmath.MPContext()
    ctx.dps = digits
    pr = ctx._prec_rounding
    rnd = pr[1]
    Gamma, W = _mp_matrix(ctx, model.Gamma), _mp_matrix(ctx, model.W)
    Q1 = Gamma * W * Gamma.T
    H, V = _raw(_mp_matrix(ctx, H_f)), _raw(_mp_matrix(ctx, V_f))
    x = _raw(_mp_matrix(ctx, np.asarray(model.x0, dtype=float).reshape(-1, 1)))
    P = _raw(_mp_matrix(ctx, model.M0))

    transitions: dict[int, tuple[list, list, list]] = {}
    steps = np.asarray(schedule.steps)
    n_epochs = steps.size
    x_hi, x_lo = np.empty((n_epochs, n)), np.empty((n_epochs, n))
    P_hi, P_lo = np.empty((n_epochs, n, n)), np.empty((n_epochs, n, n))
    M_out = np.empty((n_epochs, n, n))
    previous = 0
    for i, step in enumerate(steps):
        gap = int(step) - previous
        previous = int(step)
        if gap:
            if gap not in transitions:
                F_mp, Qn_mp = epoch_transition_exact(ctx, model.Phi, Q1, gap)
                transitions[gap] = (_raw(F_mp), _raw(F_mp.T), _raw(Qn_mp))
            F, FT, Qn = transitions[gap]
            x = _mul(F, x, pr)
            P = _add(_mul(_mul(F, P, pr), FT, pr), Qn, pr)
        M_out[i] = np.array([to_float(v, rnd=rnd) for row in P for v in row]).reshape(n, n)
        rows = [int(r) for r in np.flatnonzero(used[i])]
        if rows:
            x, P = _update(ctx, x, P, [H[r] for r in rows], [[V[r][c] for c in rows] for r in rows],
                           [[from_float(float(z[i, r]))] for r in rows], pr)
        x_hi[i], x_lo[i] = _split(pr, x, (n,))
        P_hi[i], P_lo[i] = _split(pr, P, (n, n))
    return ExactResult(x_hi, x_lo, P_hi, P_lo, M_out, digits, time.perf_counter() - t0)


def _update(ctx: mpmath.ctx_mp.MPContext, x: list, P: list, Hr: list, Vr: list, zr: list,
            pr: tuple[int, str]) -> tuple[list, list]:
    """S = Hr P Hrᵀ + Vr, K = P Hrᵀ S⁻¹, x̂ = x̄ + K (zr − Hr x̄), P = M − K S Kᵀ, symmetrised."""
    HrT = _t(Hr)
    S = _add(_mul(_mul(Hr, P, pr), HrT, pr), Vr, pr)
    S_inv = _raw(ctx.inverse(ctx.matrix([[ctx.make_mpf(v) for v in row] for row in S])))
    K = _mul(_mul(P, HrT, pr), S_inv, pr)
    x = _add(x, _mul(K, _add(zr, _mul(Hr, x, pr), pr, mpf_sub), pr), pr)
    P = _add(P, _mul(_mul(K, S, pr), _t(K), pr), pr, mpf_sub)
    # exact symmetry (the rounding above is ~10^-digits anyway); halving is exact
    return x, [[mpf_shift(v, -1) for v in row] for row in _add(P, _t(P), pr)]


@dataclass(frozen=True)
class Errors:
    """A float64 filter's (x̂, P) against the exact answer, every number dimensionless.

    dx_sigma : max over epochs and states of |x̂ − x̂_exact| / σ_exact.
    dP_rel : max over epochs and elements of |P_ij − P_exact,ij| / √(P_exact,ii P_exact,jj).
    asymmetry : max over epochs and elements of |P_ij − P_ji| / √(P_exact,ii P_exact,jj).
    min_eig : min over epochs of the smallest eigenvalue of P_ij / √(P_exact,ii P_exact,jj) (the
        filter's P in units of the exact σ; the exact answer's own value is
        :func:`min_eigenvalue_exact`, negative means P lost positive definiteness).
    """

    dx_sigma: float
    dP_rel: float
    asymmetry: float
    min_eig: float


def _normaliser(exact: ExactResult) -> np.ndarray:
    sd = exact.sigma
    return sd[:, :, None] * sd[:, None, :]


def errors(exact: ExactResult, x_hat: np.ndarray, P: np.ndarray) -> Errors:
    """:class:`Errors` of (x_hat (n_epochs, n), P (n_epochs, n, n)) against ``exact``.

    Non-finite values count as infinitely wrong (a form that broke down).
    """
    x_hat = np.asarray(x_hat, dtype=float)
    P = np.asarray(P, dtype=float)
    if x_hat.shape != exact.x_hat.shape or P.shape != exact.P.shape:
        raise ValueError(f"x_hat and P must have shapes {exact.x_hat.shape} and {exact.P.shape}, "
                         f"got {x_hat.shape} and {P.shape}")
    norm = _normaliser(exact)
    with np.errstate(invalid="ignore", over="ignore"):
        dx = np.abs((x_hat - exact.x_hat) - exact.x_hat_lo) / exact.sigma
        dP = np.abs((P - exact.P) - exact.P_lo) / norm
        asym = np.abs(P - np.swapaxes(P, 1, 2)) / norm
    if not (np.all(np.isfinite(x_hat)) and np.all(np.isfinite(P))):
        return Errors(np.inf, np.inf, np.inf, -np.inf)
    corr = P / norm
    min_eig = float(np.linalg.eigvalsh((corr + np.swapaxes(corr, 1, 2)) / 2)[:, 0].min())
    return Errors(float(dx.max()), float(dP.max()), float(asym.max()), min_eig)


def min_eigenvalue_exact(exact: ExactResult) -> float:
    """The exact answer's smallest eigenvalue of P_ij / √(P_ii P_jj), over the epochs."""
    corr = exact.P / _normaliser(exact)
    return float(np.linalg.eigvalsh(corr)[:, 0].min())
