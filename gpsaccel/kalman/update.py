r"""The pieces every linear filter of the package shares: one gain, one Joseph update, one epoch
transition and one loop over a schedule.

Gain and Joseph update (course notation: a priori M, measurement matrix H, noise V)::

    S = H M Hᵀ + V                         residual covariance
    K = M Hᵀ S⁻¹                           gain (the optimal one for this M)
    P = (I − K H) M (I − K H)ᵀ + K V Kᵀ    a posteriori covariance of the estimate x̂ = x̄ + K r

The Joseph form holds for *any* gain K, optimal or not, and keeps P symmetric and positive
semidefinite in floating point; filterpy's ``KalmanFilter.update`` uses it too.  Every function
here broadcasts over leading axes, so a stack of candidate filters is updated at once.

Epoch transition.  n fast steps with (Φ, Q) between two updates compose into one step::

    Φ_n = Φⁿ,     Q_n = Σ_{j<n} Φʲ Q Φʲᵀ

(the calibration problem's 40 accelerometer steps between GPS fixes are one step with Φ⁴⁰, Q₄₀).

The stepping loop.  A multirate filter walks the fast grid k = 0..n_steps, predicting every step
and updating at the epochs of a :class:`~gpsaccel.kalman.schedule.Schedule`.
:func:`step_schedule` is that loop, once, with hooks: what a prediction does, what an update does
(the optimal update with the rows that arrived, or a system's own variant such as report 004's
zeroed gain), and what to record at every fast step.

Numerical guard.  In float64 a covariance can stop being one: with a diffuse prior (M0 = 10¹²·I)
or very precise measurements the Joseph form's P turns asymmetric (10⁻⁶), then indefinite, and σ
becomes NaN, all without an error.  :class:`CovarianceGuard` checks every M and P of a run
(symmetry to :data:`SYMMETRY_RTOL` of √(A_ii A_jj), positive definiteness by a Cholesky
factorisation, a few µs for these sizes) and issues one :class:`NumericalWarning` per run naming
the first epoch that failed and suggesting ``method="information"``, which carries M⁻¹ and stays
exact there (:mod:`gpsaccel.kalman.information`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule


def _T(a: np.ndarray) -> np.ndarray:
    """Transpose of the last two axes."""
    return np.swapaxes(a, -1, -2)


def gain(M: np.ndarray, H: np.ndarray, V: np.ndarray, inverse: bool = False
         ) -> tuple[np.ndarray, np.ndarray]:
    """(K, S): the gain K = M Hᵀ S⁻¹ and the residual covariance S = H M Hᵀ + V.

    M (..., n, n), H (..., p, n), V (..., p, p), broadcast over the leading axes (a stack of
    filters or of runs at once).  K is computed as Kᵀ = S⁻ᵀ (M Hᵀ)ᵀ by a linear solve, which is
    M Hᵀ S⁻¹ whether or not M (and so S) is symmetric: a filter that carries the report's
    non-symmetric (I − K H) M gets exactly the gain its own equations define.  ``inverse=True``
    forms S⁻¹ and K = (M Hᵀ) S⁻¹ (:func:`cross_gain`), the form of filterpy's
    ``KalmanFilter.update``; the vectorised Monte Carlo filters use it (it equals filterpy's K
    to rounding, ~1e-16 relative, not bit for bit: filterpy sums S as H (M Hᵀ) + V).
    """
    S = H @ M @ _T(H) + V                                  # S = H M Hᵀ + V
    if inverse:
        return cross_gain(M @ _T(H), S, inverse=True), S
    K = _T(np.linalg.solve(_T(S), H @ _T(M)))              # Kᵀ = S⁻ᵀ (M Hᵀ)ᵀ
    return K, S


def cross_gain(C: np.ndarray, S: np.ndarray, inverse: bool = False) -> np.ndarray:
    """K = C S⁻¹ for a state–measurement cross-covariance C (..., n, p) and the residual
    covariance S (..., p, p): C = M Hᵀ in a linear filter, the sigma points' Pxz in an
    unscented one.  ``inverse=True`` forms S⁻¹ explicitly (filterpy's order of operations,
    K = C·inv(S)); otherwise Kᵀ = S⁻ᵀ Cᵀ by a linear solve."""
    if inverse:
        return C @ np.linalg.inv(S)
    return _T(np.linalg.solve(_T(S), _T(C)))


def joseph_update(M: np.ndarray, K: np.ndarray, H: np.ndarray, V: np.ndarray) -> np.ndarray:
    """(I − K H) M (I − K H)ᵀ + K V Kᵀ: the a posteriori covariance of any gain K (..., n, n)."""
    A = np.eye(M.shape[-1]) - K @ H
    return A @ M @ _T(A) + K @ V @ _T(K)


#: The covariance updates a filter may write (:func:`covariance_update`): the Joseph form, the
#: short form (I − K H) M (right for the optimal gain only), and Joseph's form with a sign wrong.
COVARIANCE_FORMS = ("joseph", "short", "minus", "plus")


def covariance_update(M: np.ndarray, K: np.ndarray, H: np.ndarray, V: np.ndarray,
                      form: str = "joseph") -> np.ndarray:
    """The a posteriori covariance a filter computes from M with the gain K (..., n, n)::

        "joseph"  (I − K H) M (I − K H)ᵀ + K V Kᵀ     the covariance of any gain
        "short"   (I − K H) M                         the optimal gain's only (report 004's)
        "minus"   (I − K H) M (I − K H)ᵀ − K V Kᵀ     Joseph's form with the wrong sign
        "plus"    (I + K H) M (I + K H)ᵀ + K V Kᵀ     ... or with I + K H

    The last two are a student's slips (the catalogues' ``joseph-sign``); "joseph" is exactly
    :func:`joseph_update`.
    """
    if form == "joseph":
        return joseph_update(M, K, H, V)
    if form == "short":
        return (np.eye(M.shape[-1]) - K @ H) @ M
    if form == "minus":
        A = np.eye(M.shape[-1]) - K @ H
        return A @ M @ _T(A) - K @ V @ _T(K)
    if form == "plus":
        A = np.eye(M.shape[-1]) + K @ H
        return A @ M @ _T(A) + K @ V @ _T(K)
    raise ValueError(f"form must be one of {COVARIANCE_FORMS}, got {form!r}")


def partial_update(x_bar: np.ndarray, M: np.ndarray, z: np.ndarray, H: np.ndarray,
                   V: np.ndarray, rows: np.ndarray, K: np.ndarray | None = None,
                   zeroed: bool = False, short_form: bool = False, *,
                   V_gain: np.ndarray | None = None, form: str | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x̂, P, K): the update with the components ``rows`` of z that arrived; the only one.

    x̄ (..., n) (one run or many sharing M), M (n, n), z (..., p), H (p, n), V (p, p).  The gain
    K (n, p) has zero columns for the components that did not arrive:

    * optimal (default): K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹ with the rows r that arrived;
    * ``zeroed``: the full gain M Hᵀ (H M Hᵀ + V)⁻¹ as if every component had arrived, its
      columns of the missing ones set to zero (report 004's filter: near-optimal, not optimal);
    * ``K`` given: that gain (e.g. another filter's).

    x̂ = x̄ + K r with r = z − H x̄ on the rows that arrived and 0 elsewhere.  P is the Joseph form,
    the covariance of any gain, or with ``short_form`` (I − K H) M, which holds for the optimal
    gain only (the report's); ``form`` names any of :data:`COVARIANCE_FORMS` instead.
    ``V_gain``: the V that the gain's S = H M Hᵀ + V_gain uses, where a filter's gain and its
    covariance update disagree (a student's ``residual-covariance``); P is updated with V.
    Nothing arrived: x̂ = x̄, P = M, K = 0 (in Joseph form).
    """
    rows = np.asarray(rows, dtype=int)
    p, n = H.shape
    Vg = V if V_gain is None else V_gain
    if K is None:
        K = np.zeros((n, p))
        if rows.size and zeroed:
            K[:, rows] = gain(M, H, Vg)[0][:, rows]         # (the solve keeps a non-symmetric M)
        elif rows.size:
            K[:, rows] = gain(M, H[rows], Vg[np.ix_(rows, rows)])[0]
    r = np.zeros(np.shape(x_bar)[:-1] + (p,))
    if np.ndim(x_bar) == 1:                                  # one run: matrix @ vector
        r[rows] = z[rows] - H[rows] @ x_bar
        x_hat = x_bar + K @ r
    else:                                                    # runs in rows
        r[..., rows] = z[..., rows] - x_bar @ H[rows].T
        x_hat = x_bar + r @ K.T
    form = form or ("short" if short_form else "joseph")
    P = covariance_update(M, K, H, V, form)
    return x_hat, P, K


