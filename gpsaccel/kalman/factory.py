r"""The one place a filter object is built from a model's matrices.

Every form of :mod:`gpsaccel.kalman.forms` (filterpy's ``KalmanFilter`` with the Joseph update, the
standard update, the hand-written information form, filterpy's information and square-root filters)
starts from the same (Φ, Q = Γ W Γᵀ, H, V, x0, M0), and a model with a known input adds ``B``.
:func:`make_form` reads them once from the model (:class:`Matrices`) and hands each form its own
float copies: filterpy updates ``x`` and ``P`` in place, and a filter must never write into the
model it came from.  Who builds through here:

* :func:`gpsaccel.kalman.multirate.run_multirate`, for its ``method`` (``filterpy`` is the Joseph
  form);
* :func:`gpsaccel.kalman.multirate.run_form` and :mod:`gpsaccel.kalman.compare`, for every form;
* each model's ``kalman_filter()`` (``CalibrationModel``, ``ShipModel``, ``LinearModel``), the
  students' way to a filterpy ``KalmanFilter`` (:func:`kalman_filter`).

This module does not import filterpy: a form that needs it imports it when it is built, so the
information form runs without it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.information import InformationFilter

if TYPE_CHECKING:  # filterpy pulls in scipy.stats (benchmarks/imports.py): imported where a filter is made
    from filterpy.kalman import KalmanFilter


class FormModel(Protocol):
    """What the factory needs of a model: Φ, Q, H, V, x0, M0 (any model of the course has them);
    the square-root form needs Γ and W too (its factor Γ √W of Q), a known input ``B``."""

    @property
    def Phi(self) -> np.ndarray: ...

    @property
    def Q(self) -> np.ndarray: ...

    @property
    def H(self) -> np.ndarray: ...

    @property
    def V(self) -> np.ndarray: ...

    @property
    def x0(self) -> np.ndarray: ...

    @property
    def M0(self) -> np.ndarray: ...


#: The matrices every form needs, in the order :class:`Matrices` holds them.
REQUIRED = ("Phi", "Q", "H", "V", "x0", "M0")


@dataclass(frozen=True, eq=False)
class Matrices:
    """A model's matrices as fresh float arrays (x0 as the column filterpy carries)."""

    Phi: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    V: np.ndarray
    x0: np.ndarray
    M0: np.ndarray
    B: np.ndarray | None = None
    Gamma: np.ndarray | None = None
    W: np.ndarray | None = None

    @classmethod
    def of(cls, model: FormModel) -> Matrices:
        missing = [name for name in REQUIRED if getattr(model, name, None) is None]
        if missing:
            raise ValueError(f"model must have the matrices {', '.join(REQUIRED)}; got "
                             f"{type(model).__name__} without {', '.join(missing)}")

        def copy(name: str) -> Any:
            value = getattr(model, name, None)
            return None if value is None else np.array(value, dtype=float)

        Phi, Q, H, V, x0, M0 = (copy(name) for name in REQUIRED)
        return cls(Phi, Q, H, V, x0.reshape(-1, 1), M0, copy("B"), copy("Gamma"), copy("W"))

    @property
    def dim_x(self) -> int:
        return int(self.Phi.shape[0])

    @property
    def dim_z(self) -> int:
        return int(self.H.shape[0])

    @property
    def dim_u(self) -> int:
        return 0 if self.B is None else int(self.B.shape[1])

    def fill(self, kf: Any) -> Any:
        """A filterpy ``KalmanFilter`` (or subclass) set to F = Φ, Q, H, R = V, x = x0, P = M0 (and B)."""
        kf.F, kf.Q, kf.H, kf.R, kf.x, kf.P = self.Phi, self.Q, self.H, self.V, self.x0, self.M0
        if self.B is not None:
            kf.B = self.B
        return kf

    def q_factor(self) -> np.ndarray:
        """Γ √W, a factor of Q = Γ W Γᵀ that exists for a Q of lower rank (no Cholesky of Q)."""
        from scipy.linalg import cholesky

        if self.Gamma is None or self.W is None or self.Gamma.shape[1] != self.W.shape[0]:
            raise ValueError("the square-root form needs the model's Gamma and W with "
                             "Q = Gamma W Gamma^T")
        return self.Gamma @ cholesky(self.W, lower=True)


def _joseph(m: Matrices) -> KalmanFilter:
    from filterpy.kalman import KalmanFilter

    return m.fill(KalmanFilter(dim_x=m.dim_x, dim_z=m.dim_z, dim_u=m.dim_u))


def _standard(m: Matrices) -> Any:
    from gpsaccel.kalman.forms import StandardKalmanFilter

    return m.fill(StandardKalmanFilter(dim_x=m.dim_x, dim_z=m.dim_z, dim_u=m.dim_u))


def _information(m: Matrices) -> InformationFilter:
    return InformationFilter(m.Phi, m.Q, m.H, m.V, m.x0, m.M0, B=m.B)


def _filterpy_information(m: Matrices) -> Any:
    from gpsaccel.kalman.forms import FilterpyInformation

    return FilterpyInformation(m.Phi, m.Q, m.H, m.V, m.x0, m.M0)


def _square_root(m: Matrices) -> Any:
    from gpsaccel.kalman.forms import FilterpySquareRoot

    return FilterpySquareRoot(m.Phi, m.q_factor(), m.H, m.V, m.x0, m.M0)


#: name -> (builder(matrices) -> filter object, one-line description).  Ordered as the tables print.
FORMS: dict[str, tuple[Callable[[Matrices], Any], str]] = {
    "standard": (_standard, "P = (I - KH)M (filterpy's KalmanFilter, this line changed)"),
    "joseph": (_joseph, "filterpy KalmanFilter.update (Joseph)"),
    "information": (_information, "hand-written, P = (M^-1 + H'V^-1 H)^-1"),
    "filterpy-information": (_filterpy_information, "filterpy InformationFilter (carries P^-1)"),
    "square-root": (_square_root, "filterpy SquareRootKalmanFilter (QR)"),
}


def make_form(name: str, model: FormModel) -> Any:
    """The filter object of form ``name`` (one of :data:`FORMS`) for ``model``, at (x0, M0)."""
    name = _v.choice("form", name, FORMS)
    return FORMS[name][0](Matrices.of(model))


def kalman_filter(model: FormModel) -> KalmanFilter:
    """filterpy's ``KalmanFilter`` for ``model``: F = Φ, Q = Γ W Γᵀ, H, R = V, x = x0, P = M0, and
    ``B`` (with ``dim_u``) when the model has a known input; the Joseph form of :data:`FORMS`."""
    return _joseph(Matrices.of(model))
