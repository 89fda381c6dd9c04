"""Numerical guards: the covariance form warns when it loses precision; the information form stays
exact for diffuse priors.  Against the 50-digit mpmath reference of gpsaccel.kalman.exact
(the calibration filter run at GPS rate with the same float64 inputs taken as exact numbers).

Data are always the report's model's (a realistic truth); only the filter's prior or noise
changes, as when a user sets a diffuse prior for a state they do not know.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from gpsaccel import CalibrationModel, NumericalWarning, monte_carlo, simulate
from gpsaccel.kalman.exact import errors, exact_filter
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.kalman.update import SYMMETRY_RTOL, covariance_defect

BASE = CalibrationModel()
Z = simulate(BASE, np.random.default_rng(1)).z

CASES = {
    "diffuse M0 = 1e12 I": {"M0": 1e12 * np.eye(3)},
    "tight M0 = 1e-12 I": {"M0": 1e-12 * np.eye(3)},
    "M0 = diag(1e-12, 1e-12, 1e12)": {"M0": np.diag([1e-12, 1e-12, 1e12])},
    "M0 = 1e12 I, V = 1e-12 I": {"M0": 1e12 * np.eye(3), "V": 1e-12 * np.eye(2)},
}


def run(model, method):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_multirate(model, Z, method=method)
    numerical = [w for w in caught if issubclass(w.category, NumericalWarning)]
    assert len(numerical) <= 1  # one warning per run, not one per epoch
    return res, (str(numerical[0].message) if numerical else None)


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    model = dataclasses.replace(BASE, **CASES[request.param])
    return request.param, model, exact_filter(model, Z)


def test_information_form_is_exact_for_diffuse_and_tight_priors(case):
    """Measured: 2.3e-12σ (1e12 I), 2.7e-12σ (1e-12 I), 2.5e-9σ and 5.9e-9σ for the harsh two
    (4.6e-4σ, 1.9e-13σ, 18σ and 3100σ when it formed M = ΦPΦᵀ + Q)."""
    name, model, exact = case
    res, warning = run(model, "information")
    err = errors(exact, res.x_hat, res.P)
    assert err.dx_sigma < 1e-8, (name, err)
    assert err.dP_rel < 1e-8, (name, err)
    assert warning is None, warning


def test_covariance_form_meets_1e_6_sigma_or_warns(case):
    """filterpy's Joseph form: 4.2e-3σ off at 1e12 I (P asymmetric to 3e-6), 91σ and 4.5e6σ (NaN
    σ at 24 epochs) for the harsh two; each of those warns, naming the epoch."""
    name, model, exact = case
    res, warning = run(model, "filterpy")
    err = errors(exact, res.x_hat, res.P)
    assert err.dx_sigma < 1e-6 or warning is not None, (name, err)
    if warning is not None:
        assert "epoch 1 (t = 0.2 s)" in warning and 'method="information"' in warning


def test_diffuse_prior_warning_reads_as_a_diagnosis():
    model = dataclasses.replace(BASE, M0=1e12 * np.eye(3))
    _, warning = run(model, "filterpy")
    assert warning.startswith("run_multirate(method='filterpy'): P at epoch 1 (t = 0.2 s) is not "
                              "symmetric")
    assert "150 of 151 epochs" in warning


def test_no_warning_on_the_reports_problem():
    with warnings.catch_warnings():
        warnings.simplefilter("error", NumericalWarning)
        for method in ("filterpy", "information"):
            run_multirate(BASE, Z, method=method)
        monte_carlo(BASE, 10, progress=False)


def test_monte_carlo_warns_for_a_diffuse_prior():
    model = dataclasses.replace(BASE, M0=1e12 * np.eye(3))
    with pytest.warns(NumericalWarning, match=r"monte_carlo: P at epoch 1 .* not symmetric"):
        monte_carlo(model, 10, progress=False)


def test_check_false_is_silent():
    model = dataclasses.replace(BASE, M0=1e12 * np.eye(3), V=1e-12 * np.eye(2))
    with warnings.catch_warnings():
        warnings.simplefilter("error", NumericalWarning)
        run_multirate(model, Z, check=False)


@pytest.mark.parametrize("A, expected", [
    (np.diag([1.0, 2.0]), None),
    (np.array([[1.0, np.nan], [np.nan, 1.0]]), "NaN or infinite"),
    (np.diag([1.0, -1e-3]), "variance ≤ 0"),
    (np.array([[1.0, 0.5], [0.5 + 1e-9, 1.0]]), "not symmetric"),
    (np.array([[1.0, 0.5], [0.5 + SYMMETRY_RTOL / 10, 1.0]]), None),
    (np.array([[1.0, 2.0], [2.0, 1.0]]), "not positive definite (smallest eigenvalue -1"),
])
def test_covariance_defect(A, expected):
    got = covariance_defect(A)
    assert got is None if expected is None else expected in got
