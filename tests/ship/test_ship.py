"""The ship of report 004: model, input, schedules, the multirate driver on it, the zeroed gain,
the four-filter Monte Carlo and the wind states."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.kalman.consistency import chi2_bounds, nees
from gpsaccel.kalman.gain_sequence import apply_gains
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.ship.comparison import compare_ship_filters, compare_wind, quadratic_form
from gpsaccel.ship.model import GPS_ROWS, REPORT_VARIANCES, ShipModel
from gpsaccel.ship.plan import driving_input, nominal_plan
from gpsaccel.ship.simulation import simulate_ensemble, simulate_ship
from gpsaccel.ship.zeroed_gain import joseph, run_zeroed_gain

N_RUNS = 200
IMU_ROWS = [c for c in range(9) if c not in GPS_ROWS]


@pytest.fixture(scope="module")
def model():
    return ShipModel()


@pytest.fixture(scope="module")
def comparison():
    return compare_ship_filters(n_runs=N_RUNS, seed=0)


# --------------------------------------------------------------------------- the model
def test_matrices_are_the_reports(model):
    Ts, (bx, by, bpsi) = 0.1, (0.4462, 0.0784, 1.3)
    Phi = model.Phi
    assert Phi.shape == (9, 9)
    np.testing.assert_array_equal(Phi[0], [1, Ts, Ts**2 / 2, 0, 0, 0, 0, 0, 0])
    np.testing.assert_array_equal(Phi[2], [0, -bx, 0, 0, 0, 0, 0, 0, 0])   # garbled row 3
    np.testing.assert_array_equal(Phi[5], [0, 0, 0, 0, -by, 0, 0, 0, 0])
    np.testing.assert_array_equal(Phi[6], [0, 0, 0, 0, 0, 0, 1, Ts, Ts**2 / 2])  # garbled row 7
    np.testing.assert_array_equal(Phi[8], [0, 0, 0, 0, 0, 0, 0, -bpsi, 0])
    off_block = Phi.copy()
    for i in (0, 3, 6):
        off_block[i:i + 3, i:i + 3] = 0
    assert not off_block.any()
    np.testing.assert_array_equal(model.V, np.diag(REPORT_VARIANCES))
    np.testing.assert_array_equal(model.H, np.eye(9))
    assert model.inertia == pytest.approx(12 * (0.25**2 + 1.05**2) / 12)
    # Q = Γ W Γᵀ with the random force where the input acts: rank 3, only acceleration rows
    assert np.linalg.matrix_rank(model.Q) == 3
    np.testing.assert_allclose(np.diag(model.Q)[[2, 5, 8]],
                               [0.25 / 144, 0.25 / 144, 0.0025 / model.inertia**2])
    np.testing.assert_array_equal(model.Gamma, model.B)


def test_kalman_filter_mapping(model):
    kf = model.kalman_filter()
    for ours, theirs in ((model.Phi, kf.F), (model.B, kf.B), (model.Q, kf.Q), (model.H, kf.H),
                         (model.V, kf.R), (model.M0, kf.P)):
        np.testing.assert_array_equal(ours, theirs)
    np.testing.assert_array_equal(kf.x[:, 0], model.x0)


def test_designed_input_makes_the_plan_an_exact_solution(model):
    plan, u = nominal_plan(model), driving_input(model)
    assert u.shape == (999, 3)
    x = plan[0]
    for k in range(model.n_steps):
        x = model.Phi @ x + model.B @ u[k]
        np.testing.assert_allclose(x, plan[k + 1], atol=1e-9)
    # the racetrack: cruise at 1 m/s, two 180° left turns, back on the x axis heading east
    assert np.hypot(plan[200, 1], plan[200, 4]) == pytest.approx(1.0, abs=1e-9)
    assert plan[999, 6] == pytest.approx(2 * np.pi, abs=1e-9)
    assert plan[999, 3] == pytest.approx(0.0, abs=1e-9)
    assert u[200, 0] == pytest.approx(12 * 0.4462 * 1.0, rel=1e-9)  # thrust = m βx v at cruise


def test_schedules(model):
    mono, multi = model.schedule(multirate=False), model.schedule(multirate=True)
    np.testing.assert_array_equal(mono.steps, np.arange(1, 1000))
    assert mono.mask.all()
    np.testing.assert_array_equal(multi.steps, np.arange(1, 1000))
    assert multi.mask[:, IMU_ROWS].all()
    gps_steps = multi.steps[multi.mask[:, 0]]
    np.testing.assert_array_equal(gps_steps, np.arange(10, 1000, 10))
    np.testing.assert_array_equal(multi.mask[:, 0], multi.mask[:, 3])
    slow = model.replace(gps_rate_hz=0.5, imu_rate_hz=5.0).schedule()
    np.testing.assert_array_equal(slow.steps, np.arange(2, 1000, 2))
    assert slow.mask[:, IMU_ROWS].all()
    np.testing.assert_array_equal(slow.steps[slow.mask[:, 0]], np.arange(20, 1000, 20))


# --------------------------------------------------------------------------- the driver on it
@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_driver_against_a_hand_computed_update_on_the_reduced_H(model, method):
    run = simulate_ship(model, np.random.default_rng(3))
    sched = model.schedule(multirate=True)
    z = run.measurements(sched)
    res = run_multirate(model, z, method=method, schedule=sched, u=run.u)
    Phi, Q, H, V, B = model.Phi, model.Q, model.H, model.V, model.B
    # first prediction, by hand: x̄1 = Φ x0 + B u0, M1 = Φ M0 Φᵀ + Q
    np.testing.assert_allclose(res.x_bar[0], Phi @ model.x0 + B @ run.u[0], rtol=1e-12)
    np.testing.assert_allclose(res.M[0], Phi @ model.M0 @ Phi.T + Q, rtol=1e-12)
    for i, rows in ((4, IMU_ROWS), (9, list(range(9)))):  # k = 5 (no GPS), k = 10 (GPS)
        assert list(np.flatnonzero(sched.mask[i])) == rows
        xb, M = res.x_bar[i], res.M[i]
        Hr, Vr = H[rows], V[np.ix_(rows, rows)]
        Kr = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)
        x_hat = xb + Kr @ (z[i, rows] - Hr @ xb)
        P = (np.eye(9) - Kr @ Hr) @ M
        np.testing.assert_allclose(res.x_hat[i], x_hat, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(res.P[i], P, rtol=1e-8, atol=1e-14)
        np.testing.assert_allclose(res.K[i][:, rows], Kr, rtol=1e-8, atol=1e-14)
        missing = [c for c in range(9) if c not in rows]
        assert not res.K[i][:, missing].any()
    # ... and the hand gain on the reduced H is not the report's zeroed full gain
    i = 4
    K_full = res.M[i] @ np.linalg.inv(res.M[i] + V)
    assert np.abs(K_full[:, IMU_ROWS] - res.K[i][:, IMU_ROWS]).max() > 1e-6


@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_known_input_equals_filtering_the_deviation_from_the_plan(model, method):
    """Superposition: with u, x̂ = x_plan + δx̂, δx̂ from z − H x_plan with no input."""
    run = simulate_ship(model, np.random.default_rng(4))
    sched = model.schedule(multirate=True)
    z = run.measurements(sched)
    with_u = run_multirate(model, z, method=method, schedule=sched, u=run.u)
    plan = nominal_plan(model)[: model.n_samples]
    # x0 of the model is the plan's start, so the deviation filter starts from 0
    dev = run_multirate(_ZeroMean(model), z - plan[sched.steps], method=method, schedule=sched)
    np.testing.assert_allclose(with_u.x_hat, plan[sched.steps] + dev.x_hat, atol=1e-9)
    np.testing.assert_allclose(with_u.P, dev.P, rtol=1e-12, atol=1e-16)


class _ZeroMean:
    """The ship model with x0 = 0 and no input: the filter of deviations from the plan."""

    def __init__(self, model):
        self._m = model
        self.x0 = np.zeros(9)

    def __getattr__(self, name):
        return getattr(self._m, name)

    def kalman_filter(self):
        kf = self._m.kalman_filter()
        kf.x = np.zeros((9, 1))
        kf.B = None
        return kf

    B = None


def test_gain_sequence_reproduces_the_filters_run_by_run(model):
    ens = simulate_ensemble(model, 3, np.random.default_rng(5))
    sched = model.schedule(multirate=True)
    z = ens.measurements(sched)
    for run_filter in (lambda zz: run_multirate(model, zz, schedule=sched, u=ens.u),
                       lambda zz: run_zeroed_gain(model, zz, schedule=sched, u=ens.u,
                                                  covariance="report")):
        first = run_filter(z[0])
        est = apply_gains(model.Phi, model.H, model.x0, sched, first.K, z, B=model.B, u=ens.u)
        for r in range(3):
            np.testing.assert_allclose(est.x_hat[r], run_filter(z[r]).x_hat, atol=1e-9)


# --------------------------------------------------------------------------- zeroed gain
def test_zeroed_gain_applies_the_full_gain_with_gps_columns_zeroed(model):
    run = simulate_ship(model, np.random.default_rng(6))
    sched = model.schedule(multirate=True)
    res = run_zeroed_gain(model, run.measurements(sched), schedule=sched, u=run.u)
    for i in (4, 9):
        M = res.M[i]
        K_full = M @ np.linalg.inv(M + model.V)
        np.testing.assert_allclose(res.K_full[i], K_full, rtol=1e-9, atol=1e-14)
        expected = K_full.copy()
        expected[:, list(GPS_ROWS)] *= sched.mask[i, list(GPS_ROWS)]
        np.testing.assert_allclose(res.K[i], expected, rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(res.P[i], joseph(M, res.K[i], model.H, model.V), rtol=1e-12)
    np.testing.assert_array_equal(res.P, res.P_actual)


def test_zeroed_gain_joseph_covariance_is_never_below_the_optimal(comparison):
    """P_zeroed − P_opt ⪰ 0 at every epoch (the optimal gain minimises P in the Loewner order).

    Tolerance: 1e-12 of P_opt's largest eigenvalue (rounding); measured about −3e-18."""
    for name in ("zeroed-joseph", "zeroed-report", "report-as-written"):
        excess = comparison.covariance_excess(name)
        assert excess.min() > -1e-12, name
    # it is strictly worse somewhere (the test can fail if zeroing did nothing)
    P_z = comparison.filters["zeroed-joseph"].result.P
    P_o = comparison.filters["multirate"].result.P
    assert (P_z[:, 0, 0] - P_o[:, 0, 0]).max() > 1e-7


