"""Simulated voyages of report 004's ship (ship.simulation): one type for one and many."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.kalman.consistency import z_sample_mean, z_threshold
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.plan import driving_input, nominal_plan
from gpsaccel.ship.simulation import ShipEnsemble, simulate_ensemble, simulate_ship

MODEL = ShipModel(n_samples=200)


def test_one_voyage_is_an_ensemble_of_one_without_the_run_axis():
    ens = simulate_ensemble(MODEL, 1, np.random.default_rng(4))
    one = simulate_ship(MODEL, np.random.default_rng(4))
    assert isinstance(one, ShipEnsemble) and one.n_runs is None and ens.n_runs == 1
    np.testing.assert_array_equal(one.x, ens.realization(0).x)
    np.testing.assert_array_equal(one.z, ens.z[0])
    ens = simulate_ensemble(MODEL, 3, np.random.default_rng(4))
    with pytest.raises(ValueError, match="needs an ensemble"):
        one.realization(0)
    with pytest.raises(ValueError, match="i must be < n_runs = 3"):
        ens.realization(3)


def test_truth_follows_the_model_and_sensors_add_their_noise():
    ens = simulate_ensemble(MODEL, 400, np.random.default_rng(5))
    u = driving_input(MODEL)
    k = 50
    np.testing.assert_array_equal(ens.u, u)
    # the mean state follows the noise-free plan; z − x is N(0, V); nothing measured at k = 0
    alpha = 0.01 / 18  # family-wise 1 % over the 2 x 9 tests
    mean_err = ens.x[:, k].mean(axis=0) - nominal_plan(MODEL)[k]
    var = ens.x[:, k].var(axis=0, ddof=1)
    assert np.all(np.abs(z_sample_mean(mean_err, var, 400)) < z_threshold(alpha, 1))
    noise = ens.z[:, k] - ens.x[:, k, :9]
    z_noise = z_sample_mean(noise.mean(axis=0), np.diag(MODEL.V), 400)
    assert np.all(np.abs(z_noise) < z_threshold(alpha, 1))
    assert np.isnan(ens.z[:, 0]).all()
    assert not ens.wind.any()  # a 9-state truth has no wind unless one is given


def test_measurements_keep_only_what_the_schedule_delivers():
    ens = simulate_ensemble(MODEL, 2, np.random.default_rng(6))
    sched = MODEL.schedule(multirate=True)
    z = ens.measurements(sched)
    assert z.shape == (2, sched.n_epochs, 9)
    np.testing.assert_array_equal(np.isfinite(z[0]), sched.mask)
    np.testing.assert_array_equal(z[1][sched.mask], ens.z[1, sched.steps][sched.mask])


def test_a_given_wind_is_the_truths_and_bad_arguments_name_themselves():
    ens = simulate_ensemble(MODEL.replace(wind=True, wind_drift=0.0), 2, np.random.default_rng(7),
                            wind_force=(0.8, -0.5))
    np.testing.assert_array_equal(ens.wind[:, -1], [[0.8, -0.5], [0.8, -0.5]])
    with pytest.raises(ValueError, match="model must be a ShipModel"):
        simulate_ensemble(object(), 1, np.random.default_rng(0))
    with pytest.raises(ValueError, match="rng must be a numpy.random.Generator"):
        simulate_ensemble(MODEL, 1, 0)
    with pytest.raises(ValueError, match="n_runs must be an integer >= 1"):
        simulate_ensemble(MODEL, 0, np.random.default_rng(0))
