"""Argument checks shared by the whole package (gpsaccel._validation): each names the argument."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import _validation as _v


@pytest.mark.parametrize("value", [0.05, 1e-12, 0.999])
def test_probability_accepts_open_unit_interval(value):
    assert _v.probability("alpha", value) == value


@pytest.mark.parametrize("value", [0, 1, -0.1, 1.5, float("nan"), float("inf"), "0.1", True])
def test_probability_refuses_the_rest_and_names_the_argument(value):
    with pytest.raises(ValueError, match="^alpha must be"):
        _v.probability("alpha", value)


def test_integer_refuses_floats_bools_and_small_values():
    assert _v.integer("n", np.int64(3), minimum=1) == 3
    for bad in (40.0, True, "3", None):
        with pytest.raises(ValueError, match="n must be an integer"):
            _v.integer("n", bad)
    with pytest.raises(ValueError, match="n must be an integer >= 1, got 0"):
        _v.integer("n", 0, minimum=1)


def test_positive_and_finite_floats():
    assert _v.positive_float("dt", 0.005) == 0.005
    for bad in (0.0, -1.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="dt must be a finite number > 0"):
            _v.positive_float("dt", bad)
    with pytest.raises(ValueError, match="x must be finite"):
        _v.finite_float("x", np.inf)


def test_choice_lists_the_options():
    assert _v.choice("truth", "kinematic", ("error-model", "kinematic")) == "kinematic"
    with pytest.raises(ValueError, match="truth must be one of 'a', 'b'; got 'c'"):
        _v.choice("truth", "c", ("a", "b"))


def test_whole_multiple_refuses_rates_that_do_not_divide():
    assert _v.whole_multiple("gps", 0.2, 0.005, "dt") == 40
    with pytest.raises(ValueError, match="gps = 0.2025 must be a whole multiple of dt = 0.005"):
        _v.whole_multiple("gps", 0.2025, 0.005, "dt")


def test_finite_array_shape_nan_and_inf():
    z = _v.finite_array("z", [[1.0, np.nan]], (None, 2), allow_nan=True)
    assert z.shape == (1, 2)
    with pytest.raises(ValueError, match=r"z must have shape \(n x 3\), got \(1, 2\)"):
        _v.finite_array("z", [[1.0, 2.0]], (None, 3))
    with pytest.raises(ValueError, match="z contains NaN"):
        _v.finite_array("z", [np.nan])
    with pytest.raises(ValueError, match="z contains an infinite value"):
        _v.finite_array("z", [np.inf], allow_nan=True)
    with pytest.raises(ValueError, match="z must be an array of numbers"):
        _v.finite_array("z", [[1.0], [1.0, 2.0]])


def test_spd_matrix_checks_shape_symmetry_and_definiteness():
    np.testing.assert_array_equal(_v.spd_matrix("W", 0.0004, 1), [[0.0004]])
    with pytest.raises(ValueError, match="V must be a 2 x 2 matrix"):
        _v.spd_matrix("V", np.eye(3), 2)
    with pytest.raises(ValueError, match="M0 must be symmetric"):
        _v.spd_matrix("M0", [[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(ValueError, match="M0 must be positive definite"):
        _v.spd_matrix("M0", [[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(ValueError, match="M0 contains NaN or inf"):
        _v.spd_matrix("M0", [[np.nan]])


def test_a_field_table_normalises_in_order_and_names_the_field():
    from dataclasses import dataclass

    @dataclass(frozen=True)
    class Model:
        dt: object = 1
        V: object = 2.0
        omega: object = None
        on: object = True
        drift: object = 0

    table = {"dt": _v.positive_float, "V": _v.spd(1), "omega": _v.optional(_v.positive_float),
             "on": _v.flag, "drift": _v.variance("N²")}
    m = Model()
    _v.fields(m, table)
    assert m.dt == 1.0 and type(m.dt) is float and m.omega is None and m.drift == 0.0
    np.testing.assert_array_equal(m.V, [[2.0]])
    for kwargs, match in (({"dt": 0}, "dt must be a finite number > 0"),
                          ({"omega": -1.0}, "omega must be a finite number > 0"),
                          ({"on": 1}, "on must be True or False, got 1"),
                          ({"drift": -1.0}, r"drift must be a variance >= 0 \(N²\)"),
                          ({"dt": 0, "V": -1.0}, "^dt")):  # the table's order
        with pytest.raises(ValueError, match=match):
            _v.fields(Model(**kwargs), table)
    with pytest.raises(ValueError, match=r"x0 must have shape \(3\)"):
        _v.array(3)("x0", [1.0, 2.0])
    with pytest.raises(ValueError, match="n must be an integer >= 2, got 1"):
        _v.count(2)("n", 1)