def _bonferroni_nees_ok(nees_bar, n_runs, dof, epochs, alpha=0.01):
    """Each ε̄ at the chosen epochs inside its two-sided (1 − alpha/len) chi-square bounds:
    family-wise false-alarm rate ≤ alpha whatever the correlation between epochs."""
    lo, hi = chi2_bounds(dof, n_runs, alpha / len(epochs))
    values = nees_bar[epochs]
    return bool(np.all((values >= lo) & (values <= hi))), values, (lo, hi)


EPOCHS = np.arange(49, 999, 100)  # k = 50, 150, ..., 950: ten epochs, 10 s apart


def test_optimal_multirate_filter_is_consistent(comparison):
    # fixed seed 0, 200 runs; family-wise false-alarm rate 1 % (Bonferroni over 10 epochs)
    for name in ("monorate", "multirate", "zeroed-joseph"):
        ok, values, bounds = _bonferroni_nees_ok(comparison.filters[name].nees, N_RUNS, 9, EPOCHS)
        assert ok, (name, values, bounds)
    # the report's filters judged against their true (Joseph) covariance: consistent too
    for name in ("zeroed-report", "report-as-written"):
        ok, values, bounds = _bonferroni_nees_ok(comparison.filters[name].nees_actual, N_RUNS, 9,
                                                 EPOCHS)
        assert ok, (name, values, bounds)


