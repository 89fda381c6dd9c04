"""The one factory: every form and every model's ``kalman_filter()`` built from the same matrices."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from gpsaccel import CalibrationModel, ShipModel, simulate
from gpsaccel.kalman.epochs import LinearModel
from gpsaccel.kalman.factory import FORMS, Matrices, kalman_filter, make_form
from gpsaccel.kalman.forms import StandardKalmanFilter
from gpsaccel.kalman.information import InformationFilter
from gpsaccel.kalman.multirate import run_form, run_multirate

LINEAR = LinearModel(Phi=[[1.0, 0.1], [0.0, 1.0]], Gamma=[[0.005], [0.1]], W=[[0.09]],
                     H=[[1.0, 0.0]], V=[[0.25]], M0=np.diag([4.0, 1.0]), x0=[1.0, -0.5],
                     every=5, n_epochs=12, dt=0.1)


@pytest.mark.parametrize("model", [CalibrationModel(), ShipModel(n_samples=20), LINEAR],
                         ids=["calibration", "ship", "linear"])
def test_each_models_kalman_filter_is_filterpys_with_the_models_matrices(model):
    kf = model.kalman_filter()
    assert type(kf) is KalmanFilter
    for mine, theirs in (("Phi", "F"), ("Q", "Q"), ("H", "H"), ("V", "R"), ("M0", "P")):
        assert np.array_equal(getattr(kf, theirs), getattr(model, mine)), theirs
    assert np.array_equal(kf.x, np.asarray(model.x0).reshape(-1, 1))
    B = getattr(model, "B", None)
    assert kf.dim_u == (0 if B is None else 3)
    assert (kf.B is None) if B is None else np.array_equal(kf.B, B)


@pytest.mark.parametrize("name", list(FORMS))
def test_a_filter_never_writes_into_the_model_it_came_from(name):
    """filterpy updates x and P in place; each form gets its own copies (LinearModel's matrices
    are read-only and would raise, a CalibrationModel's would silently change)."""
    model = CalibrationModel()
    before = {k: np.array(getattr(model, k)) for k in ("Phi", "Q", "H", "V", "M0", "x0")}
    kf = make_form(name, model)
    for _ in range(40):
        kf.predict()
    kf.update(np.array([[3.0], [0.2]]), R=model.V, H=model.H)
    kf.x[...] = 7.0
    for k, value in before.items():
        assert np.array_equal(getattr(model, k), value), k
    assert np.array_equal(make_form(name, LINEAR).x[:, 0], LINEAR.x0)


def test_the_drivers_methods_are_forms_of_the_factory():
    model = CalibrationModel()
    z = simulate(model, np.random.default_rng(5)).z
    for method, form in (("filterpy", "joseph"), ("information", "information")):
        a, b = run_multirate(model, z, method=method), run_form(form, model, z)
        assert np.array_equal(a.x_hat, b.x_hat) and np.array_equal(a.P, b.P), method
    assert isinstance(make_form("standard", model), StandardKalmanFilter)
    assert isinstance(make_form("information", model), InformationFilter)


def test_a_known_input_reaches_the_filters_that_take_one():
    ship = ShipModel(n_samples=20)
    assert np.array_equal(make_form("information", ship).B, ship.B)
    assert np.array_equal(kalman_filter(ship).B, ship.B)
    assert Matrices.of(CalibrationModel()).B is None


def test_what_the_factory_cannot_build_is_named():
    with pytest.raises(ValueError, match="without Phi, Q"):
        make_form("joseph", object())
    with pytest.raises(ValueError, match="square-root form needs the model's Gamma and W"):
        make_form("square-root", ShipModel(n_samples=20, wind=True))  # its W is the forces' only
    with pytest.raises(ValueError, match="form must be one of"):
        make_form("ud", CalibrationModel())
