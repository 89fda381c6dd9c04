"""One realization of the calibration problem: truth, accelerometer, GPS and the filter's measurement.

Two truths, as in the reports:

``truth="error-model"`` (report 000's Monte Carlo)
    The true error state is propagated with the filter's own model, x_{j+1} = Φ x_j + Γ w_j from
    x_0 = [p0 − p̄0, v0 − v̄0, b].  The total truth is then p = p_c + δp, v = v_c + δv, which is the
    *Euler-integrated* true acceleration (the model is exact for it).

``truth="kinematic"`` (reports 001/003)
    The truth is the closed form of a(t) = A sin(ω t): v(t) = v0 + A/ω (1 − cos ω t),
    p(t) = p0 + (v0 + A/ω) t − A/ω² sin ω t, and the error state is x = [p − p_c, v − v_c, b].
    The Euler model does not describe this truth exactly (the accelerometer samples a(t_j) but the
    velocity integrates a over the interval); the Monte Carlo engine shows the consequence.

In both, the accelerometer is integrated by Euler's rule from (p̄0, v̄0),
``v_c(t_{j+1}) = v_c(t_j) + a_c(t_j) Δt``, ``p_c(t_{j+1}) = p_c(t_j) + v_c(t_j) Δt + a_c(t_j) Δt²/2``,
and the measurement is ``z_i = [GPS p − p_c, GPS v − v_c](t_i) = H x_i + η_i``.

Random draws, in this order from the given ``numpy.random.Generator``: p0, v0, b (standard normals
scaled by √M0 and the prior means), w (n_steps standard normals × √W), η (n_gps × 2 standard normals
through the Cholesky factor of V).  The same generator state gives the same realization under both
truths.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.truths import TRUTHS


@dataclass(frozen=True, eq=False)
class Realization:
    """One simulated run.  Times in s, positions in m, velocities in m/s, accelerations in m/s².

    t, t_gps : accelerometer (n_steps + 1) and GPS (n_gps) times.
    gps_steps : accelerometer-step index of each GPS time.
    x : (n_steps + 1, 3) true error state [δp, δv, b] at every accelerometer step.
    x_gps : (n_gps, 3) the same at GPS times.
    z : (n_gps, 2) measurement GPS − accelerometer-integrated [p, v].
    a, v, p : true acceleration, velocity, position (n_steps + 1).
    a_c, v_c, p_c : accelerometer reading and its Euler integrals (n_steps + 1).
    gps_p, gps_v : GPS position and velocity (n_gps).
    w : (n_steps,) accelerometer white noise;  eta : (n_gps, 2) GPS noise.
    p0, v0, b : the true initial position, velocity and the bias.
    truth : which truth built it.
    """

    truth: str
    t: np.ndarray
    t_gps: np.ndarray
    gps_steps: np.ndarray
    x: np.ndarray
    x_gps: np.ndarray
    z: np.ndarray
    a: np.ndarray
    v: np.ndarray
    p: np.ndarray
    a_c: np.ndarray
    v_c: np.ndarray
    p_c: np.ndarray
    gps_p: np.ndarray
    gps_v: np.ndarray
    w: np.ndarray
    eta: np.ndarray
    p0: float
    v0: float
    b: float


def euler_integrate(a: np.ndarray, dt: float, p_start: float, v_start: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Euler integrals of samples a(t_j), as the reports integrate the accelerometer.

    v(t_{j+1}) = v(t_j) + a(t_j) Δt;  p(t_{j+1}) = p(t_j) + v(t_j) Δt + a(t_j) Δt²/2.
    Returns (p, v), each as long as ``a``; the last sample of ``a`` is not used.
    """
    a = np.asarray(a, dtype=float)
    v = np.empty_like(a)
    v[0] = v_start
    np.cumsum(a[:-1] * dt, out=v[1:])
    v[1:] += v_start
    p = np.empty_like(a)
    p[0] = p_start
    np.cumsum(v[:-1] * dt + a[:-1] * dt**2 / 2, out=p[1:])
    p[1:] += p_start
    return p, v


def simulate(model: CalibrationModel, rng: np.random.Generator,
             truth: str = "error-model") -> Realization:
    """Draw one realization of ``model`` with ``rng`` (see the module docstring for both truths)."""
    _check_model(model)
    if not isinstance(rng, np.random.Generator):
        raise ValueError(
            f"rng must be a numpy.random.Generator (e.g. numpy.random.default_rng(0)), "
            f"got {type(rng).__name__}"
        )
    truth = _v.choice("truth", truth, TRUTHS)
    return _draw(model, rng, truth, _Shared.of(model, truth))


def _check_model(model: object) -> None:
    if not isinstance(model, CalibrationModel):
        raise ValueError(f"model must be a CalibrationModel, got {type(model).__name__}")