def test_nees_helper_is_the_consistency_modules(comparison):
    s = comparison.filters["multirate"]
    e = comparison.ensemble.x[:3, s.result.steps] - s.x_hat[:3]
    np.testing.assert_allclose(quadratic_form(e, s.result.P),
                               np.stack([nees(e[r], s.result.P) for r in range(3)]), rtol=1e-9)


def test_the_reports_own_covariance(comparison):
    """(I − K H) M with the zeroed gain: not symmetric, not the filter's covariance.

    With the report's numbers it is within 0.2 % of the true one, and its NEES passes (measured,
    asserted, so a change shows).  The report as written (monorate gain at GPS steps) claims up
    to 1.6-1.8 x its true position variances: expected NEES tr(P⁻¹ P_actual) < 9, and the Monte Carlo
    NEES falls outside the 95 % bounds at most epochs."""
    zr = comparison.filters["zeroed-report"].result
    asym = np.abs(zr.P - np.swapaxes(zr.P, 1, 2)).max()
    assert asym > 1e-6
    ratio = zr.P[:, 0, 0] / zr.P_actual[:, 0, 0]
    assert 0.99 < ratio.min() < 1.0 < ratio.max() < 1.01
    ok, values, bounds = _bonferroni_nees_ok(comparison.filters["zeroed-report"].nees, N_RUNS, 9,
                                             EPOCHS)
    assert ok, (values, bounds)

    ra = comparison.filters["report-as-written"]
    expected = np.einsum("kii->k", np.linalg.solve(ra.result.P, ra.result.P_actual))
    assert expected.mean() < 8.5  # measured 8.43 (min 8.24) against 9 for an honest covariance
    assert np.mean(expected < comparison.bounds[0]) > 0.5  # measured 56 % of epochs
    # the Monte Carlo NEES agrees with its expectation tr(P⁻¹ P_actual) (to 3 standard errors of
    # the time average, a loose check) and fails the 95 % bounds at most epochs
    assert abs(ra.nees.mean() - expected.mean()) < 3 * np.sqrt(2 * 9 / N_RUNS)
    assert comparison.inside("report-as-written") < 0.8
    assert comparison.inside("multirate") > 0.9


