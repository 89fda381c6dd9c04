r"""Cooperative air/ground localization (report 002, ASEN 5044): model, Jacobians, nominal, truth.

The system
----------
A ground vehicle (UGV, Ackermann steering, wheelbase L = 0.5 m) and an aerial vehicle (UAV,
unicycle) move in the plane.  State, input and measurement::

    x = [ξg, ηg, θg, ξa, ηa, θa]      (m, m, rad, m, m, rad)
    u = [vg, φg, va, ωa]              (m/s, rad, m/s, rad/s)

    ẋ = f(x, u) = [vg cos θg, vg sin θg, (vg/L) tan φg, va cos θa, va sin θa, ωa]

    y = h(x) = [atan2(ηa − ηg, ξa − ξg) − θg,     bearing UGV → UAV, relative to θg   (rad)
                √((ξg − ξa)² + (ηg − ηa)²),       range                                (m)
                atan2(ηg − ηa, ξg − ξa) − θa,     bearing UAV → UGV, relative to θa   (rad)
                ξa,                               UAV GPS easting                      (m)
                ηa]                               UAV GPS northing                     (m)

Bearings use ``atan2`` (the report's tan⁻¹ of a ratio loses the quadrant).  Angles are wrapped to
[−π, π) by :func:`wrap_angle` and nowhere else: states 3 and 6 (indices 2, 5), measurements 1 and 3
(indices 0, 2), and every error or innovation (:func:`state_residual`, :func:`measurement_residual`).

Jacobians (continuous time, analytic, as the report derives them)
-----------------------------------------------------------------
With Δξ = ξa − ξg, Δη = ηa − ηg, ρ² = Δξ² + Δη²::

    A = ∂f/∂x: A[0,2] = −vg sin θg, A[1,2] = vg cos θg, A[3,5] = −va sin θa, A[4,5] = va cos θa
    B = ∂f/∂u: B[0,0] = cos θg, B[1,0] = sin θg, B[2,0] = tan φg / L, B[2,1] = vg / (L cos² φg),
               B[3,2] = cos θa, B[4,2] = sin θa, B[5,3] = 1
    C = ∂h/∂x: rows 1 and 3  [ Δη/ρ², −Δξ/ρ², −1|0, −Δη/ρ², Δξ/ρ², 0|−1 ]
               row 2          [−Δξ/ρ, −Δη/ρ, 0, Δξ/ρ, Δη/ρ, 0],   rows 4, 5: [0 0 0 1 0 0], [0 0 0 0 1 0]

DT linearization (the course's Euler form, Ω = I)::

    F = I + ΔT·A,    G = ΔT·B,    H = C,    x_{k+1} = φ_ΔT(x_k, u) + w_k,   w_k ~ N(0, Q)

``Q`` is the covariance of the discrete-time process noise added once per step, in the truth and in
the filters alike (the course's Qtrue = diag(0.001, 0.001, 0.01, 0.001, 0.001, 0.01)); the
measurement noise is ``R`` (Rtrue = diag(0.0225 rad², 64 m², 0.04 rad², 36 m², 36 m²)).

Exact propagation
-----------------
With constant inputs both vehicles drive straight lines or circular arcs, so φ_ΔT has a closed
form (:func:`propagate`): for turn rate ω (UGV: ω = vg tan φg / L; UAV: ω = ωa) and speed v::

    θ' = θ + ωΔT,   ξ' = ξ + v ΔT·[sin θ' − sin θ]/(ωΔT),   η' = η − v ΔT·[cos θ' − cos θ]/(ωΔT)

(straight motion in the limit ωΔT → 0).  The nominal trajectory is the same ODE integrated by
``scipy.integrate.solve_ivp`` (the report's ode45), see :func:`nominal_trajectory`.

Course notation and filterpy
----------------------------
x̄, M (a priori) are filterpy's ``x_prior``, ``P_prior``; x̂, P (a posteriori) are ``x_post``,
``P_post``; F, Q, H, R are filterpy's names too; P0 is the covariance of x(0) about ``x0``.

One module past 500 lines: it is report 002's whole system, as calibration/model.py and
ship/model.py are theirs (its functions, their Jacobians, the angle wrapping every residual
goes through, the exact propagation and the course's data, and the class that binds them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from gpsaccel import _validation as _v

#: Names and units of the six states, used in labels.
STATES = (("ξg", "m"), ("ηg", "m"), ("θg", "rad"), ("ξa", "m"), ("ηa", "m"), ("θa", "rad"))
#: Names and units of the five measurements.
MEASUREMENTS = (("γag (UGV→UAV bearing − θg)", "rad"), ("ρ (range)", "m"),
                ("γga (UAV→UGV bearing − θa)", "rad"), ("ξa GPS", "m"), ("ηa GPS", "m"))
#: Indices of the angles among the states (θg, θa) and among the measurements (two bearings).
ANGLE_STATES = (2, 5)
ANGLE_MEASUREMENTS = (0, 2)

N_STATES, N_INPUTS, N_MEAS = 6, 4, 5

#: CoopModel.nominal's trajectories, keyed by what determines them (ΔT, duration, L, x(0), u0,
#: tolerances), read-only; at most :data:`_NOMINALS_KEPT`, the oldest dropped first.  No lock:
#: the checker's threads may share it and its graders fork, and a lock held at a fork would stay
#: held in the child; ``list(dict)`` and ``dict.pop(key, None)`` are each one step under the GIL.
_NOMINALS: dict[tuple, np.ndarray] = {}
_NOMINALS_KEPT = 8

#: Report 002's nominal initial state and constant input.
X0 = np.array([10.0, 0.0, math.pi / 2, -60.0, 0.0, -math.pi / 2])
U0 = np.array([2.0, -math.pi / 18, 12.0, math.pi / 25])
#: Covariance of the true x(0) about X0 (and the filters' initial P), the issue's convention.
P0_DEFAULT = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])


# --------------------------------------------------------------------------- angle wrapping
_TWO_PI = 2.0 * math.pi
#: Below this many angles one ``np.mod`` costs less than finding the few that need it.
_MOD_ALL_BELOW = 512


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Angle(s) wrapped to [−π, π) (rad).  The only place the package wraps an angle.

    mod(a + π, 2π) − π.  ``np.mod`` (libm's fmod and a floor division) was a sixth of the UKF's
    time; where 0 ≤ a + π < 2π the remainder is a + π itself, exactly, so only the other angles
    go through it: the same numbers, bit for bit (NaN among them).  Mostly every angle is
    inside, which a minimum and a maximum tell in two passes (the masks take five).
    """
    t = np.asarray(a, dtype=float) + math.pi
    if t.ndim == 0 or t.size < _MOD_ALL_BELOW:
        return np.mod(t, _TWO_PI) - math.pi
    if t.min() >= 0.0 and t.max() < _TWO_PI:  # all inside (a NaN fails both): two reductions
        t -= math.pi
        return t
    out = t - math.pi
    outside = ~((t >= 0.0) & (t < _TWO_PI))
    if outside.any():
        out[outside] = np.mod(t[outside], _TWO_PI) - math.pi
    return out


