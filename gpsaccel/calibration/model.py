r"""GPS-aided accelerometer calibration (reports 000, 001, 003): the 3-state error model.

The problem
-----------
A vehicle moves along a line with true acceleration ``a(t) = A sin(ω t)`` (m/s²).  An accelerometer
sampled every ``dt`` = 0.005 s (200 Hz) reads ``a_c(t_j) = a(t_j) + b + w(t_j)`` with a constant bias
``b ~ N(0, 0.01 (m/s²)²)`` and white noise ``w ~ N(0, W)``, ``W = 0.0004 (m/s²)²``.  Integrating
``a_c`` by Euler's rule from the prior means (p̄0, v̄0) gives ``p_c``, ``v_c``.  A GPS receiver
measures position and velocity every ``gps_every`` = 40 accelerometer samples (5 Hz) with noise
``V = diag(1 m², (0.04 m/s)²)``.

Error state and its model
-------------------------
``x = [δp, δv, b]`` with ``δp = p − p_c`` (m), ``δv = v − v_c`` (m/s), ``b`` (m/s²).  Subtracting the
Euler-integrated accelerometer from the Euler-integrated truth removes ``a(t_j)``::

    x_{j+1} = Φ x_j + Γ w_j,      Φ = [[1, Δt, −Δt²/2],      Γ = −[Δt²/2, Δt, 0]ᵀ
                                       [0,  1,  −Δt   ],
                                       [0,  0,   1    ]]

    z_i = H x_i + v_i,            H = [I₂ 0],   z_i = [GPS p − p_c, GPS v − v_c](t_i)

    x_0 ~ N(0, M0),               M0 = diag(100 m², 1 (m/s)², 0.01 (m/s²)²)

Course notation and filterpy's names (the one mapping used everywhere in gpsaccel)
-------------------------------------------------------------------------------------
============================  ================================  ========================
course                        meaning                           filterpy ``KalmanFilter``
============================  ================================  ========================
Φ  (``Phi``)                  one-step transition               ``F``
Γ W Γᵀ (``Q``)                process-noise covariance          ``Q``
H  (``H``)                    measurement matrix                ``H``
V  (``V``)                    measurement-noise covariance      ``R``
M0 (``M0``)                   a priori covariance at t = 0      ``P`` (before the first update)
x̄, M                          a priori mean and covariance      ``x_prior``, ``P_prior``
x̂, P                          a posteriori mean and covariance  ``x_post``, ``P_post``
K                             gain                              ``K``
r = z − H x̄                   residual (innovation)             ``y``
============================  ================================  ========================

Two conventions for the truth's frequency exist in the reports: report 000 writes
``a = 10 sin(ω t)`` with ω = 0.1 rad/s (``omega``); reports 001/003 write ``a = A sin(2π f t)``
(``frequency_hz``).  Pass at most one of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule

if TYPE_CHECKING:  # filterpy pulls in scipy.stats (benchmarks/imports.py): imported where a filter is made
    from filterpy.kalman import KalmanFilter

#: Report 000's angular frequency of the true acceleration (rad/s), used when neither
#: ``omega`` nor ``frequency_hz`` is given.
DEFAULT_OMEGA = 0.1


#: The error state [δp, δv, b]: names and units, in order (every table and figure uses these).
STATE_NAMES = ("δp", "δv", "b")
STATE_UNITS = ("m", "m/s", "m/s²")


def phi(dt: float, sign13: float = -1.0, sign23: float = -1.0) -> np.ndarray:
    """Transition Φ(Δt) of [δp, δv, b] over Δt (s)::

        Φ(Δt) = [[1, Δt, −Δt²/2],
                 [0, 1,  −Δt   ],
                 [0, 0,   1    ]]

    ``sign13=+1`` writes Φ₁₃ = +Δt²/2, report 001's slip (the checker's ``phi-sign``);
    ``sign23=+1`` writes Φ₂₃ = +Δt (with both, the bias enters as if the accelerometer read a − b).
    """
    return np.array([[1.0, dt, sign13 * dt**2 / 2], [0.0, 1.0, sign23 * dt], [0.0, 0.0, 1.0]])


def gamma(dt: float) -> np.ndarray:
    """Noise input Γ(Δt) = −[Δt²/2, Δt, 0]ᵀ (3x1): how accelerometer noise w (m/s²) enters."""
    return -np.array([[dt**2 / 2], [dt], [0.0]])


#: What each field of :class:`CalibrationModel` must be (a ValueError names the field otherwise).
FIELDS: dict[str, _v.Check] = {
    "dt": _v.positive_float, "gps_every": _v.count(1), "duration": _v.positive_float,
    "W": _v.spd(1), "V": _v.spd(2), "M0": _v.spd(3), "accel_amplitude": _v.finite_float,
    "omega": _v.optional(_v.positive_float), "frequency_hz": _v.optional(_v.positive_float),
    "p0_mean": _v.finite_float, "v0_mean": _v.finite_float,
}


@dataclass(frozen=True, eq=False)
class CalibrationModel:
    """The report-000 calibration problem; every field has the report's default.

    Parameters
    ----------
    dt : accelerometer sample interval Δt (s).
    gps_every : accelerometer samples per GPS interval (GPS interval = gps_every·dt s).
    duration : length of the run (s); a whole number of GPS intervals.
    W : accelerometer white-noise variance ((m/s²)²), a scalar or 1x1.
    V : GPS noise covariance, 2x2 (m², (m/s)²).
    M0 : a priori covariance of [δp, δv, b] at t = 0, 3x3 (m², (m/s)², (m/s²)²).
    accel_amplitude : A in a(t) = A sin(...) (m/s²).
    omega : angular frequency ω in a(t) = A sin(ω t) (rad/s); report 000's convention.
    frequency_hz : frequency f in a(t) = A sin(2π f t) (Hz); reports 001/003's convention.
    p0_mean, v0_mean : prior means p̄0 (m) and v̄0 (m/s) of the true initial position and velocity;
        the accelerometer integration starts from them.
    """

    dt: float = 0.005
    gps_every: int = 40
    duration: float = 30.0
    W: np.ndarray = field(default_factory=lambda: np.array([[0.0004]]))
    V: np.ndarray = field(default_factory=lambda: np.diag([1.0, 0.04**2]))
    M0: np.ndarray = field(default_factory=lambda: np.diag([100.0, 1.0, 0.01]))
    accel_amplitude: float = 10.0
    omega: float | None = None
    frequency_hz: float | None = None
    p0_mean: float = 0.0
    v0_mean: float = 100.0

    def __post_init__(self) -> None:
        if self.omega is not None and self.frequency_hz is not None:
            raise ValueError("omega and frequency_hz: give at most one (ω = 2π f)")
        _v.fields(self, FIELDS)
        _v.whole_multiple("duration", self.duration, self.gps_interval, "the GPS interval")
        self._check_reach()

    def _check_reach(self) -> None:
        """Every truth integrates a(t): |v − v0| ≤ |A| T and |p − p0 − v0 T| ≤ |A| T² must be
        numbers, as must the (v0 ± 5σ) T of the drawn initial state."""
        T = self.duration
        reach = max(abs(self.accel_amplitude) * T * max(T, 1.0),
                    (abs(self.v0_mean) + 5.0 * math.sqrt(self.M0[1, 1])) * T
                    + abs(self.p0_mean) + 5.0 * math.sqrt(self.M0[0, 0]))
        if not math.isfinite(reach) or reach > 1e300:
            raise ValueError(
                f"accel_amplitude = {self.accel_amplitude!r} m/s² (with v0_mean, p0_mean and M0) "
                f"over duration = {T!r} s: position and velocity would reach ≈ {reach:.3g}, "
                f"beyond float64; choose a smaller amplitude, prior or duration")

    # ----------------------------------------------------------------- time grid
    @property
    def gps_interval(self) -> float:
        """Time between GPS measurements (s)."""
        return self.gps_every * self.dt

    @property
    def n_gps(self) -> int:
        """Number of GPS epochs, t = 0 and t = duration included (151 on the defaults)."""
        return round(self.duration / self.gps_interval) + 1

    @property
    def n_steps(self) -> int:
        """Number of accelerometer steps in the run (6000 on the defaults)."""
        return (self.n_gps - 1) * self.gps_every

    @property
    def t_imu(self) -> np.ndarray:
        """Accelerometer sample times t_j = j·dt, j = 0..n_steps (s)."""
        return np.arange(self.n_steps + 1) * self.dt

    @property
    def t_gps(self) -> np.ndarray:
        """GPS times t_i = i·gps_every·dt (s)."""
        return np.arange(self.n_gps) * self.gps_interval

    @property
    def angular_frequency(self) -> float:
        """ω of the true acceleration (rad/s), whichever convention was given."""
        if self.frequency_hz is not None:
            return 2.0 * math.pi * self.frequency_hz
        return DEFAULT_OMEGA if self.omega is None else self.omega

    # ----------------------------------------------------------------- matrices
    @property
    def Phi(self) -> np.ndarray:
        """One accelerometer-step transition Φ(Δt) of [δp, δv, b]."""
        return phi(self.dt)

    @property
    def Gamma(self) -> np.ndarray:
        """Noise input Γ(Δt) (3x1): how w(t_j) enters [δp, δv, b]."""
        return gamma(self.dt)

    @property
    def Q(self) -> np.ndarray:
        """Process-noise covariance of one step, Γ W Γᵀ (filterpy's ``Q``)."""
        G = self.Gamma
        return G @ self.W @ G.T

    @property
    def H(self) -> np.ndarray:
        """GPS measurement matrix [I₂ 0]."""
        return np.eye(2, 3)

    @property
    def dim_x(self) -> int:
        return 3

    @property
    def dim_z(self) -> int:
        return 2

    @property
    def x0(self) -> np.ndarray:
        """A priori mean of the error state at t = 0: zero (the accelerometer starts at p̄0, v̄0)."""
        return np.zeros(3)

    def schedule(self) -> Schedule:
        """Which accelerometer steps carry a GPS measurement: both components every gps_every."""
        return Schedule.from_periods(self.n_steps, [self.gps_every, self.gps_every])

    def kalman_filter(self) -> KalmanFilter:
        """A filterpy ``KalmanFilter`` for one accelerometer step: F = Φ, Q = ΓWΓᵀ, H, R = V, P = M0."""
        from gpsaccel.kalman.factory import kalman_filter  # filterpy: only when called

        return kalman_filter(self)

    # ----------------------------------------------------------------- truth
    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """True acceleration a(t) = A sin(ω t) (m/s²)."""
        return self.accel_amplitude * np.sin(self.angular_frequency * np.asarray(t))

    def velocity(self, t: np.ndarray, v0: float) -> np.ndarray:
        """Closed-form true velocity v(t) = v0 + A/ω (1 − cos ω t) (m/s).

        Evaluated as v0 + A t f(ω t), f(x) = (1 − cos x)/x = 2 sin²(x/2)/x: no A/ω, which
        overflows for a tiny ω, and no 1 − cos x, which cancels for a small ω t."""
        w, A = self.angular_frequency, self.accel_amplitude
        t = np.asarray(t, dtype=float)
        return v0 + A * t * _one_minus_cos_over(w * t)

    def position(self, t: np.ndarray, p0: float, v0: float) -> np.ndarray:
        """Closed-form true position p(t) = p0 + (v0 + A/ω) t − A/ω² sin ω t (m).

        Evaluated as p0 + v0 t + A t² g(ω t), g(x) = (x − sin x)/x² (a series for small x), which
        is the same number without the A/ω² that is infinite for ω = 10⁻³⁰⁰ and without the
        cancellation of (A/ω) t against A/ω² sin ω t."""
        w, A = self.angular_frequency, self.accel_amplitude
        t = np.asarray(t, dtype=float)
        return p0 + v0 * t + A * t * t * _x_minus_sin_over_square(w * t)

    def replace(self, **changes: Any) -> CalibrationModel:
        """A copy with some fields changed (validated again)."""
        from dataclasses import replace

        return replace(self, **changes)


def _one_minus_cos_over(x: np.ndarray) -> np.ndarray:
    """(1 − cos x)/x = 2 sin²(x/2)/x, with the limit 0 at x = 0 (no cancellation)."""
    x = np.asarray(x, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 2.0 * np.sin(x / 2) ** 2 / x
    return np.where(np.abs(x) < 1e-150, x / 2, out)


def _x_minus_sin_over_square(x: np.ndarray) -> np.ndarray:
    """(x − sin x)/x², by its series Σ (−1)ᵏ x^(2k+1)/(2k+3)! (nine terms, Horner) for |x| < 1,
    where the direct form cancels (10⁻¹¹ relative at x = 0.01), else directly."""
    x = np.asarray(x, dtype=float)
    x2 = x * x
    series = np.ones_like(x2)
    for d in (342.0, 272.0, 210.0, 156.0, 110.0, 72.0, 42.0, 20.0):  # (2k+2)(2k+3), k = 8 .. 1
        series = 1.0 - x2 / d * series
    series = x / 6.0 * series
    with np.errstate(invalid="ignore", divide="ignore"):
        direct = (x - np.sin(x)) / x2
    return np.where(np.abs(x) < 1.0, series, direct)
