"""The racetrack plan of report 004's ship and the known input that makes the model follow it.

The report loads its input from a file (``inputD.mat``) that is not in the report, so
:func:`driving_input` designs one: a racetrack survey (start from rest, accelerate to 1 m/s along x,
a 180° left turn, back along −x, a second 180° left turn, along x again; 100 s), obtained by
inverting the noise-free model along the plan (:func:`nominal_plan`), so that without noise the
ship follows it exactly.
"""

from __future__ import annotations

import functools
import math
from typing import Any, Protocol

import numpy as np


class ShipParameters(Protocol):
    """What the plan needs of :class:`gpsaccel.ship.model.ShipModel` (which needs the plan for its
    x0: a protocol here, not an import, so the two modules do not import each other)."""

    @property
    def dt(self) -> float: ...

    @property
    def n_samples(self) -> int: ...

    @property
    def beta(self) -> tuple[float, float, float]: ...

    @property
    def mass(self) -> float: ...

    @property
    def inertia(self) -> float | None: ...

#: The racetrack plan of :func:`driving_input`: cruise speed (m/s), the end of the speed-up (s),
#: the two 180° left turns (start, end in s) and the length of the smooth yaw-rate ramps (s).
PLAN: dict[str, Any] = {"speed": 1.0, "speed_up": 10.0, "turns": ((25.0, 45.0), (65.0, 85.0)), "ramp": 2.0}


def _smooth_step(s: np.ndarray) -> np.ndarray:
    """0 for s ≤ 0, 1 for s ≥ 1, (1 − cos π s)/2 between: a ramp with zero slope at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return (1.0 - np.cos(math.pi * s)) / 2.0


def planned_rates(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planned speed s(t) (m/s) and yaw rate r(t) (rad/s) of the racetrack, :data:`PLAN`.

    s rises smoothly from 0 to the cruise speed over ``speed_up`` s; r is a smooth trapezoid in
    each turn whose integral is exactly π (a 180° left turn).
    """
    t = np.asarray(t, dtype=float)
    speed = PLAN["speed"] * _smooth_step(t / PLAN["speed_up"])
    ramp = PLAN["ramp"]
    rate = np.zeros_like(t)
    for start, end in PLAN["turns"]:
        r_max = math.pi / (end - start - ramp)  # ∫ r dt = r_max (end − start − ramp)
        rate += r_max * (_smooth_step((t - start) / ramp) - _smooth_step((t - end + ramp) / ramp))
    return speed, rate


def nominal_plan(model: ShipParameters) -> np.ndarray:
    """(N + 1, 9) noise-free states along the plan, k = 0..N (one beyond the grid for the input).

    Velocities are the plan's speed along the planned heading; accelerations their forward
    differences (v_{k+1} − v_k)/Ts; positions and heading follow the model's own recursion
    p_{k+1} = p_k + Ts v_k + Ts²/2 a_k, so the plan is exactly a solution of
    x_{k+1} = Φ x_k + B u_k with the input of :func:`driving_input`.  It depends on Ts and N only.
    """
    return _plan(model.dt, model.n_samples).copy()


@functools.lru_cache(maxsize=8)
def _plan(Ts: float, n_samples: int) -> np.ndarray:
    n = n_samples + 1
    t = np.arange(n + 1) * Ts
    speed, rate = planned_rates(t)

    def integrate(v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """p_0 = 0, p_{k+1} = p_k + Ts v_k + Ts²/2 a_k."""
        return np.concatenate(([0.0], np.cumsum(Ts * v + Ts**2 / 2 * a)))

    out = np.zeros((n, 9))
    out[:, 7] = rate[:n]
    out[:, 8] = np.diff(rate) / Ts
    psi = integrate(out[:, 7], out[:, 8])  # n + 1 values: one more for the last velocity
    out[:, 6] = psi[:n]
    for col, f in ((1, np.cos), (4, np.sin)):
        v = speed * f(psi)
        out[:, col] = v[:n]
        out[:, col + 1] = np.diff(v) / Ts
        out[:, col - 1] = integrate(out[:, col], out[:, col + 1])[:n]
    out.flags.writeable = False
    return out


def driving_input(model: ShipParameters) -> np.ndarray:
    """(n_steps, 3) the known input u_k = [F_x, F_y, τ] (N, N, N m), k = 0..N−2.

    From the acceleration rows a_{k+1} = −β v_k + u_k/m of the plan:
    ``F = m (a_{k+1} + β v_k)`` for x and y, ``τ = I (ψ̈_{k+1} + βψ ψ̇_k)``.
    """
    plan = nominal_plan(model)[: model.n_samples]
    bx, by, bpsi = model.beta
    m, inertia = model.mass, model.inertia
    assert inertia is not None  # set in ShipModel.__post_init__
    return np.column_stack([m * (plan[1:, 2] + bx * plan[:-1, 1]),
                            m * (plan[1:, 5] + by * plan[:-1, 4]),
                            inertia * (plan[1:, 8] + bpsi * plan[:-1, 7])])