@dataclass(frozen=True)
class _Shared:
    """What every realization of one model and truth has in common, computed once for a batch
    (:func:`simulate_many`): the true acceleration a(t_j) and, for the closed-form truth, the
    terms of p(t) and v(t) that no draw enters (about half of a kinematic realization's time).

    ``position`` and ``velocity`` are :meth:`CalibrationModel.position` ``(t, 0, 0)`` and
    :meth:`~CalibrationModel.velocity` ``(t, 0)``: those evaluate p0 + v0 t + A t² g(ω t) and
    v0 + A t f(ω t) left to right, so p0 + v0 t + position and v0 + velocity are their values
    for (p0, v0) to the bit (tests/calibration/test_simulation.py holds it).
    """

    a: np.ndarray
    position: np.ndarray | None
    velocity: np.ndarray | None

    @staticmethod
    def of(model: CalibrationModel, truth: str) -> _Shared:
        t = model.t_imu
        if truth == "error-model":
            return _Shared(model.acceleration(t), None, None)
        return _Shared(model.acceleration(t), model.position(t, 0.0, 0.0), model.velocity(t, 0.0))


def _draw(model: CalibrationModel, rng: np.random.Generator, truth: str,
          shared: _Shared) -> Realization:
    """One realization (``simulate``'s), with the draw-free parts from ``shared``."""
    dt, n_steps = model.dt, model.n_steps
    t = model.t_imu
    gps_steps = np.arange(model.n_gps) * model.gps_every

    sd0 = np.sqrt(np.diag(model.M0))
    p0, v0, b = np.array([model.p0_mean, model.v0_mean, 0.0]) + sd0 * rng.standard_normal(3)
    w = np.sqrt(model.W[0, 0]) * rng.standard_normal(n_steps)
    eta = rng.standard_normal((model.n_gps, 2)) @ np.linalg.cholesky(model.V).T

    a = shared.a.copy()                      # each realization its own arrays, as always
    a_c = a + b
    a_c[:-1] += w
    p_c, v_c = euler_integrate(a_c, dt, model.p0_mean, model.v0_mean)

    if truth == "error-model":
        # x_{j+1} = Φ x_j + Γ w_j, written as sums: with c_j = Σ_{i<j} w_i,
        # δv_j = δv_0 − j Δt b − Δt c_j  and  δp_j = δp_0 + Δt Σ_{i<j} δv_i − j Δt²/2 b − Δt²/2 c_j.
        x = np.empty((n_steps + 1, 3))
        j = np.arange(n_steps + 1)
        c = np.concatenate(([0.0], np.cumsum(w)))
        x[:, 1] = (v0 - model.v0_mean) - j * dt * b - dt * c
        x[:, 0] = (p0 - model.p0_mean) + dt * np.concatenate(([0.0], np.cumsum(x[:-1, 1]))) \
            - j * dt**2 / 2 * b - dt**2 / 2 * c
        x[:, 2] = b
        p, v = p_c + x[:, 0], v_c + x[:, 1]
    else:
        assert shared.position is not None and shared.velocity is not None
        p, v = p0 + v0 * t + shared.position, v0 + shared.velocity
        x = np.column_stack([p - p_c, v - v_c, np.full(n_steps + 1, b)])

    x_gps = x[gps_steps]
    gps_p = p[gps_steps] + eta[:, 0]
    gps_v = v[gps_steps] + eta[:, 1]
    z = x_gps[:, :2] + eta  # = [gps_p − p_c, gps_v − v_c] without the cancellation error
    return Realization(truth, t, model.t_gps, gps_steps, x, x_gps, z, a, v, p, a_c, v_c, p_c,
                       gps_p, gps_v, w, eta, float(p0), float(v0), float(b))


def simulate_many(model: CalibrationModel, n_runs: int, seed: int = 0,
                  truth: str = "error-model") -> list[Realization]:
    """``n_runs`` independent realizations from ``numpy.random.default_rng(seed)``: those of
    ``simulate(model, rng, truth)`` called ``n_runs`` times, the truth's draw-free parts computed
    once."""
    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    _check_model(model)
    truth = _v.choice("truth", truth, TRUTHS)
    rng = np.random.default_rng(seed)
    shared = _Shared.of(model, truth)
    return [_draw(model, rng, truth, shared) for _ in range(n_runs)]


def truth_mean(model: CalibrationModel, truth: str) -> np.ndarray:
    """(n_gps, 3) E[x] at the GPS times: the deterministic part of the true error state.

    Zero for ``"error-model"``.  For ``"kinematic"``: [p_cf − p_E, v_cf − v_E, 0], the closed
    forms p_cf(t), v_cf(t) of a(t) from rest at 0 minus the Euler integrals p_E, v_E of the samples
    a(t_j) (m, m/s): what the Euler error model leaves out.  It does not depend on p0, v0, b or w
    (both integrations are linear in them), so it is computed from rest at 0, which keeps the
    rounding of p ≈ 3 km out of a difference of millimetres.
    """
    truth = _v.choice("truth", truth, TRUTHS)
    if truth == "error-model":
        return np.zeros((model.n_gps, 3))
    t = model.t_imu
    p_e, v_e = euler_integrate(model.acceleration(t), model.dt, 0.0, 0.0)
    p_cf, v_cf = model.position(t, 0.0, 0.0), model.velocity(t, 0.0)
    gps = np.arange(model.n_gps) * model.gps_every
    return np.column_stack([(p_cf - p_e)[gps], (v_cf - v_e)[gps], np.zeros(model.n_gps)])
