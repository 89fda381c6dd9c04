"""The exact reference: closed forms, agreement between precisions, the error measures."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from gpsaccel import CalibrationModel, simulate
from gpsaccel.kalman.exact import epoch_transition_exact, errors, exact_filter

# dt = 2⁻⁸ s: Φ and Γ are exact in float64, so the closed forms below hold to the last digit
EXACT_DT = CalibrationModel(dt=2.0**-8, gps_every=40, duration=30.0)


@pytest.fixture(scope="module")
def run():
    model = CalibrationModel()
    return model, simulate(model, np.random.default_rng(7)).z


def test_forty_steps_compose_into_the_closed_form():
    """Φ⁴⁰ = [[1, T, −T²/2], [0, 1, −T], [0, 0, 1]] and Q₄₀ = W [[Δt⁴(n³/3 − n/12), Δt³n²/2, 0],
    [Δt³n²/2, nΔt², 0], [0, 0, 0]] with T = nΔt, n = 40."""
    ctx = mpmath.MPContext()
    ctx.dps = 60
    m = EXACT_DT
    G = ctx.matrix(m.Gamma.tolist())
    F, Qn = epoch_transition_exact(ctx, m.Phi, G * ctx.mpf(float(m.W[0, 0])) * G.T, 40)
    n, dt, W = 40, ctx.mpf(m.dt), ctx.mpf(float(m.W[0, 0]))
    T = n * dt
    F_closed = ctx.matrix([[1, T, -T**2 / 2], [0, 1, -T], [0, 0, 1]])
    Q_closed = W * ctx.matrix([[dt**4 * (ctx.mpf(n)**3 / 3 - ctx.mpf(n) / 12), dt**3 * n**2 / 2, 0],
                               [dt**3 * n**2 / 2, n * dt**2, 0], [0, 0, 0]])
    assert ctx.mnorm(F - F_closed, 1) == 0
    assert ctx.mnorm(Q_closed - Qn, 1) < ctx.mpf(10)**-55 * ctx.mnorm(Q_closed, 1)


def test_first_update_is_the_closed_form(run):
    """At t = 0 with a diagonal M0 and H = [I₂ 0]: P = diag(m_p v_p/(m_p + v_p), m_v v_v/(m_v + v_v),
    m_b), x̂ = [m_p z_p/(m_p + v_p), m_v z_v/(m_v + v_v), 0]."""
    model, z = run
    ex = exact_filter(model, z)
    mp = mpmath.MPContext()
    mp.dps = 50
    m_p, m_v, m_b = (mp.mpf(v) for v in np.diag(model.M0))
    v_p, v_v = (mp.mpf(v) for v in np.diag(model.V))
    expected_P = [m_p * v_p / (m_p + v_p), m_v * v_v / (m_v + v_v), m_b]
    expected_x = [m_p * mp.mpf(z[0, 0]) / (m_p + v_p), m_v * mp.mpf(z[0, 1]) / (m_v + v_v), 0]
    for i in range(3):
        got_P = mp.mpf(ex.P[0, i, i]) + mp.mpf(ex.P_lo[0, i, i])
        assert abs(got_P - expected_P[i]) <= 1e-30 * expected_P[i]
        got_x = mp.mpf(ex.x_hat[0, i]) + mp.mpf(ex.x_hat_lo[0, i])
        assert abs(got_x - expected_x[i]) <= 1e-30 * (abs(expected_x[i]) + 1e-300)
    assert np.all(ex.P[0][~np.eye(3, dtype=bool)] == 0)


def test_fifty_digits_agree_with_eighty(run):
    """hi + lo of the 50-digit answer equals the 80-digit one to 10⁻³⁰ relative: its own error is
    nowhere near the float64 errors it measures."""
    model, z = run
    a, b = exact_filter(model, z, digits=50), exact_filter(model, z, digits=80)
    assert np.array_equal(a.x_hat, b.x_hat) and np.array_equal(a.P, b.P)
    assert np.all(np.abs(a.x_hat_lo - b.x_hat_lo) <= 1e-30 * np.abs(a.x_hat))
    assert np.all(np.abs(a.P_lo - b.P_lo) <= 1e-30 * np.abs(a.P))


def test_errors_measure_what_they_say(run):
    model, z = run
    ex = exact_filter(model, z)
    exact_self = errors(ex, ex.x_hat, ex.P)  # the exact answer rounded to float64: half an ulp
    assert exact_self.dx_sigma < 1e-13 and exact_self.dP_rel < 1e-15 and exact_self.asymmetry == 0
    x = ex.x_hat.copy()
    x[100, 2] += 3e-7 * ex.sigma[100, 2]
    P = ex.P.copy()
    P[20, 0, 1] += 2e-5 * ex.sigma[20, 0] * ex.sigma[20, 1]
    e = errors(ex, x, P)
    assert e.dx_sigma == pytest.approx(3e-7, rel=1e-6)
    assert e.dP_rel == pytest.approx(2e-5, rel=1e-9) and e.asymmetry == pytest.approx(2e-5, rel=1e-9)
    broken = errors(ex, np.full_like(x, np.nan), P)
    assert broken.dx_sigma == np.inf and broken.min_eig == -np.inf


def test_missing_components_are_not_measured(run):
    """NaN = not measured: an outage row leaves P = M there."""
    model, z = run
    z = z.copy()
    z[10] = np.nan
    ex = exact_filter(model, z)
    assert np.array_equal(ex.P[10], ex.M[10]) and not np.array_equal(ex.P[11], ex.M[11])


def test_bad_input_is_named(run):
    model, z = run
    with pytest.raises(ValueError, match="digits"):
        exact_filter(model, z, digits=10)
    with pytest.raises(ValueError, match="z"):
        exact_filter(model, z[:-1])
    ex = exact_filter(model, z)
    with pytest.raises(ValueError, match="shapes"):
        errors(ex, ex.x_hat[:-1], ex.P)