def angle_index(angles: tuple[int, ...]) -> slice | list[int]:
    """Angle indices (``ANGLE_STATES``, ``ANGLE_MEASUREMENTS``) as a basic slice when they are two
    (indexing with it is a view, not a fancy-indexed copy); others as a list."""
    if len(angles) == 2 and angles[1] > angles[0]:
        return slice(angles[0], angles[1] + 1, angles[1] - angles[0])
    return list(angles)


_STATE_ANGLES, _MEASUREMENT_ANGLES = angle_index(ANGLE_STATES), angle_index(ANGLE_MEASUREMENTS)


def _wrap_at(v: np.ndarray, at: slice | list[int], copy: bool = True) -> np.ndarray:
    out = np.array(v, dtype=float, copy=True) if copy else v
    out[..., at] = wrap_angle(out[..., at])
    return out


def wrap_state_inplace(x: np.ndarray) -> np.ndarray:
    """:func:`wrap_state` on a float array the caller owns, in place (no copy); returns it.

    For the filters' own temporaries (sigma points, a propagated step), which a copy per step
    only made slower."""
    return _wrap_at(x, _STATE_ANGLES, copy=False)


def wrap_state(x: np.ndarray) -> np.ndarray:
    """A copy of state(s) x (..., 6) with θg and θa wrapped to [−π, π)."""
    return _wrap_at(x, _STATE_ANGLES)


def wrap_measurement(y: np.ndarray) -> np.ndarray:
    """A copy of measurement(s) y (..., 5) with both bearings wrapped to [−π, π)."""
    return _wrap_at(y, _MEASUREMENT_ANGLES)


