"""What a coop filter run produced (:class:`FilterResult`), and its NEES and NIS.

Its own module so that a reader looking for "the result" or "the NIS" finds it by name, and so
that code that only reads results (figures, the Monte Carlo tests) need not read the filter.  The
statistics are the core's (:mod:`gpsaccel.kalman.consistency`): headings enter the NEES through
the wrapped error :func:`~gpsaccel.coop.model.state_residual`, and a component that was not
measured (NaN in r) is left out of the NIS, which then has fewer degrees of freedom.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel.coop.model import state_residual
from gpsaccel.kalman import consistency


@dataclass
class FilterResult:
    """What a filter run produced; arrays may carry a leading run axis (N, ...) from run_batch.

    t : (K+1,) s.  x_bar, x_hat : (..., K+1, 6) x̄ and x̂ (angles wrapped); M, P :
    (..., K+1, 6, 6) M and P.  r : (..., K+1, 5) residual r = y − ŷ (NaN where not measured, row 0
    NaN); S : (..., K+1, 5, 5) its covariance.  Row 0 holds the initial x̂_0, P_0.
    """

    method: str
    t: np.ndarray
    x_bar: np.ndarray
    M: np.ndarray
    x_hat: np.ndarray
    P: np.ndarray
    r: np.ndarray
    S: np.ndarray

    @property
    def sigma(self) -> np.ndarray:
        """Posterior standard deviations √diag(P) (..., K+1, 6)."""
        return np.sqrt(np.diagonal(self.P, axis1=-2, axis2=-1))

    def errors(self, x_true: np.ndarray) -> np.ndarray:
        """Estimation errors x − x̂ (headings wrapped), same leading shape as x_hat."""
        return state_residual(x_true, self.x_hat)

    def nees(self, x_true: np.ndarray) -> np.ndarray:
        """NEES eᵀ P⁻¹ e at every step (..., K+1)."""
        return consistency.nees(self.errors(x_true), self.P)

    def nis(self) -> np.ndarray:
        """NIS rᵀ S⁻¹ r at every step (..., K+1); 0 with 0 dof where nothing was measured."""
        return consistency.nis(self.r, self.S)
