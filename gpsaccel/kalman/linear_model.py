r"""Any linear-Gaussian model with a measurement schedule, and what a student chooses writing a
filter for it (its ingredients), in course notation.

:class:`LinearModel` is the instructor's problem (Φ, Γ, W, H, V, M0, x0, a measurement every
``every`` propagation steps); :class:`LinearIngredients` is one filter for it, right or wrong,
which :meth:`LinearIngredients.epoch_filter` assembles into the one epoch recursion of
:mod:`gpsaccel.kalman.epochs`.  A mistake of the generic catalogue
(:mod:`gpsaccel.kalman.linear_catalogue`) changes one of these ingredients.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.epochs import EpochFilter
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import epoch_transition

if TYPE_CHECKING:  # filterpy pulls in scipy.stats (benchmarks/imports.py): imported where a filter is made
    from filterpy.kalman import KalmanFilter

#: ``.memo``: (Φ, Q, n) -> (Φⁿ, Q_e) while :func:`shared_transitions` is open in this thread.
_TRANSITIONS = threading.local()


@contextmanager
def shared_transitions() -> Iterator[None]:
    """Within the block, :meth:`LinearIngredients.epoch_filter` computes the transition of each
    (Φ, Q, n) once and hands the same arrays to every filter that has it: report 000's candidate
    filters (:func:`gpsaccel.check.linear_diagnosis.candidates`), thousands of them, have a
    transition per distinct (Φ, Q, n), a few hundred.
    The same recursion on the same numbers, so bit for bit what each filter computes alone;
    nothing is kept after the block (per thread)."""
    outer = getattr(_TRANSITIONS, "memo", None)
    _TRANSITIONS.memo = {} if outer is None else outer
    try:
        yield
    finally:
        _TRANSITIONS.memo = outer


def _transition(Phi: np.ndarray, Q: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
    memo = getattr(_TRANSITIONS, "memo", None)
    if memo is None:
        return epoch_transition(Phi, Q, steps)
    key = (Phi.shape, Phi.dtype.str, Phi.tobytes(), Q.shape, Q.dtype.str, Q.tobytes(), steps)
    if key not in memo:
        memo[key] = epoch_transition(Phi, Q, steps)
    return memo[key]


def _matrix(name: str, value: object, rows: int | None = None, cols: int | None = None
            ) -> np.ndarray:
    arr = np.atleast_2d(_v.finite_array(name, value))
    if arr.ndim != 2 or (rows is not None and arr.shape[0] != rows) or \
            (cols is not None and arr.shape[1] != cols):
        want = f"({'n' if rows is None else rows}, {'m' if cols is None else cols})"
        raise ValueError(f"{name} must be a matrix of shape {want}, got {arr.shape}")
    return arr


@dataclass(frozen=True, eq=False)
class LinearModel:
    """A linear-Gaussian system and its measurement schedule, in course notation.

    x_{j+1} = Φ x_j + Γ w_j, w_j ~ N(0, W) at every propagation step j (of ``dt`` s);
    z_i = H x_{i·every} + v_i, v_i ~ N(0, V) at the epochs i = 0 .. n_epochs − 1;
    x_0 ~ N(x0, M0).  ``states`` and ``measurements`` name the components (for messages).
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    W: np.ndarray
    H: np.ndarray
    V: np.ndarray
    M0: np.ndarray
    x0: np.ndarray
    every: int
    n_epochs: int
    dt: float = 1.0
    states: tuple[str, ...] = ()
    measurements: tuple[str, ...] = ()
    rtol: float = field(default=1e-10, repr=False)

    def __post_init__(self) -> None:
        Phi = _matrix("Phi", self.Phi)
        n = Phi.shape[0]
        if Phi.shape != (n, n):
            raise ValueError(f"Phi must be square, got shape {Phi.shape}")
        Gamma = _matrix("Gamma", self.Gamma, rows=n)
        W = _v.spd_matrix("W", self.W, Gamma.shape[1])
        H = _matrix("H", self.H, cols=n)
        V = _v.spd_matrix("V", self.V, H.shape[0])
        M0 = _v.spd_matrix("M0", self.M0, n)
        x0 = _v.finite_array("x0", self.x0, (n,))
        every = _v.integer("every", self.every, minimum=1)
        n_epochs = _v.integer("n_epochs", self.n_epochs, minimum=2)
        dt = _v.positive_float("dt", self.dt)
        states = tuple(self.states) or tuple(f"x{i + 1}" for i in range(n))
        meas = tuple(self.measurements) or tuple(f"z{i + 1}" for i in range(H.shape[0]))
        if len(states) != n or len(meas) != H.shape[0]:
            raise ValueError(f"states must name the {n} states and measurements the "
                             f"{H.shape[0]} measurements, got {states} and {meas}")
        for name, value in (("Phi", Phi), ("Gamma", Gamma), ("W", W), ("H", H), ("V", V),
                            ("M0", M0), ("x0", x0), ("every", every), ("n_epochs", n_epochs),
                            ("dt", dt), ("states", states), ("measurements", meas)):
            if isinstance(value, np.ndarray):  # the model's own read-only copy: a filter that
                value = np.array(value)        # updates in place (filterpy's square root did,
                value.setflags(write=False)    # on x0) raises instead of changing the problem
            object.__setattr__(self, name, value)

    @property
    def n(self) -> int:
        return int(self.Phi.shape[0])

    @property
    def dim_x(self) -> int:
        return self.n

    @property
    def dim_z(self) -> int:
        return int(self.H.shape[0])

    @property
    def Q(self) -> np.ndarray:
        """The process noise of one step, Q = Γ W Γᵀ (filterpy's ``Q``)."""
        return self.Gamma @ self.W @ self.Gamma.T

    def schedule(self) -> Schedule:
        """Every component at every ``every``-th step 0, every, ..., n_steps: what the
        multirate driver (:func:`gpsaccel.kalman.multirate.run_multirate`), the filter forms
        (:mod:`gpsaccel.kalman.forms`) and the exact filter (:mod:`gpsaccel.kalman.exact`) run."""
        return Schedule.from_periods(self.n_steps, [self.every] * self.dim_z)

    def kalman_filter(self) -> KalmanFilter:
        """A filterpy ``KalmanFilter`` for one step: F = Φ, Q = Γ W Γᵀ, H, R = V, x = x0, P = M0."""
        from gpsaccel.kalman.factory import kalman_filter  # filterpy: only when called

        return kalman_filter(self)

    @property
    def t(self) -> np.ndarray:
        """The epoch times, s (epoch i at step i·every)."""
        return np.arange(self.n_epochs) * self.every * self.dt

    @property
    def n_steps(self) -> int:
        """Propagation steps from the first epoch to the last."""
        return (self.n_epochs - 1) * self.every

    def simulate(self, rng: np.random.Generator, n_runs: int) -> tuple[np.ndarray, np.ndarray]:
        """``n_runs`` realizations: z (n_runs, n_epochs, p) and the true x (n_runs, n_epochs, n)
        at the epochs, drawn from ``rng`` (a ``numpy.random.Generator``)."""
        n_runs = _v.integer("n_runs", n_runs, minimum=1)
        n, m, p = self.n, self.Gamma.shape[1], self.H.shape[0]
        x = self.x0 + rng.standard_normal((n_runs, n)) @ np.linalg.cholesky(self.M0).T
        w = rng.standard_normal((self.n_steps, n_runs, m)) @ np.linalg.cholesky(self.W).T
        v = rng.standard_normal((n_runs, self.n_epochs, p)) @ np.linalg.cholesky(self.V).T
        xs = np.empty((n_runs, self.n_epochs, n))
        xs[:, 0] = x
        for j in range(self.n_steps):
            x = x @ self.Phi.T + w[j] @ self.Gamma.T          # x_{j+1} = Φ x_j + Γ w_j
            if (j + 1) % self.every == 0:
                xs[:, (j + 1) // self.every] = x
        return xs @ self.H.T + v, xs


@dataclass(frozen=True, eq=False)
class LinearIngredients:
    """What a student chooses writing a filter for a :class:`LinearModel`.

    Phi, Gamma, W : one-step Φ and the process noise Q = Γ W Γᵀ (``Q``, when given, is the
    one-step process noise instead); steps : predictions between updates; H, V, M0, x0 : as in
    the model; mean_propagated : False is x̄_i = x̂_{i−1}; update_every_step : False, or an update
    at every step with the "last" measurement (True is "last") or the "next" one; output,
    skip_first, skip_last, update_P, V_gain, form, updates, z_shift, z_weight, x0_from_z : see
    :class:`EpochFilter`.
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    W: np.ndarray
    steps: int
    H: np.ndarray
    V: np.ndarray
    M0: np.ndarray
    x0: np.ndarray
    n_epochs: int
    mean_propagated: bool = True
    output: str = "posterior"
    skip_first: bool | str = False
    skip_last: bool | str = False
    predict_first: bool = False
    update_P: bool = True
    update_every_step: bool | str = False
    Q: np.ndarray | None = None
    V_gain: np.ndarray | None = None
    form: str = "joseph"
    updates: str | None = None
    z_shift: str | None = None
    z_weight: np.ndarray | None = None
    x0_from_z: bool = False

    @classmethod
    def correct(cls, model: LinearModel) -> LinearIngredients:
        return cls(model.Phi, model.Gamma, model.W, model.every, model.H, model.V, model.M0,
                   model.x0, model.n_epochs)

    def epoch_filter(self) -> EpochFilter:
        Q = self.Gamma @ self.W @ self.Gamma.T if self.Q is None else self.Q   # Q = Γ W Γᵀ
        F, Qe = _transition(self.Phi, Q, self.steps)
        A = F if self.mean_propagated else np.eye(F.shape[0])
        x0, M0 = self.x0, self.M0
        if self.predict_first:                                 # one propagation before z_0:
            x0, M0 = A @ x0, F @ M0 @ F.T + Qe                 # x̄_0 = A x0, M_0 = F M0 Fᵀ + Q_e
        which = "last" if self.update_every_step is True else self.update_every_step
        fast = (self.Phi, Q, self.steps, which) if which else None
        return EpochFilter(A, F, Qe, self.H, self.V, x0, M0, self.n_epochs,
                           self.output, self.skip_first, self.skip_last, self.update_P, fast,
                           self.V_gain, self.form, self.updates, self.z_shift, self.z_weight,
                           self.x0_from_z)