def epoch_transition(Phi: np.ndarray, Q: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(Φⁿ, Σ_{j<n} Φʲ Q Φʲᵀ): mean transition and process noise of n = ``steps`` fast steps.

    Computed by the same recursion as n predictions, Q_n ← Φ Q_n Φᵀ + Q, so it agrees with a
    filter that predicts step by step to the last bit that recursion keeps.
    """
    steps = _v.integer("steps", steps, minimum=0)
    F = np.eye(Phi.shape[0])
    Qe = np.zeros_like(Q, dtype=float)
    for _ in range(steps):
        F = Phi @ F
        Qe = Phi @ Qe @ Phi.T + Q
    return F, Qe


def step_schedule(schedule: Schedule, predict: Callable[[int], None],
                  update: Callable[[int], None],
                  on_step: Callable[[int], None] | None = None) -> None:
    """Walk the fast grid of ``schedule``: the one loop of every multirate filter here.

    ``predict(k)`` moves the filter from fast step k to k + 1; ``update(i)`` runs the update of
    epoch i (at fast step ``schedule.steps[i]``, after the predictions that reach it);
    ``on_step(k)``, if given, is called when step k has been reached (k = 0 first, and at an
    epoch before its update), for whatever a caller records on the fast grid.  After the last
    epoch the filter keeps predicting to the end of the grid.
    """
    step = 0
    if on_step is not None:
        on_step(0)
    for i, epoch_step in enumerate(schedule.steps):
        while step < epoch_step:
            predict(step)
            step += 1
            if on_step is not None:
                on_step(step)
        update(i)
    while step < schedule.n_steps:
        predict(step)
        step += 1
        if on_step is not None:
            on_step(step)


# ------------------------------------------------------------------------------ numerical guard
class NumericalWarning(RuntimeWarning):
    """A covariance lost symmetry or positive definiteness in floating point: the numbers of that
    run are not to be trusted to the digits printed (see :class:`CovarianceGuard`)."""


#: Largest |A_ij − A_ji| / √(A_ii A_jj) a covariance may have: rounding leaves ~10⁻¹⁵ on a
#: well-conditioned problem, a diffuse prior drives the Joseph form's P to 10⁻⁶.
SYMMETRY_RTOL = 1e-10


def covariance_defect(A: np.ndarray) -> str | None:
    """None if ``A`` (n, n) is a covariance to working precision, else what is wrong with it:
    a NaN or infinite element, a variance ≤ 0, asymmetry above :data:`SYMMETRY_RTOL` (relative
    to √(A_ii A_jj)), or no Cholesky factor (not positive definite)."""
    A = np.asarray(A, dtype=float)
    if not np.all(np.isfinite(A)):
        return "has a NaN or infinite element"
    d = np.diagonal(A)
    if np.any(d <= 0.0):
        k = int(np.argmin(d))
        return f"has a variance ≤ 0 (element [{k}, {k}] = {d[k]:.3g})"
    asym = float(np.max(np.abs(A - A.T) / np.sqrt(np.outer(d, d))))
    if asym > SYMMETRY_RTOL:
        return f"is not symmetric (max |A_ij − A_ji| / √(A_ii A_jj) = {asym:.2g})"
    try:
        np.linalg.cholesky((A + A.T) / 2)
    except np.linalg.LinAlgError:
        lam = float(np.linalg.eigvalsh((A + A.T) / 2)[0])
        return f"is not positive definite (smallest eigenvalue {lam:.3g})"
    return None


def _sound_stack(A: np.ndarray) -> bool:
    """True if every matrix of A (..., n, n) passes :func:`covariance_defect` (vectorised)."""
    if not np.all(np.isfinite(A)):
        return False
    d = np.diagonal(A, axis1=-2, axis2=-1)
    if np.any(d <= 0.0):
        return False
    At = np.swapaxes(A, -1, -2)
    if np.max(np.abs(A - At) / np.sqrt(d[..., :, None] * d[..., None, :])) > SYMMETRY_RTOL:
        return False
    try:
        np.linalg.cholesky((A + At) / 2)
    except np.linalg.LinAlgError:
        return False
    return True


class CovarianceGuard:
    """Checks a run's covariances epoch by epoch; :meth:`warn` reports the first failure once.

    ``who`` names the run in the message (e.g. ``"run_multirate(method='filterpy')"``) and
    ``advice`` says what to do (by default: use the information form).
    """

    def __init__(self, who: str, advice: str | None = None) -> None:
        self.who = who
        self.advice = advice if advice is not None else (
            'The covariance form rounds badly for this prior or noise (a diffuse or very tight '
            'M0, very precise measurements); method="information" carries M⁻¹ and stays exact '
            'there (README: which form when)')
        self.first: tuple[int, float, str, str] | None = None
        self.bad_epochs = 0
        self.epochs = 0

    def check(self, i: int, t: float, **covariances: np.ndarray) -> bool:
        """Check each named covariance of epoch ``i`` (time ``t``, s); True if all are sound."""
        self.epochs += 1
        for name, A in covariances.items():
            defect = covariance_defect(A)
            if defect is not None:
                self.bad_epochs += 1
                if self.first is None:
                    self.first = (i, t, name, defect)
                return False
        return True

    def check_stack(self, t: np.ndarray, **stacks: np.ndarray) -> None:
        """:meth:`check` for every epoch i of stacks (n_epochs, n, n) at times ``t``, the sound
        case decided at once over the whole stack (the epoch-by-epoch walk only when it fails)."""
        if all(_sound_stack(A) for A in stacks.values()):
            self.epochs += len(t)
            return
        for i in range(len(t)):
            self.check(i, float(t[i]), **{name: A[i] for name, A in stacks.items()})

    def warn(self, stacklevel: int = 3) -> None:
        """One :class:`NumericalWarning` if any epoch failed (none otherwise)."""
        if self.first is None:
            return
        i, t, name, defect = self.first
        warnings.warn(NumericalWarning(
            f"{self.who}: {name} at epoch {i} (t = {t:g} s) {defect}; {self.bad_epochs} of "
            f"{self.epochs} epochs affected, so x̂ and σ there are not to be trusted. "
            f"{self.advice}"), stacklevel=stacklevel)
