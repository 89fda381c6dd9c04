"""Simulated voyages of report 004's ship: the truth x_{k+1} = Φ x_k + B u_k + Γ w_k and its sensors."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.plan import driving_input


@dataclass(frozen=True, eq=False)
class ShipEnsemble:
    """Simulated voyages on the grid k = 0..N−1 (units of :data:`gpsaccel.ship.model.STATES`).

    One type for one voyage and for many: the arrays of an ensemble have a leading run axis
    (``n_runs``); :meth:`realization` takes one run out, without that axis.

    t : (N,) times (s).  u : (n_steps, 3) the known input.
    x : ([n_runs,] N, dim_x) true state of the model (9 ship states, plus the wind with ``wind``).
    wind : ([n_runs,] N, 2) the true wind force (N), zero when there is none.
    z : ([n_runs,] N, 9) every component as a sensor would read it at every k; NaN at k = 0
        (nothing is measured there).  A schedule picks which are used: :meth:`measurements`.
    """

    model: ShipModel
    t: np.ndarray
    u: np.ndarray
    x: np.ndarray
    wind: np.ndarray
    z: np.ndarray

    @property
    def n_runs(self) -> int | None:
        """Number of voyages; None for a single voyage (no run axis)."""
        return int(self.x.shape[0]) if self.x.ndim == 3 else None

    def measurements(self, schedule: Schedule) -> np.ndarray:
        """([n_runs,] n_epochs, 9) the rows of z at the schedule's epochs, NaN where not delivered."""
        _check_schedule(self.model, schedule)
        out = self.z[..., schedule.steps, :].copy()
        out[..., ~schedule.mask] = np.nan
        return out

    def realization(self, i: int) -> ShipEnsemble:
        """Run ``i`` on its own (arrays without the run axis)."""
        if self.n_runs is None:
            raise ValueError("realization() needs an ensemble; this is a single voyage")
        i = _v.integer("i", i, minimum=0)
        if i >= self.n_runs:
            raise ValueError(f"i must be < n_runs = {self.n_runs}, got {i}")
        return ShipEnsemble(self.model, self.t, self.u, self.x[i], self.wind[i], self.z[i])


#: A single voyage is a :class:`ShipEnsemble` without the run axis (the name says which is meant).
ShipRealization = ShipEnsemble


def _check_schedule(model: ShipModel, schedule: Schedule) -> None:
    if not isinstance(schedule, Schedule):
        raise ValueError(f"schedule must be a Schedule, got {type(schedule).__name__}")
    if schedule.n_steps != model.n_steps or schedule.dim_z != 9:
        raise ValueError(f"schedule must cover n_steps = {model.n_steps} with 9 components, got "
                         f"n_steps = {schedule.n_steps}, {schedule.dim_z} components")


def simulate_ensemble(model: ShipModel, n_runs: int, rng: np.random.Generator,
                      wind_force: tuple[float, float] | np.ndarray | None = None) -> ShipEnsemble:
    """Draw ``n_runs`` voyages: x_{k+1} = Φ x_k + B u_k + Γ w_k,  z_k = H x_k + v_k.

    The ship starts at x_0 ~ N(x0, M0).  ``wind_force`` (N, N) sets a wind the truth has: with a
    9-state model it is a constant force the filter does not know about; with ``wind=True`` it
    replaces the draw from the wind prior (the wind then drifts with ``wind_drift``).  Without it
    the 9-state truth has no wind and the 11-state truth draws it from N(0, wind_prior I₂).

    Random draws, in this order (the same for both models, so a seed gives the same ship noise):
    (n_runs, 11) standard normals for the start (ship states through the Cholesky factor of M0,
    then the wind), (n_runs, n_steps, 5) for the force/torque and the wind's walk,
    (n_runs, N, 9) for the sensors through the Cholesky factor of V.
    """
    if not isinstance(model, ShipModel):
        raise ValueError(f"model must be a ShipModel, got {type(model).__name__}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    if wind_force is not None:
        wind_force = _v.finite_array("wind_force", wind_force, (2,))
    N, n_steps = model.n_samples, model.n_steps
    e0 = rng.standard_normal((n_runs, 11))
    e_w = rng.standard_normal((n_runs, n_steps, 5))
    e_v = rng.standard_normal((n_runs, N, 9))

    # The truth always lives in the 11-state world (ship + wind); a 9-state model sees part of it.
    world = model.replace(wind=True, wind_drift=model.wind_drift if model.wind else 0.0)
    Phi, B, G = world.Phi, world.B, world.Gamma
    x = np.empty((n_runs, N, 11))
    x[:, 0, :9] = model.x0[:9] + e0[:, :9] @ np.linalg.cholesky(model.M0_ship).T
    if wind_force is not None:
        x[:, 0, 9:] = wind_force
    elif model.wind:
        x[:, 0, 9:] = math.sqrt(model.wind_prior) * e0[:, 9:]
    else:
        x[:, 0, 9:] = 0.0
    scale = np.sqrt(np.diag(world.W_full))
    u = driving_input(model)
    for k in range(n_steps):
        x[:, k + 1] = x[:, k] @ Phi.T + B @ u[k] + (e_w[:, k] * scale) @ G.T
    z = x[:, :, :9] + e_v @ np.linalg.cholesky(model.V).T
    z[:, 0] = np.nan
    keep = model.dim_x
    return ShipEnsemble(model, model.t, u, x[:, :, :keep].copy(), x[:, :, 9:].copy(), z)


def simulate_ship(model: ShipModel, rng: np.random.Generator,
                  wind_force: tuple[float, float] | np.ndarray | None = None) -> ShipRealization:
    """One voyage, drawn as run 0 of :func:`simulate_ensemble` (same draws, same order)."""
    return simulate_ensemble(model, 1, rng, wind_force).realization(0)