def test_rmse_table(comparison):
    """Monorate beats multirate in position; the report as written is worst (measured ~x2)."""
    rm = {n: s.rmse for n, s in comparison.filters.items()}
    assert rm["monorate"][0] < rm["multirate"][0] < rm["report-as-written"][0]
    assert rm["report-as-written"][0] > 1.5 * rm["multirate"][0]
    text = str(comparison)
    assert "zeroed gain, Joseph covariance" in text and "mean NEES" in text


# --------------------------------------------------------------------------- wind
def test_wind_states_estimate_the_wind_and_remove_the_track_bias():
    w = compare_wind(n_runs=50, seed=1, wind_force=(0.8, -0.5))
    plain, wind = w.track_rmse
    assert wind < 0.3 * plain
    assert np.all(np.abs(w.mean_error_plain) > 1.0)       # the unaware filter is off by metres
    assert np.all(np.abs(w.mean_error_wind) < 0.3)
    # the final wind estimate: run-average within 4 standard errors of the true mean wind
    err = w.wind_hat[:, -1] - w.wind[:, -1]
    se = w.wind_sigma[-1] / np.sqrt(err.shape[0])
    assert np.all(np.abs(err.mean(axis=0)) < 4 * se), (err.mean(axis=0), se)
    assert w.wind_sigma[-1].max() < 0.2


