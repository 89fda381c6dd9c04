"""The filter forms: each one against the exact answer, and what filterpy needs to run them."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import SquareRootKalmanFilter

from gpsaccel import CalibrationModel, simulate
from gpsaccel.kalman.exact import errors, exact_filter
from gpsaccel.kalman.factory import FORMS, make_form
from gpsaccel.kalman.multirate import run_form

#: Every form at the report's numbers is within this of the exact answer (in σ, and in
#: √(P_ii P_jj)); measured: 4e-12 in x̂, 2e-13 in P (seed 0, with gaps).
TOLERANCE = 1e-10


@pytest.fixture(scope="module")
def problem():
    model = CalibrationModel()
    z = simulate(model, np.random.default_rng(0)).z
    z[50:60, 1] = np.nan  # velocity missing for 2 s
    z[70:75] = np.nan     # an outage
    z[80, 0] = np.nan
    return model, z, exact_filter(model, z)


@pytest.mark.parametrize("name", list(FORMS))
def test_every_form_is_the_exact_filter_at_the_reports_numbers(problem, name):
    model, z, ex = problem
    res = run_form(name, model, z)
    e = errors(ex, res.x_hat, res.P)
    assert e.dx_sigma < TOLERANCE and e.dP_rel < TOLERANCE
    assert e.asymmetry < TOLERANCE and e.min_eig > 0
    assert res.method == name


def test_standard_differs_from_joseph_only_in_the_covariance_line():
    """Same gain and estimate to the last bit after one update; P agrees to rounding."""
    model = CalibrationModel()
    a, b = make_form("standard", model), make_form("joseph", model)
    for _ in range(40):  # M no longer diagonal
        a.predict()
        b.predict()
    M = a.P.copy()
    z = np.array([[3.0], [0.2]])
    a.update(z)
    b.update(z)
    assert np.array_equal(a.K, b.K) and np.array_equal(a.x, b.x)
    assert np.array_equal(a.P, (np.eye(3) - a.K @ a.H) @ M)
    assert np.allclose(a.P, b.P, rtol=1e-13, atol=1e-16)


def test_filterpy_square_root_cannot_take_this_q_through_its_setter():
    """Why the adapter sets the factor Γ√W itself: Q = ΓWΓᵀ has rank 1, no Cholesky factor."""
    model = CalibrationModel()
    kf = SquareRootKalmanFilter(dim_x=3, dim_z=2)
    with pytest.raises(np.linalg.LinAlgError):
        kf.Q = model.Q
    sr = make_form("square-root", model)
    assert np.allclose(sr.filter.Q, model.Q, rtol=1e-15, atol=0)


def test_unknown_form_is_named():
    with pytest.raises(ValueError, match="form"):
        make_form("ud", CalibrationModel())


def test_square_root_prediction_is_filterpys_to_the_bit():
    """The adapter's predict (scipy's one LAPACK call, dgeqrf) against filterpy's own (scipy's full
    QR), step by step, from a badly conditioned P^½ (the prior sweep's last point) and from the
    report's; a P^½ that is no longer finite is refused as scipy's qr refuses it."""
    model = CalibrationModel()
    for M0 in (model.M0, model.M0 * 1e12):
        ours = make_form("square-root", model.replace(M0=M0))
        theirs = make_form("square-root", model.replace(M0=M0)).filter
        for k in range(200):
            ours.predict()
            SquareRootKalmanFilter.predict(theirs)
            if k % 40 == 39:
                z = np.array([[1.0], [0.1]])
                ours.update(z)
                theirs.update(z)
        assert ours.filter._P1_2.tobytes() == theirs._P1_2.tobytes()
        assert ours.x.tobytes() == theirs.x.tobytes()
        assert ours.filter._P1_2_prior.tobytes() == theirs._P1_2_prior.tobytes()
    ours.filter._P1_2 = np.full((3, 3), np.nan)
    with pytest.raises(ValueError, match="infs or NaNs"):
        ours.predict()