def state_residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a − b for states (..., 6), the heading differences wrapped (an error or a perturbation)."""
    return _wrap_at(np.asarray(a, dtype=float) - np.asarray(b, dtype=float), _STATE_ANGLES,
                    copy=False)  # the difference is new: wrapped where it is


def measurement_residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a − b for measurements (..., 5), the bearing differences wrapped (an innovation)."""
    return _wrap_at(np.asarray(a, dtype=float) - np.asarray(b, dtype=float),
                    _MEASUREMENT_ANGLES, copy=False)


# --------------------------------------------------------------------------- f, h, Jacobians
def _state(x: object, name: str = "x") -> np.ndarray:
    # a finite float array of states passes as it is (nothing here writes to it): the filters
    # call f, h and the Jacobians every step, where the full check cost a tenth of the loop
    if (type(x) is np.ndarray and x.dtype == np.float64 and x.ndim >= 1
            and x.shape[-1] == N_STATES and np.isfinite(x).all()):
        return x
    arr = _v.finite_array(name, x)
    if arr.ndim < 1 or arr.shape[-1] != N_STATES:
        raise ValueError(f"{name} must have {N_STATES} states in its last axis "
                         f"[ξg, ηg, θg, ξa, ηa, θa], got shape {arr.shape}")
    return arr


def _input(u: object) -> np.ndarray:
    if (type(u) is np.ndarray and u.dtype == np.float64 and u.shape == (N_INPUTS,)
            and np.isfinite(u).all()):
        return u  # as _state: passed as it is
    arr = _v.finite_array("u", u)
    if arr.shape != (N_INPUTS,):
        raise ValueError(f"u must have shape ({N_INPUTS},) [vg, φg, va, ωa], got {arr.shape}")
    return arr


def f(x: np.ndarray, u: np.ndarray, L: float = 0.5) -> np.ndarray:
    """ẋ = f(x, u) for states x (..., 6), input u (4,), wheelbase L (m)."""
    x, u = _state(x), _input(u)
    out = np.empty_like(x)
    out[..., 0] = u[0] * np.cos(x[..., 2])
    out[..., 1] = u[0] * np.sin(x[..., 2])
    out[..., 2] = u[0] / L * math.tan(u[1])
    out[..., 3] = u[2] * np.cos(x[..., 5])
    out[..., 4] = u[2] * np.sin(x[..., 5])
    out[..., 5] = u[3]
    return out


def h(x: np.ndarray) -> np.ndarray:
    """y = h(x) for states x (..., 6) → (..., 5), bearings wrapped to [−π, π)."""
    return _wrap_at(h_unwrapped(_state(x)), _MEASUREMENT_ANGLES, copy=False)


def h_unwrapped(x: np.ndarray) -> np.ndarray:
    """h(x) with the bearings as atan2(...) − heading, not wrapped (in (−3π, 3π))."""
    dxi = x[..., 3] - x[..., 0]
    deta = x[..., 4] - x[..., 1]
    y = np.empty(x.shape[:-1] + (N_MEAS,))
    y[..., 0] = np.arctan2(deta, dxi) - x[..., 2]
    y[..., 1] = np.hypot(dxi, deta)
    y[..., 2] = np.arctan2(-deta, -dxi) - x[..., 5]
    y[..., 3] = x[..., 3]
    y[..., 4] = x[..., 4]
    return y


