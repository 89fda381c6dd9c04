"""The multirate driver: predict at the fast rate, update whenever the schedule says a sensor reports.

Any linear-Gaussian model with the course's matrices runs through it: it needs ``Phi``, ``Q``
(= Γ W Γᵀ), ``H``, ``V``, ``M0``, ``x0``, ``dt`` and a ``schedule()`` (see
:class:`gpsaccel.kalman.schedule.Schedule`).  Two filters run under the same driver:

* ``method="filterpy"``: filterpy's ``KalmanFilter`` (covariance form with the Joseph update);
* ``method="information"``: the hand-written :class:`~gpsaccel.kalman.information.InformationFilter`;

both built from the model's matrices by :func:`gpsaccel.kalman.factory.make_form`, which builds
every other form too (:func:`run_form` runs one by name).

Known input.  A model with a control-input matrix ``B`` (n, m) can be driven by a known input
sequence ``u`` (n_steps, m): the prediction from fast step k to k + 1 is then
``x̄_{k+1} = Φ x̂_k + B u_k`` (the covariance propagation M = Φ P Φᵀ + Q does not change, a known
input adds no uncertainty).  Without ``u`` the prediction is x̄ = Φ x̂, as before.

Missing data.  ``z`` has one row per update epoch of the schedule.  A NaN element means that
component was not measured: the update uses only the finite components (the matching rows of H and
the rows and columns of V).  A row that is entirely NaN is an outage: the filter only propagates,
K = 0 and P = M there.  Infinite values are an error.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.factory import FormModel, make_form
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import CovarianceGuard, step_schedule

#: The driver's methods and the form (:data:`gpsaccel.kalman.factory.FORMS`) each one runs.
METHODS = {"filterpy": "joseph", "information": "information"}
#: What :func:`run_multirate` needs of a model (``schedule`` is a method).
MODEL_ATTRIBUTES = ("Phi", "Q", "H", "V", "M0", "x0", "dt", "schedule")


class MissingInputWarning(UserWarning):
    """A model with a control input was filtered without its input ``u``."""


class LinearGaussianModel(FormModel, Protocol):
    """What the driver needs of a model (``CalibrationModel`` and ``ShipModel`` have it): the
    matrices the factory builds a filter from, the fast step and the schedule of updates."""

    @property
    def dt(self) -> float: ...

    def schedule(self) -> Schedule: ...


@dataclass(frozen=True, eq=False)
class MultirateResult:
    """Everything one multirate run produces, at the update epochs and on the fast grid.

    Epoch arrays (one row per update epoch, ``n_epochs`` rows; for the calibration model the
    GPS times, 151 rows on the defaults):

    t_meas : (n_epochs,) epoch times (s); ``t_gps`` is the same array.
    x_bar, M : a priori mean x̄ (n_epochs, n) and covariance M (n_epochs, n, n).
    x_hat, P : a posteriori mean x̂ and covariance P.
    K : (n_epochs, n, p) gain; zero columns for components not measured.
    r : (n_epochs, p) residual r = z − H x̄; NaN for components not measured.
    S : (n_epochs, p, p) residual covariance H M Hᵀ + V (all components, measured or not).
    used : (n_epochs, p) bool, the components that entered each update.

    Fast-grid arrays (``n_steps + 1`` rows):

    t : (n_steps + 1,) fast-grid times (s).
    x_fast, M_fast : the filter's latest mean and covariance at every fast step — a priori between
        updates and at an epoch before its update (for plotting between GPS fixes).
    """

    method: str
    t: np.ndarray
    t_meas: np.ndarray
    steps: np.ndarray
    x_bar: np.ndarray
    M: np.ndarray
    x_hat: np.ndarray
    P: np.ndarray
    K: np.ndarray
    r: np.ndarray
    S: np.ndarray
    used: np.ndarray
    x_fast: np.ndarray
    M_fast: np.ndarray

    @property
    def t_gps(self) -> np.ndarray:
        """The update epochs' times (s), under the calibration problem's name."""
        return self.t_meas

    @property
    def sigma(self) -> np.ndarray:
        """(n_epochs, n) a posteriori standard deviations √diag P."""
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2))


def make_filter(model: LinearGaussianModel, method: str):
    """The filter object for ``method``, initialised at (x0, M0) from the model's matrices (and its
    control-input matrix ``B``, if it has one)."""
    return make_form(METHODS[_v.choice("method", method, METHODS)], model)


@dataclass(frozen=True, eq=False)
class DriverInputs:
    """A driver's inputs after checking: the schedule, H and V as float arrays, z, and (B, u)."""

    schedule: Schedule
    H: np.ndarray
    V: np.ndarray
    z: np.ndarray
    B: np.ndarray | None
    u: np.ndarray | None