def test_wind_model_runs_under_both_forms():
    m = ShipModel(wind=True)
    assert m.Phi.shape == (11, 11) and m.H.shape == (9, 11)
    run = simulate_ship(m, np.random.default_rng(2))
    sched = m.schedule()
    a = run_multirate(m, run.measurements(sched), schedule=sched, u=run.u)
    b = run_multirate(m, run.measurements(sched), "information", schedule=sched, u=run.u)
    sd = np.sqrt(np.diagonal(a.P, axis1=1, axis2=2))
    assert np.max(np.abs(a.x_hat - b.x_hat) / sd) < 1e-6


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, match", [
    ({"gps_rate_hz": 3.0}, "gps_rate_hz"),
    ({"imu_rate_hz": 20.0}, "imu_rate_hz"),
    ({"V": np.diag([1.0] * 8 + [-1.0])}, "V must be positive definite"),
    ({"M0_ship": np.ones((9, 9))}, "M0_ship must be positive definite"),
    ({"W": np.eye(2)}, "W must be a 3 x 3"),
    ({"beta": (0.4, 0.1)}, "beta"),
    ({"dt": 0.0}, "dt"),
    ({"wind_drift": -1.0}, "wind_drift"),
])
def test_bad_model_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ShipModel(**kwargs)


def test_bad_run_input(model):
    run = simulate_ship(model, np.random.default_rng(0))
    sched = model.schedule()
    z = run.measurements(sched)
    with pytest.raises(ValueError, match="available"):
        model.schedule_from_mask(np.ones((999, 9), dtype=bool))
    with pytest.raises(ValueError, match="u must have shape"):
        run_multirate(model, z, schedule=sched, u=run.u[:-1])
    with pytest.raises(ValueError, match="B"):
        cal = CalibrationModel()
        run_multirate(cal, np.zeros((cal.n_gps, 2)), u=np.zeros((cal.n_steps, 1)))
    with pytest.raises(ValueError, match="covariance"):
        run_zeroed_gain(model, z, schedule=sched, u=run.u, covariance="short")
    with pytest.raises(ValueError, match="schedule must cover"):
        run.measurements(model.replace(n_samples=500).schedule())
    with pytest.raises(ValueError, match="wind_force"):
        simulate_ship(model, np.random.default_rng(0), wind_force=(1.0, 2.0, 3.0))
    res = run_multirate(model, z, schedule=sched, u=run.u)
    z_bad = z.copy()
    z_bad[4, 1] = np.nan  # an IMU row the gain uses
    with pytest.raises(ValueError, match="z is NaN where the gain"):
        apply_gains(model.Phi, model.H, model.x0, sched, res.K, z_bad[None], B=model.B, u=run.u)



# --------------------------------------------------------------------------- CLI and figures
def test_cli_ship_prints_the_tables(capsys):
    from gpsaccel.cli import main

    assert main(["ship", "--runs", "20", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    for text in ("monorate (all sensors every step)", "mean NEES", "exact cost",
                 "track RMSE, 11-state filter"):
        assert text in out
    assert main(["ship", "--runs", "1"]) == 2


def test_report_004_figures(tmp_path):
    from gpsaccel.figures import write_figures

    paths = write_figures(["004"], tmp_path, runs=10, seed=2, dpi=40)
    names = [p.name for p in paths]
    assert len(names) == 14
    assert names[10] == "r004-fig11-difference-acceleration.png"
    assert (tmp_path / "index.html").read_text(encoding="utf-8").count("<figure>") == 14


def test_acceleration_difference_panels_show_accelerations():
    from gpsaccel.figures.r004 import figures

    figs = {f.number: f for f in figures(5, 0)}
    labels = [ax.get_ylabel() for ax in figs["11"].figure.axes]
    assert labels == ["Δẍ (m/s²)", "Δÿ (m/s²)", "Δψ̈ (rad/s²)"]
