r"""The Kalman filter's algebraically equal forms, each as a filter object the multirate driver runs.

In exact arithmetic every form below computes the same x̂ and P; in float64 they round differently,
and how much that matters depends on the conditioning (:mod:`gpsaccel.kalman.compare` measures it
against :mod:`gpsaccel.kalman.exact`).  This module holds the filter classes; every form is built
from a model's matrices in one place, :func:`gpsaccel.kalman.factory.make_form` (its table
:data:`~gpsaccel.kalman.factory.FORMS`), and run by :func:`gpsaccel.kalman.multirate.run_form`.
With S = H M Hᵀ + V and K = M Hᵀ S⁻¹:

``standard``  P = (I − K H) M.  :class:`StandardKalmanFilter`: filterpy's ``KalmanFilter`` with
    this one line changed.
``joseph``  P = (I − K H) M (I − K H)ᵀ + K V Kᵀ.  filterpy's ``KalmanFilter.update``.
``information``  P = (M⁻¹ + Hᵀ V⁻¹ H)⁻¹, K = P Hᵀ V⁻¹.  The hand-written
    :class:`~gpsaccel.kalman.information.InformationFilter` (the reports' form).
``filterpy-information``  filterpy's ``InformationFilter``: it carries the information matrix
    P⁻¹ = M⁻¹ + Hᵀ V⁻¹ H and predicts it as M⁻¹ = ((Φ⁻ᵀ P⁻¹ Φ⁻¹)⁻¹ + Q)⁻¹.
``square-root``  filterpy's ``SquareRootKalmanFilter``: carries a factor P = P^½ P^½ᵀ; the update
    is one QR factorisation of [[V^½ᵀ, 0], [(H M^½)ᵀ, M^½ᵀ]] (giving S^½, K and P^½), the
    prediction one QR of [Φ P^½, Q^½]ᵀ; P is never formed by a subtraction.

Every filter object has filterpy's ``KalmanFilter`` interface as the driver uses it (``x``, ``P``,
``K``, ``predict()``, ``update(z, R, H)`` with ``R``/``H`` the rows of a partial measurement), so
:func:`gpsaccel.kalman.multirate.run_multirate` runs each of them at the fast rate (report 000's
accelerometer rate), as the course's filter runs.

Two of filterpy's filters need care, both handled in their adapters:

* ``InformationFilter`` computes a log-likelihood in ``update`` with the n×n information matrix
  as the covariance of the p-vector residual, which raises when p < n; it is built with
  ``compute_log_likelihood=False``.  Its covariance is ``P = inv(P_inv)``, one more inversion.
* ``SquareRootKalmanFilter``'s ``Q`` setter takes a Cholesky factor of Q, and a Q = Γ W Γᵀ of
  lower rank (report 000's is rank 1: the bias has no process noise) has none, so it raises
  ``LinAlgError``.  Its algorithm needs only some factor with Q = Q^½ Q^½ᵀ, and Γ √W is an exact
  one: the adapter sets the filter's factor (``_Q1_2``) to it.  So the square-root form here is
  filterpy's, not a hand-written one.  Its ``update`` is for all ``dim_z`` components; a partial
  measurement (NaN in z) resizes its work matrix for that call.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from filterpy.kalman import InformationFilter as FilterpyInformationFilter
from filterpy.kalman import KalmanFilter, SquareRootKalmanFilter
from scipy.linalg import cholesky, get_lapack_funcs


class StandardKalmanFilter(KalmanFilter):
    """filterpy's ``KalmanFilter`` with the standard covariance update P = (I − K H) M.

    filterpy has no switch for it (its ``update`` is always Joseph's); everything else, the
    prediction included, is filterpy's.  The standard form is cheapest and exact in exact arithmetic,
    but P is a difference of two nearly equal matrices when the update shrinks M by much, and its
    rounding is neither symmetric nor guaranteed positive definite.
    """

    x: np.ndarray
    P: np.ndarray

    def update(self, z: np.ndarray, R: np.ndarray | None = None,
               H: np.ndarray | None = None) -> None:
        """r = z − H x̄,  S = H M Hᵀ + V,  K = M Hᵀ S⁻¹,  x̂ = x̄ + K r,  P = (I − K H) M."""
        R = self.R if R is None else R
        H = self.H if H is None else H
        z = np.asarray(z, dtype=float).reshape(-1, 1)
        self.y = z - H @ self.x
        PHT = self.P @ H.T
        self.S = H @ PHT + R
        self.SI = self.inv(self.S)
        self.K = PHT @ self.SI
        self.x = self.x + self.K @ self.y
        self.P = (self._I - self.K @ H) @ self.P
        self.z = z.copy()
        self.x_post, self.P_post = self.x.copy(), self.P.copy()


class _FilterpyAdapter:
    """The driver's interface (``x``, ``P``, ``predict()``) over a filterpy filter ``self.filter``."""

    filter: Any  # a filterpy filter (filterpy has no type hints)

    @property
    def x(self) -> np.ndarray:
        return self.filter.x

    @property
    def P(self) -> np.ndarray:
        return self.filter.P

    def predict(self) -> None:
        self.filter.predict()


class FilterpyInformation(_FilterpyAdapter):
    """filterpy's ``InformationFilter`` with the driver's interface (``x``, ``P``, ``K``).

    The filter itself carries the mean x and the information matrix P⁻¹ (``P_inv``); ``P`` here is
    filterpy's own ``inv(P_inv)``.
    """

    def __init__(self, Phi: np.ndarray, Q: np.ndarray, H: np.ndarray, V: np.ndarray,
                 x0: np.ndarray, M0: np.ndarray) -> None:
        kf = FilterpyInformationFilter(dim_x=Phi.shape[0], dim_z=H.shape[0],
                                       compute_log_likelihood=False)
        kf.F, kf.Q, kf.H = Phi, Q, H  # filterpy keeps F⁻¹ too
        kf.R_inv, kf.P_inv = np.linalg.inv(V), np.linalg.inv(M0)
        kf.x = np.array(x0, dtype=float).reshape(-1, 1)  # its own copy: filterpy updates x in place
        self.filter = kf
        self.K = np.zeros((Phi.shape[0], H.shape[0]))

    def update(self, z: np.ndarray, R: np.ndarray | None = None,
               H: np.ndarray | None = None) -> None:
        kf = self.filter
        saved = kf.H, kf.dim_z
        if H is not None:  # a partial measurement: its rows of H for this call
            kf.H, kf.dim_z = H, H.shape[0]
        try:
            kf.update(np.asarray(z, dtype=float).reshape(-1, 1),
                      R_inv=None if R is None else np.linalg.inv(R))
        finally:
            kf.H, kf.dim_z = saved
        self.K = kf.K


class FilterpySquareRoot(_FilterpyAdapter):
    """filterpy's ``SquareRootKalmanFilter`` with the driver's interface (``x``, ``P``, ``K``).

    Its process-noise factor is Γ √W (see the module docstring); ``P`` is filterpy's
    ``P^½ P^½ᵀ``.
    """

    def __init__(self, Phi: np.ndarray, Q_factor: np.ndarray, H: np.ndarray, V: np.ndarray,
                 x0: np.ndarray, M0: np.ndarray) -> None:
        kf = SquareRootKalmanFilter(dim_x=Phi.shape[0], dim_z=H.shape[0])
        kf.F, kf.H, kf.R, kf.P = Phi, H, V, M0  # R and P: filterpy keeps their Cholesky factors
        kf._Q1_2 = Q_factor
        kf.x = np.array(x0, dtype=float).reshape(-1, 1)  # its own copy: filterpy updates x in place
        self.filter = kf
        n = Phi.shape[0]
        self._work = np.zeros((n + Q_factor.shape[1], n), order="F")  # [Φ P^½, Q^½]ᵀ
        (self._geqrf,) = get_lapack_funcs(("geqrf",), (self._work,))
        self._lwork = int(self._geqrf(self._work, lwork=-1)[2][0].real)  # scipy's workspace query
        self._below = np.tril_indices(n, -1)

    @property
    def K(self) -> np.ndarray:
        return self.filter.K

    def predict(self) -> None:
        """filterpy's ``SquareRootKalmanFilter.predict`` (x̄ = Φ x̂; M^½ from one QR of
        [Φ P^½, Q^½]ᵀ), with the QR as the one LAPACK call (``dgeqrf``) that scipy's ``qr`` makes
        for it: filterpy asks for the full QR and throws its orthogonal factor away, and scipy's
        wrappers around the call (``mode="r"`` included) cost twice the factorisation.  The same
        call on the same matrix gives the same R, bit for bit (tests/calibration/test_forms.py),
        without forming Q: the lesson's sweeps run this 6000 times per form and point.  No
        control input: the driver never passes one."""
        kf = self.filter
        n = kf.dim_x
        kf.x = np.dot(kf.F, kf.x) + np.dot(kf.B, 0)  # filterpy's own expression, to the bit
        a = self._work
        a[:n] = np.dot(kf.F, kf._P1_2).T
        a[n:] = kf._Q1_2.T
        if not np.isfinite(a).all():  # as scipy's qr refuses it (check_finite)
            raise ValueError("array must not contain infs or NaNs")
        r, _, _, info = self._geqrf(a, lwork=self._lwork)
        if info < 0:
            raise ValueError(f"illegal value in {-info}th argument of internal geqrf")
        r = np.ascontiguousarray(r[:n])  # R's leading block, laid out as scipy's np.triu(...)
        r[self._below] = 0.0  # R's strict lower triangle holds the Householder vectors: np.triu
        kf._P1_2 = r.T
        kf.x_prior = np.copy(kf.x)
        kf._P1_2_prior = np.copy(kf._P1_2)

    def update(self, z: np.ndarray, R: np.ndarray | None = None,
               H: np.ndarray | None = None) -> None:
        kf = self.filter
        z = np.asarray(z, dtype=float).reshape(-1, 1)
        if H is None or H.shape[0] == kf.dim_z:
            kf.update(z, None if R is None else cholesky(R, lower=True))
            return
        saved = kf.H, kf.dim_z, kf.M
        kf.H, kf.dim_z = H, H.shape[0]
        kf.M = np.zeros((kf.dim_z + kf.dim_x, kf.dim_z + kf.dim_x))
        try:
            kf.update(z, cholesky(R, lower=True))
        finally:
            kf.H, kf.dim_z, kf.M = saved