def check_inputs(model: LinearGaussianModel, z: np.ndarray, schedule: Schedule | None,
                 u: np.ndarray | None) -> DriverInputs:
    """Check what a multirate driver is given (shared by every driver of this package).

    ``schedule`` defaults to ``model.schedule()``; ``z`` must be (n_epochs, p) with NaN allowed
    (not measured) and no inf; a known input ``u`` must be (n_steps, m) and the model must have a
    matching ``B`` (n, m).
    """
    missing = [a for a in MODEL_ATTRIBUTES if not hasattr(model, a)]
    if missing:
        raise ValueError(
            f"model must be a linear-Gaussian model (CalibrationModel, ShipModel, ...) with "
            f"{', '.join(MODEL_ATTRIBUTES[:-1])} and schedule(); got {type(model).__name__} "
            f"without {', '.join(missing)}")
    if schedule is not None and not isinstance(schedule, Schedule):
        raise ValueError(f"schedule must be a gpsaccel.Schedule (None: model.schedule()), got "
                         f"{type(schedule).__name__} {schedule!r}"[:200])
    schedule = model.schedule() if schedule is None else schedule
    H, V = np.asarray(model.H, dtype=float), np.asarray(model.V, dtype=float)
    p, n = H.shape
    if schedule.dim_z != p:
        raise ValueError(f"schedule delivers {schedule.dim_z} components but H has {p} rows")
    z = _v.finite_array("z", z, (schedule.n_epochs, p), allow_nan=True)
    B = None
    B_model = getattr(model, "B", None)
    if u is None and B_model is not None and np.any(np.asarray(B_model, dtype=float) != 0):
        warnings.warn(
            f"{type(model).__name__} has a control input (B) but no u was given: the filter "
            f"predicts as if u = 0, which for the ship's thrust and torque is a wrong model "
            f"(RMSE of x, y many times larger); pass u=..., e.g. the voyage's or ensemble's .u",
            MissingInputWarning, stacklevel=3)
    if u is not None:
        B = getattr(model, "B", None)
        if B is None:
            raise ValueError("u was given but the model has no control-input matrix B")
        B = np.asarray(B, dtype=float)
        if B.ndim != 2 or B.shape[0] != n:
            raise ValueError(f"model.B must have shape ({n}, m), got {B.shape}")
        u = _v.finite_array("u", u, (schedule.n_steps, B.shape[1]))
    return DriverInputs(schedule, H, V, z, B, u)


class UpdateHook(Protocol):
    """How a filter updates at an epoch (the driver's hook; :func:`optimal_update` by default).

    Called as ``hook(kf, i, z, rows, H, V)`` with the filter ``kf`` at its a priori (x̄, M) of
    epoch i, that epoch's measurement ``z`` (p,), the indices ``rows`` of the components that
    arrived, and the full H (p, n) and V (p, p).  It leaves x̂ and P in ``kf.x`` (n, 1) and
    ``kf.P`` and returns the gain it applied, (n, p) with zero columns for components not used.
    """

    def __call__(self, kf, i: int, z: np.ndarray, rows: np.ndarray, H: np.ndarray,
                 V: np.ndarray) -> np.ndarray: ...


def optimal_update(kf, i: int, z: np.ndarray, rows: np.ndarray, H: np.ndarray,
                   V: np.ndarray) -> np.ndarray:
    """The optimal update with exactly the rows that arrived (the filter's own ``update``).

    With H_r, V_r the rows (and columns) of the components r that arrived:
    K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹, x̂ = x̄ + K_r (z_r − H_r x̄), P in the filter's own form
    (Joseph for filterpy, information form for :class:`InformationFilter`).  Nothing arrived:
    x̂ = x̄, P = M, K = 0.
    """
    K = np.zeros((H.shape[1], H.shape[0]))
    if rows.size:
        kf.update(z[rows].reshape(-1, 1), R=V[np.ix_(rows, rows)], H=H[rows])
        K[:, rows] = kf.K
    return K


