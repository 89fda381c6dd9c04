r"""A hand-written Kalman filter with the reports' information-form update.

Written by hand on purpose: it is the comparison for filterpy's covariance (Joseph) form.  The
equations are those of report 000, section 3.5.1::

    propagation   x̄_{k+1} = Φ x̂_k (+ B u_k)        M_{k+1} = Φ P_k Φᵀ + Γ W Γᵀ
    update        P_k = (M_k⁻¹ + Hᵀ V⁻¹ H)⁻¹        K_k = P_k Hᵀ V⁻¹
                  x̂_k = x̄_k + K_k (z_k − H x̄_k)    r_k = z_k − H x̄_k

Between measurements the a posteriori estimate is the a priori one (no new data): after
:meth:`predict` the filter's current estimate ``x``/``P`` is x̄/M, after :meth:`update` it is x̂/P.
Method and attribute names follow filterpy's ``KalmanFilter`` (``x``, ``P``, ``K``, ``y``,
``predict()``, ``update(z, R, H)``) so the multirate driver runs either filter unchanged.
"""

from __future__ import annotations

import numpy as np


class InformationFilter:
    """Linear Kalman filter with the information-form measurement update.

    Parameters
    ----------
    Phi : (n, n) transition Φ of one step.
    Q : (n, n) process-noise covariance Γ W Γᵀ of one step.
    H : (p, n) measurement matrix.
    V : (p, p) measurement-noise covariance.
    x0 : (n,) a priori mean at the first step.
    M0 : (n, n) a priori covariance at the first step.
    B : (n, m) control-input matrix of a known input u (optional), as filterpy's ``B``.
    """

    def __init__(self, Phi: np.ndarray, Q: np.ndarray, H: np.ndarray, V: np.ndarray,
                 x0: np.ndarray, M0: np.ndarray, B: np.ndarray | None = None) -> None:
        self.Phi, self.Q, self.H, self.V, self.B = Phi, Q, H, V, B
        self.x = np.asarray(x0, dtype=float).reshape(-1, 1)   # x̄ or x̂, whichever is latest
        self.P = np.asarray(M0, dtype=float).copy()            # M or P, whichever is latest
        self.x_bar, self.M = self.x.copy(), self.P.copy()
        self.K = np.zeros((self.x.shape[0], H.shape[0]))
        self.y = np.zeros((H.shape[0], 1))

    def predict(self, u: np.ndarray | None = None, B: np.ndarray | None = None) -> None:
        """x̄ = Φ x̂ (+ B u with a known input u),  M = Φ P Φᵀ + Q.

        ``B`` overrides the filter's own ``B`` for this call (filterpy's signature).
        """
        B = self.B if B is None else B
        self.x = self.Phi @ self.x
        if u is not None:
            if B is None:
                raise ValueError("u was given but the filter has no control-input matrix B")
            self.x = self.x + B @ np.asarray(u, dtype=float).reshape(-1, 1)
        self.P = self.Phi @ self.P @ self.Phi.T + self.Q
        self.x_bar, self.M = self.x, self.P

    def update(self, z: np.ndarray, R: np.ndarray | None = None,
               H: np.ndarray | None = None) -> None:
        """P = (M⁻¹ + Hᵀ V⁻¹ H)⁻¹,  K = P Hᵀ V⁻¹,  x̂ = x̄ + K (z − H x̄).

        ``R`` and ``H`` override V and H for this call (the rows of a partial measurement).
        """
        V = self.V if R is None else R
        H = self.H if H is None else H
        z = np.asarray(z, dtype=float).reshape(-1, 1)
        self.x_bar, self.M = self.x, self.P  # the update's a priori is the latest estimate
        V_inv = np.linalg.inv(V)
        self.P = np.linalg.inv(np.linalg.inv(self.M) + H.T @ V_inv @ H)
        self.P = (self.P + self.P.T) / 2  # the inverse of a symmetric matrix, to the last bit
        self.K = self.P @ H.T @ V_inv
        self.y = z - H @ self.x_bar
        self.x = self.x_bar + self.K @ self.y

    @property
    def x_hat(self) -> np.ndarray:
        """The latest a posteriori mean (equal to x̄ until an update refines it)."""
        return self.x