def jacobian_A(x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """A = ∂f/∂x (..., 6, 6) at states x (..., 6) and input u."""
    x, u = _state(x), _input(u)
    A = np.zeros(x.shape[:-1] + (6, 6))
    A[..., 0, 2] = -u[0] * np.sin(x[..., 2])
    A[..., 1, 2] = u[0] * np.cos(x[..., 2])
    A[..., 3, 5] = -u[2] * np.sin(x[..., 5])
    A[..., 4, 5] = u[2] * np.cos(x[..., 5])
    return A


def jacobian_B(x: np.ndarray, u: np.ndarray, L: float = 0.5) -> np.ndarray:
    """B = ∂f/∂u (..., 6, 4) at states x (..., 6) and input u."""
    x, u = _state(x), _input(u)
    B = np.zeros(x.shape[:-1] + (6, 4))
    B[..., 0, 0] = np.cos(x[..., 2])
    B[..., 1, 0] = np.sin(x[..., 2])
    B[..., 2, 0] = math.tan(u[1]) / L
    B[..., 2, 1] = u[0] / (L * math.cos(u[1]) ** 2)
    B[..., 3, 2] = np.cos(x[..., 5])
    B[..., 4, 2] = np.sin(x[..., 5])
    B[..., 5, 3] = 1.0
    return B


def jacobian_C(x: np.ndarray) -> np.ndarray:
    """C = ∂h/∂x (..., 5, 6) at states x (..., 6); undefined when the vehicles coincide."""
    x = _state(x)
    dxi = x[..., 3] - x[..., 0]
    deta = x[..., 4] - x[..., 1]
    r2 = dxi**2 + deta**2
    r = np.sqrt(r2)
    C = np.zeros(x.shape[:-1] + (5, 6))
    for row in (0, 2):  # both bearings share the position partials (they differ by π)
        C[..., row, 0] = deta / r2
        C[..., row, 1] = -dxi / r2
        C[..., row, 3] = -deta / r2
        C[..., row, 4] = dxi / r2
    C[..., 0, 2] = -1.0
    C[..., 2, 5] = -1.0
    C[..., 1, 0] = -dxi / r
    C[..., 1, 1] = -deta / r
    C[..., 1, 3] = dxi / r
    C[..., 1, 4] = deta / r
    C[..., 3, 3] = 1.0
    C[..., 4, 4] = 1.0
    return C


def _arc(xi, eta, theta, v, omega, dt):
    """Exact motion over dt at speed v and turn rate omega (scalars): straight or a circular arc."""
    s = omega * dt
    theta1 = theta + s
    if abs(s) < 1e-9:  # straight line; the arc formula's error there is O(s²) ≈ 0
        c = 0.5 * s
        return (xi + v * dt * np.cos(theta + c), eta + v * dt * np.sin(theta + c), theta1)
    k = v * dt / s
    return (xi + k * (np.sin(theta1) - np.sin(theta)),
            eta - k * (np.cos(theta1) - np.cos(theta)), theta1)


def propagate(x: np.ndarray, u: np.ndarray, dt: float, L: float = 0.5) -> np.ndarray:
    """φ_dt(x, u): the exact solution of ẋ = f(x, u) over dt (s) with constant u; x (..., 6).

    Angles are not wrapped here (callers wrap with :func:`wrap_state`).
    """
    x, u = _state(x), _input(u)
    out = np.empty_like(x)
    out[..., 0], out[..., 1], out[..., 2] = _arc(x[..., 0], x[..., 1], x[..., 2], u[0],
                                                 u[0] / L * math.tan(u[1]), dt)
    out[..., 3], out[..., 4], out[..., 5] = _arc(x[..., 3], x[..., 4], x[..., 5], u[2], u[3], dt)
    return out


# --------------------------------------------------------------------------- the model
def _csv(name: str) -> np.ndarray:
    ref = resources.files("gpsaccel") / "data" / "cooplocalization" / name
    with resources.as_file(ref) as path:
        return np.loadtxt(path, delimiter=",", ndmin=1)


def course_Q() -> np.ndarray:
    """The course's Qtrue (6 x 6), from package data (Qtrue.csv)."""
    return _csv("Qtrue.csv").reshape(6, 6)


def course_R() -> np.ndarray:
    """The course's Rtrue (5 x 5), from package data (Rtrue.csv)."""
    return _csv("Rtrue.csv").reshape(5, 5)


def course_ydata() -> np.ndarray:
    """The course's observation log as stored: 5 x 1001, first column NaN (package data)."""
    return _csv("ydata.csv")


def course_tvec() -> np.ndarray:
    """The course's time vector (1001,), 0..100 s every 0.1 s (package data)."""
    return _csv("tvec.csv")


#: What each field of :class:`CoopModel` must be (a ValueError names the field otherwise).
FIELDS: dict[str, _v.Check] = {
    "dt": _v.positive_float, "duration": _v.positive_float, "L": _v.positive_float,
    "x0": _v.array(N_STATES), "u0": _v.array(N_INPUTS), "P0": _v.spd(N_STATES),
    "Qtrue": _v.spd(N_STATES), "Rtrue": _v.spd(N_MEAS),
}


@dataclass(frozen=True, eq=False)
class CoopModel:
    """Report 002's cooperative localization problem; every field has the course's default.

    Parameters
    ----------
    dt : sample interval ΔT (s).
    duration : length of a run (s); a whole number of ΔT.
    L : UGV wheelbase (m).
    x0 : nominal initial state (6,) (m, m, rad, m, m, rad).
    u0 : constant nominal input (4,) (m/s, rad, m/s, rad/s).
    P0 : covariance of the true x(0) about x0 (6 x 6), also the filters' initial P.
    Qtrue : covariance of the DT process noise added once per step (6 x 6) (m², rad²).
    Rtrue : measurement-noise covariance (5 x 5) (rad², m², rad², m², m²).
    """

    dt: float = 0.1
    duration: float = 100.0
    L: float = 0.5
    x0: np.ndarray = field(default_factory=lambda: X0.copy())
    u0: np.ndarray = field(default_factory=lambda: U0.copy())
    P0: np.ndarray = field(default_factory=lambda: P0_DEFAULT.copy())
    Qtrue: np.ndarray = field(default_factory=course_Q)
    Rtrue: np.ndarray = field(default_factory=course_R)

    def __post_init__(self) -> None:
        _v.fields(self, FIELDS)
        _v.whole_multiple("duration", self.duration, self.dt, "dt")

    # ----------------------------------------------------------------- time grid
    @property
    def n_steps(self) -> int:
        """Number of ΔT steps in a run (1000 on the defaults)."""
        return round(self.duration / self.dt)

    @property
    def t(self) -> np.ndarray:
        """Sample times t_k = k·ΔT, k = 0..n_steps (s)."""
        return np.arange(self.n_steps + 1) * self.dt

    # ----------------------------------------------------------------- model functions
    def f(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """ẋ = f(x, u) (u defaults to u0)."""
        return f(x, self.u0 if u is None else u, self.L)

    def h(self, x: np.ndarray) -> np.ndarray:
        """y = h(x), bearings wrapped."""
        return h(x)

    def A(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """∂f/∂x at (x, u)."""
        return jacobian_A(x, self.u0 if u is None else u)

    def B(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """∂f/∂u at (x, u)."""
        return jacobian_B(x, self.u0 if u is None else u, self.L)

    def C(self, x: np.ndarray) -> np.ndarray:
        """∂h/∂x at x."""
        return jacobian_C(x)

    def F(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """DT transition of a perturbation, F = I + ΔT·A(x, u)."""
        return np.eye(N_STATES) + self.dt * self.A(x, u)

    def G(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """DT input matrix of a perturbation, G = ΔT·B(x, u)."""
        return self.dt * self.B(x, u)

    def H(self, x: np.ndarray) -> np.ndarray:
        """DT measurement matrix of a perturbation, H = C(x)."""
        return self.C(x)

    def step(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """Noiseless one-step propagation φ_ΔT(x, u), exact (closed form), angles wrapped."""
        return wrap_state(propagate(x, self.u0 if u is None else u, self.dt, self.L))

    # ----------------------------------------------------------------- trajectories
    def nominal(self, x_start: np.ndarray | None = None, rtol: float = 1e-12,
                atol: float = 1e-10) -> np.ndarray:
        """The noiseless nonlinear trajectory (n_steps+1, 6) from ``x_start`` (default x0).

        Integrated by ``scipy.integrate.solve_ivp`` (DOP853, the given tolerances) with the
        input held at u0, evaluated at :attr:`t`; angles wrapped.  The integration is
        deterministic, so each distinct problem is integrated once per process and every call
        gets its own copy (:data:`_NOMINALS`: a graded coop notebook asks for the same
        trajectory about nine times, and integrating it was most of the grader's own CPU for the
        notebook; benchmarks/per_file.py measures a coop notebook's grade).
        """
        x_start = self.x0 if x_start is None else _v.finite_array("x_start", x_start,
                                                                   (N_STATES,))
        key = (self.dt, self.duration, self.L, np.asarray(x_start, float).tobytes(),
               self.u0.tobytes(), float(rtol), float(atol))
        kept = _NOMINALS.get(key)
        if kept is None:
            kept = self._integrate(x_start, rtol, atol)
            kept.flags.writeable = False
            _NOMINALS[key] = kept
            for old in list(_NOMINALS)[:-_NOMINALS_KEPT]:  # the oldest first (dicts keep order)
                _NOMINALS.pop(old, None)
        return kept.copy()

    def _integrate(self, x_start: np.ndarray, rtol: float, atol: float) -> np.ndarray:
        from scipy.integrate import solve_ivp  # here, not at import (benchmarks/imports.py)

        u = self.u0
        sol = solve_ivp(lambda _t, x: f(x, u, self.L), (0.0, self.t[-1]), x_start,
                        method="DOP853", t_eval=self.t, rtol=rtol, atol=atol)
        if not sol.success:  # pragma: no cover - DOP853 on this smooth ODE does not fail
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        return wrap_state(sol.y.T)

    def linearized_simulation(self, dx0: np.ndarray, nominal: np.ndarray | None = None
                              ) -> tuple[np.ndarray, np.ndarray]:
        """Noiseless DT perturbation propagation about the nominal (report 002 part 1c).

        δx_{k+1} = F_k δx_k with F_k = I + ΔT·A(x*_k, u0), δy_k = H_k δx_k with H_k = C(x*_k).
        Returns (δx (n_steps+1, 6), δy (n_steps+1, 5)); the total state is x* + δx and the
        linearized measurement h(x*) + δy.
        """
        dx0 = _v.finite_array("dx0", dx0, (N_STATES,))
        xn = self.nominal() if nominal is None else self._trajectory("nominal", nominal)
        F = self.F(xn)
        dx = np.empty_like(xn)
        dx[0] = dx0
        for k in range(self.n_steps):
            dx[k + 1] = F[k] @ dx[k]
        dy = np.einsum("kij,kj->ki", self.C(xn), dx)
        return dx, dy

    def simulate(self, rng: np.random.Generator, n_runs: int = 1,
                 Q: np.ndarray | None = None) -> Truth:
        """``n_runs`` truth runs with process noise and their noisy measurements.

        The course's convention, per step: integrate the noiseless ODE over ΔT (exactly, by
        :func:`propagate`), then add w_k ~ N(0, Q) (default Qtrue); x(0) ~ N(x0, P0);
        y_k = h(x_k) + v_k, v_k ~ N(0, Rtrue) for k ≥ 1 (y_0 is NaN, as in the course's log).
        Random numbers are drawn in a fixed order: x(0) for all runs, w for all steps, v for all
        steps, so a seed fixes everything.
        """
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy.random.Generator (e.g. "
                             f"numpy.random.default_rng(0)), got {type(rng).__name__} {rng!r}")
        n_runs = _v.integer("n_runs", n_runs, minimum=1)
        Q = self.Qtrue if Q is None else _v.spd_matrix("Q", Q, N_STATES)
        K = self.n_steps
        x = np.empty((n_runs, K + 1, N_STATES))
        x[:, 0] = wrap_state(self.x0 + rng.standard_normal((n_runs, 6))
                             @ np.linalg.cholesky(self.P0).T)
        w = rng.standard_normal((K, n_runs, 6)) @ np.linalg.cholesky(Q).T
        v = rng.standard_normal((n_runs, K + 1, 5)) @ np.linalg.cholesky(self.Rtrue).T
        for k in range(K):
            x[:, k + 1] = wrap_state_inplace(propagate(x[:, k], self.u0, self.dt, self.L) + w[k])
        y = wrap_measurement(h(x) + v)
        y[:, 0] = np.nan
        return Truth(self.t, x, y)

    def log(self, ydata: np.ndarray | None = None) -> np.ndarray:
        """An observation log in the course's layout (5 x n_steps+1) as rows (n_steps+1, 5).

        Default: the course's 100-second log (package data).  A NaN means "not measured" (the
        log's first column is all NaN); infinities are refused.
        """
        ydata = course_ydata() if ydata is None else ydata
        arr = _v.finite_array("ydata", ydata, (N_MEAS, self.n_steps + 1), allow_nan=True)
        return arr.T.copy()

    def _trajectory(self, name: str, x: object) -> np.ndarray:
        return _v.finite_array(name, x, (self.n_steps + 1, N_STATES))


@dataclass
class Truth:
    """Monte Carlo truth runs: t (K+1,) s, x (N, K+1, 6), y (N, K+1, 5) with y[:, 0] = NaN."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray

    @property
    def n_runs(self) -> int:
        return self.x.shape[0]
