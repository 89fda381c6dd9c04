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

What the filter carries: the information matrix, not M
------------------------------------------------------
The state of the recursion is Y = P⁻¹ (after an update) or Y = M⁻¹ (after a prediction); ``P``
and ``M`` are its inverses, for reading.  The prediction is done on Y itself (Woodbury's identity
with Q = G Gᵀ, G from Q's eigen-decomposition, and A = Φ⁻ᵀ Y Φ⁻¹)::

    M⁻¹ = (Φ P Φᵀ + Q)⁻¹ = A − A G (I + Gᵀ A G)⁻¹ Gᵀ A,

and the update is a sum, Y ← Y + Hᵀ V⁻¹ H, with K = Y⁻¹ Hᵀ V⁻¹ by a Cholesky solve.  Why: with a
diffuse prior (M0 = 10¹²·I) the bias is unobservable at the first fix, so P keeps a 10¹²
variance, and M = Φ P Φᵀ + Q is 10¹² g gᵀ (g: Φ's bias column) plus the O(1) part that holds
what the first fix taught about δp and δv.  Formed in float64, every element of M is rounded at
10¹² · 2⁻⁵³ ≈ 10⁻⁴: the O(1) part is lost to 10⁻⁴ before any inversion, and inverting M to
update cannot bring it back (x̂ off by 4.6·10⁻⁴σ from a 50-digit reference).  Y never holds a
10¹² next to an O(1): it holds 10⁻¹² where the bias is unknown.  Carried this way the form is
exact to ~10⁻¹¹σ for M0 = 10¹²·I and 10⁻¹²·I, and to ~10⁻⁸σ for the harsh priors where the
covariance form is off by σ's or loses positive definiteness (README, "Which form when").
A transition Φ that is singular has no Φ⁻¹: the filter then forms M = Φ P Φᵀ + Q and inverts
it, the reports' way.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_factor, cho_solve


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
        self.x = np.array(x0, dtype=float).reshape(-1, 1)     # x̄ or x̂, whichever is latest
        self._P: np.ndarray | None = np.asarray(M0, dtype=float).copy()  # M or P, the latest
        self.Y = _spd_inverse(self.P)                          # its inverse: what is carried
        self.x_bar = self.x.copy()
        self._M: np.ndarray | None = self.P.copy()  # None: M is the latest P (after a prediction)
        self.K = np.zeros((self.x.shape[0], H.shape[0]))
        self.y = np.zeros((H.shape[0], 1))
        w, U = np.linalg.eigh((np.asarray(Q, dtype=float) + np.asarray(Q, dtype=float).T) / 2)
        keep = w > max(w.max(initial=0.0), 0.0) * 1e-15 * w.size
        self._G = U[:, keep] * np.sqrt(w[keep])  # Q = G Gᵀ (only Q's nonzero directions)
        self._Phi_inv: np.ndarray | None
        try:
            self._Phi_inv = np.linalg.inv(Phi)
        except np.linalg.LinAlgError:
            self._Phi_inv = None  # singular Φ: predict by forming M (see the module docstring)

    def predict(self, u: np.ndarray | None = None, B: np.ndarray | None = None) -> None:
        """x̄ = Φ x̂ (+ B u with a known input u),  M⁻¹ = A − A G (I + Gᵀ A G)⁻¹ Gᵀ A.

        ``B`` overrides the filter's own ``B`` for this call (filterpy's signature).  A = Φ⁻ᵀ Y Φ⁻¹
        is the information after Φ alone, Q = G Gᵀ; M = (M⁻¹)⁻¹ is formed when read (``P``).
        """
        B = self.B if B is None else B
        self.x = self.Phi @ self.x
        if u is not None:
            if B is None:
                raise ValueError("u was given but the filter has no control-input matrix B")
            self.x = self.x + B @ np.asarray(u, dtype=float).reshape(-1, 1)
        if self._Phi_inv is None:
            self.P = self.Phi @ self.P @ self.Phi.T + self.Q
            self.Y = _spd_inverse(self.P)
        else:
            A = self._Phi_inv.T @ self.Y @ self._Phi_inv
            AG = A @ self._G
            C = self._G.T @ AG
            if C.shape == (1, 1):  # Q of rank 1 (the calibration model): a scalar division
                Y = A - (AG / (1.0 + C[0, 0])) @ AG.T
            else:
                Y = A - AG @ np.linalg.solve(np.eye(C.shape[0]) + C, AG.T)
            self.Y = (Y + Y.T) / 2
            self._P = None  # M = Y⁻¹ is for reading only (the recursion goes on with Y): formed
            #                 when read, not at each of the fast steps between two updates
        self.x_bar, self._M = self.x, None  # M is the latest P

    def update(self, z: np.ndarray, R: np.ndarray | None = None,
               H: np.ndarray | None = None) -> None:
        """P⁻¹ = M⁻¹ + Hᵀ V⁻¹ H,  K = P Hᵀ V⁻¹,  x̂ = x̄ + K (z − H x̄).

        ``R`` and ``H`` override V and H for this call (the rows of a partial measurement).
        """
        V = self.V if R is None else R
        H = self.H if H is None else H
        z = np.asarray(z, dtype=float).reshape(-1, 1)
        self.x_bar, self.M = self.x, self.P  # the update's a priori is the latest estimate
        V_inv = np.linalg.inv(V)
        Y = self.Y + H.T @ V_inv @ H
        self.Y = (Y + Y.T) / 2
        self.K, self.P = _spd_solve(self.Y, H.T @ V_inv)
        self.y = z - H @ self.x_bar
        self.x = self.x_bar + self.K @ self.y

    @property
    def P(self) -> np.ndarray:
        """The latest covariance (M after :meth:`predict`, P after :meth:`update`): Y⁻¹,
        symmetrised, formed on first reading after a prediction."""
        if self._P is None:
            M = np.linalg.inv(self.Y)
            self._P = (M + M.T) / 2
        return self._P

    @P.setter
    def P(self, value: np.ndarray) -> None:
        self._P = value

    @property
    def M(self) -> np.ndarray:
        """The a priori covariance of the latest update (or, after a prediction, the latest P)."""
        return self.P if self._M is None else self._M

    @M.setter
    def M(self, value: np.ndarray) -> None:
        self._M = value

    @property
    def x_hat(self) -> np.ndarray:
        """The latest a posteriori mean (equal to x̄ until an update refines it)."""
        return self.x


def _spd_solve(Y: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Y⁻¹ b, Y⁻¹) for a symmetric Y, by Cholesky when it is positive definite (an LU solve
    otherwise: the driver's guard reports such a covariance); Y⁻¹ symmetric to the last bit."""
    try:
        c = cho_factor(Y, lower=True)
        X, Yi = cho_solve(c, b), cho_solve(c, np.eye(Y.shape[0]))
    except np.linalg.LinAlgError:
        X, Yi = np.linalg.solve(Y, b), np.linalg.inv(Y)
    return X, (Yi + Yi.T) / 2


def _spd_inverse(Y: np.ndarray) -> np.ndarray:
    return _spd_solve(Y, np.zeros((Y.shape[0], 0)))[1]
