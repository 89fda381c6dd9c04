r"""The AAUSHIP model ship of report 004: a 9-state model, its driving input, truth and measurements.

The state and its units
-----------------------
``x = [x, ẋ, ẍ, y, ẏ, ÿ, ψ, ψ̇, ψ̈]``: position (m), velocity (m/s) and acceleration (m/s²) along
the world axes x and y, heading ψ (rad), yaw rate (rad/s) and yaw acceleration (rad/s²).  Indices
in :data:`STATES`.  The report's transition is block-diagonal; following the issue we take it as a
*world-frame* model, so the x–y track is (x, y) itself (the report's track figure dead-reckons a
track from ψ and ẋ instead).  The heading therefore does not steer the track in the model; the
designed input keeps them consistent along the plan.

One step, Ts = ``dt`` = 0.1 s (the report's code; its text says the IMU runs at 20 Hz)
--------------------------------------------------------------------------------------
Each axis (x, y, ψ) has the same 3x3 block with its drag coefficient β (1/s)::

    [p, v, a]_{k+1} = [[1, Ts, Ts²/2],   [p, v, a]_k  +  [0, 0, 1/m]ᵀ (u_k + w_k)
                       [0, 1,  Ts   ],
                       [0, −β, 0    ]]

The acceleration row says a_{k+1} = −β v_k + (force_k)/m: drag proportional to speed plus the
applied force per unit mass (per unit inertia I for ψ).  βx = 0.4462, βy = 0.0784, βψ = 1.3 (the
report's numbers); m = 12 kg, I = m (0.25² + 1.05²)/12 = 1.165 kg m² (the report's hull).
Rows 3 and 7 of the report's matrix have only eight entries in the text: row 3 is read as
``[0, −βx, 0, 0, 0, 0, 0, 0, 0]`` (the pattern of rows 6 and 9: drag on the velocity, nothing on
the acceleration itself), row 7 as ``[0, 0, 0, 0, 0, 0, 1, Ts, Ts²/2]`` (the pattern of rows 1 and
4, a leading zero lost).  Each block is stable: its eigenvalues are 1 and (1 ± √(1 − 4βTs))/2.

Known input (``B``, ``u``)
--------------------------
``u = [F_x, F_y, τ]``: the propeller thrust resolved on the world axes (N) and the rudder's yaw
torque (N m); ``B`` puts 1/m on ẍ and ÿ and 1/I on ψ̈.  The report loads its input from a file
(``inputD.mat``) that is not in the report, so :func:`gpsaccel.ship.plan.driving_input` designs one:
a racetrack survey (start from rest, accelerate to 1 m/s along x, a 180° left turn, back along −x, a second
180° left turn, along x again; 100 s).  The input is obtained by inverting the noise-free model
along that plan, so without noise the ship follows it exactly; thrust ≈ 5.4 N along x at cruise,
torque ≈ 0.26 N m in the turns.  Because the report's drag differs between the world axes, the
force that holds the plan is not exactly along the heading (the price of the world-frame reading).

Process noise (our choice; the report's ``Qz = cov(Z(n−1) Z(n)ᵀ)`` is not a covariance of anything)
----------------------------------------------------------------------------------------------------
Unknown forces (waves, gusts, propeller ripple) act where the known input acts: ``Γ = B`` and
``W = diag(σ_F², σ_F², σ_τ²)`` with σ_F = 0.5 N (about 10 % of the cruise thrust) and
σ_τ = 0.05 N m (about 20 % of the turning torque), white from step to step.  Q = Γ W Γᵀ has rank 3:
positions and velocities are disturbed only through the accelerations, as in a real hull.

Measurements
------------
Every state is measured (the report's ``An = I``) with the report's variances
``V = diag(15 m², 0.2 (m/s)², 4.9451e-5 (m/s²)², 16 m², 0.2, 4.8815e-5, 0.2 rad², 0.2 (rad/s)²,
2.3559e-5 (rad/s²)²)`` (the text's "4.945le-5" read as 4.9451e-5; its second ``varWvel = .2`` is
the yaw-rate variance).  The GPS supplies the x and y positions (rows 0 and 3, :data:`GPS_ROWS`),
the IMU everything else.  Monorate: every component at every step k = 1..N−1 (as the report's loop
``n = 2:N``; nothing is measured at k = 0).  Multirate: the IMU at ``imu_rate_hz`` (10 Hz, every
step) and the GPS at ``gps_rate_hz`` (1 Hz, k = 10, 20, ...; the report's counter gives k = 11,
21, ..., the same rate with a 0.1 s phase shift).

Start.  ``x0`` is the plan's state at k = 0 (at rest at the origin, heading east) and
``M0_ship = diag(4 m², 0.01 (m/s)², 0.01 (m/s²)², 4, 0.01, 0.01, 0.01 rad², 0.001 (rad/s)²,
0.001 (rad/s²)²)``.  The report starts with P = 0 and a truth exactly at 0, which makes the
position covariance singular at the first step without GPS.

Wind or current (``wind=True``), which the report proposes but does not implement
---------------------------------------------------------------------------------
Two more states ``[b_x, b_y]``, a force (N) on the hull along the world axes, entering like the
thrust (1/m on ẍ and ÿ), constant or a slow random walk: ``b_{k+1} = b_k + ω_k``,
``ω ~ N(0, wind_drift I₂)``, prior ``N(0, wind_prior I₂)``; by default wind_drift = 1e-5 N² per
step (σ ≈ 0.1 N over the 100 s voyage) and wind_prior = 1 N².  The wind is not measured.

The course-notation / filterpy mapping is that of :mod:`gpsaccel.calibration.model`, plus
``B`` (course) = ``B`` (filterpy) and ``u`` passed to ``predict(u=...)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.ship.plan import nominal_plan

if TYPE_CHECKING:  # filterpy pulls in scipy.stats (benchmarks/imports.py): imported where a filter is made
    from filterpy.kalman import KalmanFilter

#: Names and units of the 9 ship states, in order.
STATES = (("x", "m"), ("ẋ", "m/s"), ("ẍ", "m/s²"), ("y", "m"), ("ẏ", "m/s"), ("ÿ", "m/s²"),
          ("ψ", "rad"), ("ψ̇", "rad/s"), ("ψ̈", "rad/s²"))
#: Names and units of the two wind-force states of the augmented model.
WIND_STATES = (("b_x", "N"), ("b_y", "N"))
#: Measurement rows delivered by the GPS (x and y positions); the IMU delivers the others.
GPS_ROWS = (0, 3)
#: Report 004's measurement-noise variances, in state order.
REPORT_VARIANCES = (15.0, 0.2, 4.9451e-5, 16.0, 0.2, 4.8815e-5, 0.2, 0.2, 2.3559e-5)


def _drag(name: str, value: Any) -> tuple[float, float, float]:
    """Three positive drag coefficients (βx, βy, βψ)."""
    beta = tuple(value) if np.ndim(value) == 1 else ()
    if len(beta) != 3:
        raise ValueError(f"{name} must be three drag coefficients (βx, βy, βψ), got {value!r}")
    x, y, psi = (_v.positive_float(f"{name}[{i}]", b) for i, b in enumerate(beta))
    return x, y, psi


#: What each field of :class:`ShipModel` must be (a ValueError names the field otherwise).
FIELDS: dict[str, _v.Check] = {
    "dt": _v.positive_float, "n_samples": _v.count(2), "beta": _drag,
    "mass": _v.positive_float, "inertia": _v.positive_float,
    "V": _v.spd(9), "W": _v.spd(3), "M0_ship": _v.spd(9),
    "gps_rate_hz": _v.positive_float, "imu_rate_hz": _v.positive_float,
    "multirate": _v.flag, "wind": _v.flag, "wind_drift": _v.variance("N²"),
    "wind_prior": _v.positive_float,
}


@dataclass(frozen=True, eq=False)
class ShipModel:
    """Report 004's ship (module docstring); every field has the report's value or our stated choice.

    Parameters
    ----------
    dt : the step Ts (s).
    n_samples : N, samples k = 0..N−1 on the grid (n_steps = N − 1 steps).
    beta : drag coefficients (βx, βy, βψ) (1/s).
    mass : m (kg).  inertia : I about the vertical axis (kg m²); default m (0.25² + 1.05²)/12.
    V : 9x9 measurement-noise covariance (units of the states squared).
    W : 3x3 covariance of the random force and torque (N², N², (N m)²) per step.
    M0_ship : 9x9 a priori covariance of the ship states at k = 0 (``M0`` adds the wind's).
    gps_rate_hz, imu_rate_hz : sensor rates in the multirate case; each must divide 1/dt.
    multirate : which schedule ``schedule()`` returns by default (GPS at its own rate, or all at
        every step).
    wind : add the two wind-force states b_x, b_y (N).
    wind_drift : variance of the wind's random-walk step (N²); 0 for a constant wind.
    wind_prior : prior variance of each wind component at k = 0 (N²).
    """

    dt: float = 0.1
    n_samples: int = 1000
    beta: tuple[float, float, float] = (0.4462, 0.0784, 1.3)
    mass: float = 12.0
    inertia: float | None = None
    V: np.ndarray = field(default_factory=lambda: np.diag(REPORT_VARIANCES))
    W: np.ndarray = field(default_factory=lambda: np.diag([0.5**2, 0.5**2, 0.05**2]))
    M0_ship: np.ndarray = field(
        default_factory=lambda: np.diag([4.0, 0.01, 0.01, 4.0, 0.01, 0.01, 0.01, 0.001, 0.001]))
    gps_rate_hz: float = 1.0
    imu_rate_hz: float = 10.0
    multirate: bool = True
    wind: bool = False
    wind_drift: float = 1e-5
    wind_prior: float = 1.0

    def __post_init__(self) -> None:
        if self.inertia is None:  # the report's hull: m (0.25² + 1.05²)/12
            object.__setattr__(self, "inertia", _v.positive_float("mass", self.mass)
                               * (0.25**2 + 1.05**2) / 12.0)
        _v.fields(self, FIELDS)
        for name in ("gps_rate_hz", "imu_rate_hz"):
            _v.whole_multiple(f"1/{name}", 1.0 / getattr(self, name), self.dt, "dt")

    # ----------------------------------------------------------------- grid
    @property
    def n_steps(self) -> int:
        """Number of steps on the grid (N − 1 = 999 on the defaults)."""
        return self.n_samples - 1

    @property
    def t(self) -> np.ndarray:
        """Grid times t_k = k·Ts, k = 0..N−1 (s)."""
        return np.arange(self.n_samples) * self.dt

    @property
    def dim_x(self) -> int:
        """9, or 11 with the wind states."""
        return 11 if self.wind else 9

    @property
    def dim_z(self) -> int:
        return 9

    @property
    def dim_u(self) -> int:
        return 3

    @property
    def state_names(self) -> tuple[tuple[str, str], ...]:
        """(name, unit) of every state, in order."""
        return STATES + (WIND_STATES if self.wind else ())

    def periods(self, multirate: bool | None = None) -> np.ndarray:
        """(9,) steps between deliveries of each measurement component."""
        multirate = self.multirate if multirate is None else multirate
        out = np.ones(9, dtype=np.int64)
        if multirate:
            out[:] = round(1.0 / (self.imu_rate_hz * self.dt))
            out[list(GPS_ROWS)] = round(1.0 / (self.gps_rate_hz * self.dt))
        return out

    def schedule(self, multirate: bool | None = None) -> Schedule:
        """When each component is measured: k = 1..N−1 at its period (all every step if monorate)."""
        k = np.arange(self.n_samples)[:, None]
        available = (k % self.periods(multirate) == 0) & (k >= 1)
        return Schedule.from_mask(available)

    def schedule_from_mask(self, available: np.ndarray) -> Schedule:
        """A schedule from an (N, 9) boolean availability mask on the grid (k = 0..N−1)."""
        available = np.asarray(available)
        if available.shape != (self.n_samples, 9) or available.dtype != bool:
            raise ValueError(f"available must be a boolean array of shape ({self.n_samples}, 9), "
                             f"got {available.dtype} {available.shape}")
        return Schedule.from_mask(available)

    # ----------------------------------------------------------------- matrices
    @property
    def Phi(self) -> np.ndarray:
        """One-step transition Φ (block-diagonal 9x9; 11x11 with the wind pushing ẍ, ÿ)."""
        Ts = self.dt
        out = np.zeros((self.dim_x, self.dim_x))
        for axis, beta in enumerate(self.beta):
            i = 3 * axis
            out[i:i + 3, i:i + 3] = [[1.0, Ts, Ts**2 / 2], [0.0, 1.0, Ts], [0.0, -beta, 0.0]]
        if self.wind:
            out[:9, 9:] = self._force_input()[:, :2]
            out[9:, 9:] = np.eye(2)
        return out

    def _force_input(self) -> np.ndarray:
        """9x3: force F_x, F_y (N) and torque τ (N m) to the acceleration rows."""
        out = np.zeros((9, 3))
        out[2, 0] = out[5, 1] = 1.0 / self.mass
        assert self.inertia is not None  # set in __post_init__
        out[8, 2] = 1.0 / self.inertia
        return out

    @property
    def B(self) -> np.ndarray:
        """Control input of u = [F_x, F_y, τ] (dim_x x 3): 1/m on ẍ, ÿ and 1/I on ψ̈."""
        return np.vstack([self._force_input(), np.zeros((self.dim_x - 9, 3))])

    @property
    def Gamma(self) -> np.ndarray:
        """Noise input Γ: the random force/torque enters like u (and the wind walks, if any)."""
        if not self.wind:
            return self._force_input()
        out = np.zeros((11, 5))
        out[:9, :3] = self._force_input()
        out[9:, 3:] = np.eye(2)
        return out

    @property
    def W_full(self) -> np.ndarray:
        """Covariance of all the process noise of Γ: W, and the wind's drift with ``wind``."""
        if not self.wind:
            return self.W
        out = np.zeros((5, 5))
        out[:3, :3] = self.W
        out[3:, 3:] = self.wind_drift * np.eye(2)
        return out

    @property
    def Q(self) -> np.ndarray:
        """Process-noise covariance of one step Γ W Γᵀ (filterpy's ``Q``); rank 3 (5 with wind)."""
        G = self.Gamma
        return G @ self.W_full @ G.T

    @property
    def H(self) -> np.ndarray:
        """Every ship state measured: [I₉ 0] (the wind is not measured)."""
        return np.eye(9, self.dim_x)

    @property
    def x0(self) -> np.ndarray:
        """A priori mean at k = 0: the plan's start (and no wind)."""
        plan = nominal_plan(self)
        return np.concatenate([plan[0], np.zeros(self.dim_x - 9)])

    @property
    def M0(self) -> np.ndarray:
        """A priori covariance M0 of the whole state (M0_ship, and wind_prior I₂ with ``wind``)."""
        out = np.zeros((self.dim_x, self.dim_x))
        out[:9, :9] = self.M0_ship
        out[9:, 9:] = self.wind_prior * np.eye(self.dim_x - 9)
        return out

    def kalman_filter(self) -> KalmanFilter:
        """filterpy ``KalmanFilter``: F = Φ, B, Q = ΓWΓᵀ, H, R = V, P = M0 (with the wind prior)."""
        from gpsaccel.kalman.factory import kalman_filter  # filterpy: only when called

        return kalman_filter(self)

    def replace(self, **changes: Any) -> ShipModel:
        """A copy with some fields changed (validated again)."""
        from dataclasses import replace

        return replace(self, **changes)
