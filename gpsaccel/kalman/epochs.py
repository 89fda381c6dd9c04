r"""A linear filter at its measurement epochs: the one recursion every linear filter of the course
is, right or wrong, and the gains of many such filters at once.

Every filter a student writes for a linear problem whose measurements arrive every ``every``-th
propagation step — right or wrong — is, at the measurement epochs, a recursion of one shape::

    x̄_0 = x0,                      M_0 = M0
    x̄_i = A x̂_{i−1},               M_i = F P_{i−1} Fᵀ + Q_e          (i ≥ 1)
    K_i = M_i Hᵀ (H M_i Hᵀ + V)⁻¹
    P_i = (I − K_i H) M_i (I − K_i H)ᵀ + K_i V K_iᵀ                   (Joseph form)
    x̂_i = x̄_i + K_i (z_i − H x̄_i)

The optimal filter has ``A = F = Φⁿ`` (n = every) and ``Q_e = Σ_{j<n} Φʲ ΓWΓᵀ Φʲᵀ``
(:func:`gpsaccel.kalman.update.epoch_transition`, exactly what n one-step predictions do).  A
mistake (:class:`gpsaccel.kalman.mistakes.Mistake`) changes one ingredient of it; the gains and
covariances do not depend on the data, so :func:`batch_gains` computes them once for many
candidate filters at once and :meth:`EpochFilter.apply` runs the mean for every realization at
once.

The rest of what was this module lives next door, one job each: the mistake mechanism
(:mod:`gpsaccel.kalman.mistakes`), any linear model and its ingredients
(:mod:`gpsaccel.kalman.linear_model`), the generic catalogue (:mod:`gpsaccel.kalman.linear_catalogue`)
and its wording (:mod:`gpsaccel.kalman.linear_messages`).  Their names stay readable from here
(``gpsaccel.kalman.epochs.LinearModel``, as docs and instructors' notebooks write it), loaded on
first use so that no import circle exists.  Nothing here knows a system.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from gpsaccel.kalman.update import covariance_update, gain, joseph_update


# ------------------------------------------------------------------------------ the epoch filter
@dataclass(frozen=True, eq=False)
class EpochFilter:
    """A linear filter written at the measurement epochs (module docstring for the recursion).

    A : (n, n) mean transition from one epoch to the next (x̄_i = A x̂_{i−1}).
    F, Qe : (n, n) covariance transition and process noise between epochs (M_i = F P Fᵀ + Qe).
    H (p, n), V (p, p), x0 (n,), M0 (n, n): measurement model and prior at the first epoch.
    n_gps : number of epochs.
    output : ``"posterior"`` returns (x̂, P); ``"prior"`` returns (x̄, M) (returns-a-priori).
    skip_first, skip_last : True skips the update at the first (last) epoch; ``"covariance"``
        updates the mean there but leaves P = M (so every later gain follows the skipped P).
    update_P : False never updates P (P_i = M_i at every epoch; the gains K_i = M_i Hᵀ S⁻¹ still
        update the mean): covariance-update-skipped everywhere.
    fast : None, or (Φ, Q, n, which) of one propagation step when the filter updates at *every*
        step (n per epoch interval) with a measurement it has: ``which`` "last" the last one,
        z_{i−1}, until z_i arrives, or "next" the one that comes at the end of the interval, z_i
        (update-every-step); A, F, Qe are then unused between epochs.

    What a student may get wrong in the update itself (each None or "joseph": right):

    V_gain : the V of the gain's S = H M Hᵀ + V_gain, where P's update uses V
        (residual-covariance: V left out of S, or its standard deviations there).
    form : how P is updated from M, one of :data:`gpsaccel.kalman.update.COVARIANCE_FORMS`
        ("minus", "plus": joseph-sign).
    updates : None updates at every epoch; "even" only at epochs 0, 2, 4, ..., "odd" only at
        1, 3, 5, ... (fixes-skipped; the others only propagate, and are stored).

    and in the mean only (P is untouched):

    z_shift : None; "first" updates epoch i with z_{i−1} (epoch 0 with z_0), "wrap" with
        z_{i−1} and epoch 0 with z_{−1}, Python's last row (measurement-late).
    z_weight : (p, p) or None: the residual takes z_weight·z for z.  An information filter whose
        y adds Hᵀ V z (V where V⁻¹ belongs) is x̂ = x̄ + K (V² z − H x̄): z_weight = V V
        (information-vector).
    x0_from_z : x̄₀ = x0 + H⁺ (z₀ − H x0): the prior mean started at the first measurement
        (x0-wrong).
    """

    A: np.ndarray
    F: np.ndarray
    Qe: np.ndarray
    H: np.ndarray
    V: np.ndarray
    x0: np.ndarray
    M0: np.ndarray
    n_gps: int
    output: str = "posterior"
    skip_first: bool | str = False
    skip_last: bool | str = False
    update_P: bool = True
    fast: tuple | None = None
    V_gain: np.ndarray | None = None
    form: str = "joseph"
    updates: str | None = None
    z_shift: str | None = None
    z_weight: np.ndarray | None = None
    x0_from_z: bool = False

    @cached_property
    def gains(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K, M, P): gains (n_gps, n, p), a priori and a posteriori covariances (n_gps, n, n)."""
        K, M, P = batch_gains([self])
        return K[0], M[0], P[0]

    @cached_property
    def fast_gains(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(K, M, P, K_between) of a filter that updates at every step (``fast``): the epochs'
        K, M, P as :attr:`gains`, and K_between (n_gps, n − 1, n, p) the gains of the updates
        between epoch i − 1 and epoch i (row 0 unused)."""
        return self.fast_recursion(self.n_gps)

    def fast_recursion(self, n_epochs: int
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:attr:`fast_gains` of the first ``n_epochs`` epochs only (bit for bit its rows)."""
        assert self.fast is not None, "fast_gains is for a filter that updates at every step"
        Phi, Q, steps = self.fast[:3]
        (p, n) = self.H.shape
        K, M, P = np.zeros((n_epochs, n, p)), np.empty((n_epochs, n, n)), np.empty((n_epochs, n, n))
        Kb = np.zeros((n_epochs, max(steps - 1, 0), n, p))
        C = self.M0
        for i in range(n_epochs):
            for s in range(steps if i else 0):
                C = Phi @ C @ Phi.T + Q                          # one step: M = Φ P Φᵀ + Q
                if s < steps - 1:                                # an update with z_{i−1}
                    Kb[i, s] = gain(C, self.H, self.V)[0]
                    C = joseph_update(C, Kb[i, s], self.H, self.V)
            M[i] = C
            K[i] = gain(C, self.H, self.V)[0]
            C = joseph_update(C, K[i], self.H, self.V)
            P[i] = (C + C.T) / 2
            C = P[i]
        return K, M, P, Kb

    @property
    def P_out(self) -> np.ndarray:
        """The covariance this filter returns: P, or M with ``output="prior"``."""
        _, M, P = self.gains
        return M if self.output == "prior" else P

    def apply(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Run on z (n_runs, n_gps, p) → (x (n_runs, n_gps, n), P (n_gps, n, n)), as returned.

        With ``output="posterior"`` these are x̂ and P; with ``"prior"`` x̄ and M.
        """
        z = np.asarray(z, dtype=float)
        K, M, P = self.gains
        n_runs, n = z.shape[0], self.A.shape[0]
        x_bar = np.empty((n_runs, self.n_gps, n))
        x_hat = np.empty_like(x_bar)
        xb = np.broadcast_to(np.asarray(self.x0, dtype=float), (n_runs, n))
        if self.x0_from_z:                                    # x̄₀ = x0 + H⁺ (z₀ − H x0)
            xb = xb + (z[:, 0] - xb @ self.H.T) @ np.linalg.pinv(self.H).T
        z = self._used_z(z)
        Kb = self.fast_gains[3] if self.fast is not None else None
        for i in range(self.n_gps):
            if i and Kb is not None:
                zb = z[:, i] if self.fast[3] == "next" else z[:, i - 1]  # type: ignore[index]
                xb = self._between(x_hat[:, i - 1], zb, Kb[i])
            elif i:
                xb = x_hat[:, i - 1] @ self.A.T
            x_bar[:, i] = xb
            r = z[:, i] - xb @ self.H.T                       # r_i = z_i − H x̄_i
            x_hat[:, i] = xb + r @ K[i].T                     # x̂_i = x̄_i + K_i r_i
        if self.output == "prior":
            return x_bar, M
        return x_hat, P

    def _used_z(self, z: np.ndarray) -> np.ndarray:
        """The measurements the mean's residuals take (``z_weight``, ``z_shift``)."""
        if self.z_weight is not None:
            z = z @ np.asarray(self.z_weight).T
        if self.z_shift is not None:
            first = z[:, :1] if self.z_shift == "first" else z[:, -1:]
            z = np.concatenate([first, z[:, :-1]], axis=1)
        return z

    def _between(self, x: np.ndarray, z: np.ndarray, Kb: np.ndarray) -> np.ndarray:
        """x̄_i of a filter that updates at every step with z_{i−1} (``fast``), from x̂_{i−1}."""
        assert self.fast is not None
        Phi = self.fast[0]
        for K in Kb:
            x = x @ Phi.T
            x = x + (z - x @ self.H.T) @ K.T
        return x @ Phi.T


def batch_gains(filters: Sequence[EpochFilter], n_epochs: int | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gains and covariances of many filters at once: K (C, n_gps, n, p), M and P (C, n_gps, n, n).

    All filters must share n_gps and the state/measurement sizes.  The Joseph update
    (:func:`gpsaccel.kalman.update.joseph_update`) keeps P symmetric and positive definite even
    for badly scaled mistakes.  ``n_epochs``: only the first epochs (bit for bit those rows of the
    whole run; the diagnosis bounds a candidate's distance by them).  Each filter's rows are its
    own: the same whichever filters share the stack.  Nothing is cached on the filters: filters
    built once and run for many callers hold no covariance between them.
    """
    n_gps = filters[0].n_gps
    n_epochs = n_gps if n_epochs is None else n_epochs
    skip = _skip_masks(filters, n_gps, n_epochs)
    hold = np.array([not f.update_P for f in filters])
    F, Qe, H, V, M0 = (np.stack([getattr(f, a) for f in filters])
                       for a in ("F", "Qe", "H", "V", "M0"))
    V_gain = (np.stack([f.V if f.V_gain is None else f.V_gain for f in filters])
              if any(f.V_gain is not None for f in filters) else None)
    forms = np.array([f.form for f in filters])
    K, M, P, _ = gain_recursion(F, Qe, H, V, M0, n_epochs, skip=skip,
                                hold=hold if hold.any() else None, V_gain=V_gain,
                                forms=forms if (forms != "joseph").any() else None)
    for c, f in enumerate(filters):
        if f.fast is not None:                        # updates between the epochs: its own loop
            K[c], M[c], P[c] = f.fast_recursion(n_epochs)[:3]  # not f.fast_gains: cache none
    return K, M, P


def gain_recursion(F: np.ndarray, Qe: np.ndarray, H: np.ndarray, V: np.ndarray, M0: np.ndarray,
                   n_gps: int, inverse: bool = False, symmetrise: bool = True,
                   skip: dict | None = None, hold: np.ndarray | None = None,
                   V_gain: np.ndarray | None = None, forms: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(K, M, P, S) of the epoch recursion (module docstring) for n_gps epochs: the one loop.

    The matrices may carry leading axes (a stack of filters, ``batch_gains``), or none (one
    filter, the calibration ensemble's plan).  ``inverse``: S⁻¹ formed as filterpy does
    (:func:`gpsaccel.kalman.update.gain`).  ``symmetrise``: P ← (P + Pᵀ)/2 after each update.
    ``skip``: {(epoch, "P" or "x"): (C,) bool} the filters that skip that update at that epoch.
    ``hold``: (C,) bool, the filters whose P is never updated (P_i = M_i at every epoch).
    ``V_gain``: the V of each filter's gain (:class:`EpochFilter`); ``forms``: (C,) each
    filter's covariance update (:func:`gpsaccel.kalman.update.covariance_update`).
    """
    lead, (n, p) = F.shape[:-2], (F.shape[-1], H.shape[-2])
    K = np.zeros(lead + (n_gps, n, p))
    M = np.empty(lead + (n_gps, n, n))
    P = np.empty(lead + (n_gps, n, n))
    S = np.empty(lead + (n_gps, p, p))
    Ft = np.swapaxes(F, -1, -2)
    skip = skip or {}
    for i in range(n_gps):
        Mi = M0 if i == 0 else F @ P[..., i - 1, :, :] @ Ft + Qe    # M_i = F P_{i−1} Fᵀ + Q_e
        M[..., i, :, :] = Mi
        Ki, S[..., i, :, :] = _gain(Mi, H, V if V_gain is None else V_gain,
                                    inverse)                     # K_i = M Hᵀ (H M Hᵀ + V)⁻¹
        Kp = Ki
        if (i, "P") in skip:
            Kp = np.where(skip[i, "P"][:, None, None], 0.0, Ki)   # P_i = M_i
            Ki = np.where(skip[i, "x"][:, None, None], 0.0, Ki)   # and x̂_i = x̄_i
        if hold is not None:
            Kp = np.where(hold[:, None, None], 0.0, Kp)          # P never updated
        Pi = joseph_update(Mi, Kp, H, V)
        if forms is not None:                                    # a student's covariance update
            for form in set(forms) - {"joseph"}:
                c = forms == form
                Pi[c] = covariance_update(Mi[c], Kp[c], H[c], V[c], form)
        K[..., i, :, :] = Ki
        P[..., i, :, :] = (Pi + np.swapaxes(Pi, -1, -2)) / 2 if symmetrise else Pi
    return K, M, P, S


def _gain(M: np.ndarray, H: np.ndarray, V: np.ndarray, inverse: bool
          ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`gpsaccel.kalman.update.gain`; in a stack of candidate filters, one whose S is
    singular (a mistaken filter can lose V from S and rank from M) gets a NaN gain, and so NaN
    from there on, which matches nothing, instead of stopping the others."""
    try:
        return gain(M, H, V, inverse=inverse)
    except np.linalg.LinAlgError:
        if M.ndim < 3:
            raise
    S = H @ M @ np.swapaxes(H, -1, -2) + V
    finite = np.isfinite(S).all(axis=(-1, -2))
    bad = ~finite
    bad[finite] = np.linalg.matrix_rank(S[finite]) < S.shape[-1]
    V = np.where(bad[:, None, None], np.eye(S.shape[-1]), V)      # any S that solves ...
    M = np.where(bad[:, None, None], 0.0, M)
    K = gain(M, H, V, inverse=inverse)[0]
    K[bad] = np.nan                                                # ... then NaN for those
    return K, S


def _skip_masks(filters: Sequence[EpochFilter], n_gps: int, n_epochs: int) -> dict:
    """{(epoch, "P" or "x"): (C,) bool} the filters that skip the covariance or the mean update
    at that epoch (:func:`gain_recursion`'s ``skip``), for the epochs where any does: the first
    or last one skipped (``skip_first``, ``skip_last``: True both, "covariance" P only) and every
    other one (``updates``: neither)."""
    P = np.zeros((len(filters), n_gps), dtype=bool)
    x = np.zeros_like(P)
    for c, f in enumerate(filters):
        for i, how in ((0, f.skip_first), (n_gps - 1, f.skip_last)):
            P[c, i] |= bool(how)
            x[c, i] |= how is True
        if f.updates is not None:                    # fixes-skipped: neither x̂ nor P updated
            P[c, 1 if f.updates == "even" else 0::2] = True
            x[c, 1 if f.updates == "even" else 0::2] = True
    return {(i, kind): m[:, i] for i in range(n_epochs) if P[:, i].any()
            for kind, m in (("P", P), ("x", x))}


#: The names that moved out (module docstring) -> their module, read from it on first use.
_MOVED = {**dict.fromkeys(("Catalogue", "Mistake", "combinations", "with_changes"),
                          "gpsaccel.kalman.mistakes"),
          **dict.fromkeys(("LinearIngredients", "LinearModel"), "gpsaccel.kalman.linear_model"),
          **dict.fromkeys(("LINEAR_MESSAGES", "LinearCatalogue", "phi_sign_variants",
                           "predict_before_first_update", "state_orders", "structural_mistakes"),
                          "gpsaccel.kalman.linear_catalogue")}


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        return getattr(importlib.import_module(_MOVED[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