def run_multirate(model: LinearGaussianModel, z: np.ndarray, method: str = "filterpy",
                  schedule: Schedule | None = None, u: np.ndarray | None = None,
                  update: UpdateHook = optimal_update,
                  kf: Any = None, check: bool = True) -> MultirateResult:
    """Filter measurements ``z`` (n_epochs, p) taken on ``schedule`` (default ``model.schedule()``).

    At every fast step the filter predicts with Φ and Q (and ``B u_k`` when a known input ``u``,
    (n_steps, m), is given; the model must then have ``B``); at each epoch it updates with the
    components that the schedule delivers and that are finite in ``z``, by ``update``
    (:func:`optimal_update`, or a system's own variant: :class:`UpdateHook`).

    ``kf`` runs a filter object of one's own in place of ``method``'s (any with filterpy's
    ``KalmanFilter`` interface as used here: ``x``, ``P``, ``K``, ``predict()`` and
    ``update(z, R=..., H=...)``, initialised at (x0, M0)); ``method`` then only names the result.

    ``check``: every epoch's M and P are checked for symmetry and positive definiteness
    (:class:`~gpsaccel.kalman.update.CovarianceGuard`); the first failure gives one
    :class:`~gpsaccel.kalman.update.NumericalWarning` naming the epoch.  For an information
    filter (one that carries ``Y``, M⁻¹ or P⁻¹) its P⁻¹ is checked instead, the matrix x̂, K
    and σ come from (its M⁻¹ may round indefinite in a direction nothing has measured yet, with
    no harm to x̂).  ``check=False`` for filters that are wrong on purpose (the report's
    unsymmetrised (I − KH)M).
    """
    inputs = check_inputs(model, z, schedule, u)
    if kf is None:
        method = _v.choice("method", method, METHODS)
        kf = make_filter(model, method)
    schedule, H, V, z, B, u = (inputs.schedule, inputs.H, inputs.V, inputs.z, inputs.B, inputs.u)
    p, n = H.shape

    def predict(k: int) -> None:
        """From fast step k to k + 1."""
        if u is None:
            kf.predict()
        else:
            kf.predict(u=u[k].reshape(-1, 1), B=B)

    n_epochs, n_fast = schedule.n_epochs, schedule.n_steps + 1
    x_bar = np.empty((n_epochs, n))
    M = np.empty((n_epochs, n, n))
    x_hat = np.empty((n_epochs, n))
    P = np.empty((n_epochs, n, n))
    K = np.zeros((n_epochs, n, p))
    r = np.full((n_epochs, p), np.nan)
    S = np.empty((n_epochs, p, p))
    used = schedule.mask & np.isfinite(z)
    x_fast = np.empty((n_fast, n))
    M_fast = np.empty((n_fast, n, n))

    def record(k: int) -> None:
        x_fast[k], M_fast[k] = kf.x[:, 0], kf.P

    carries_information = isinstance(getattr(kf, "Y", None), np.ndarray)
    guard = None
    if check:
        guard = CovarianceGuard(f"run_multirate(method={method!r})", None if not carries_information
                                else "Even the information form cannot hold this problem in "
                                     "float64: rescale the states, or see "
                                     "gpsaccel.kalman.exact for a high-precision reference.")

    Y = np.empty((n_epochs, n, n)) if guard is not None and carries_information else None

    def update_at(i: int) -> None:
        x_bar[i], M[i] = kf.x[:, 0], kf.P
        S[i] = H @ kf.P @ H.T + V
        rows = np.flatnonzero(used[i])
        r[i, rows] = z[i, rows] - H[rows] @ x_bar[i]
        K[i] = update(kf, i, z[i], rows, H, V)
        x_hat[i], P[i] = kf.x[:, 0], kf.P
        if Y is not None:
            Y[i] = kf.Y

    step_schedule(schedule, predict, update_at, record)
    if guard is not None:
        # Checked once over the run's stacks (the epoch-by-epoch walk only if one fails): the same
        # verdict and warning as checking at every epoch, at a fraction of its cost.
        steps_t = np.asarray(schedule.steps) * model.dt
        guard.check_stack(steps_t, **({"P⁻¹": Y} if Y is not None else {"M": M, "P": P}))
        guard.warn(stacklevel=3)

    t = np.arange(n_fast) * model.dt
    return MultirateResult(method, t, t[schedule.steps], schedule.steps, x_bar, M, x_hat, P,
                           K, r, S, used, x_fast, M_fast)


def run_form(name: str, model: LinearGaussianModel, z: np.ndarray) -> MultirateResult:
    """Run form ``name`` (:data:`gpsaccel.kalman.factory.FORMS`) on measurements ``z`` (n_epochs, p)
    under this driver (predictions at the fast rate, updates at the epochs; NaN = not measured);
    the result's ``method`` is ``name``."""
    return run_multirate(model, z, method=name, kf=make_form(name, model))
