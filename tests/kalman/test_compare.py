"""kalman.compare: the forms side by side against the exact (mpmath) answer, for any linear model.

The model here is not report 000's: a 3-state constant-acceleration target with position and
velocity measured every 4 steps and an outage (NaN) in the data.  The exact answer at the epochs
equals the epoch recursion of :mod:`gpsaccel.kalman.epochs` (a different float64 computation) to
rounding; every built-in form is within rounding of it; a wrong filter is not.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.kalman.compare import compare
from gpsaccel.kalman.exact import errors, exact_filter
from gpsaccel.kalman.factory import FORMS
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_model import LinearModel

DT = 0.05
MODEL = LinearModel(Phi=[[1, DT, DT**2 / 2], [0, 1, DT], [0, 0, 1]],
                    Gamma=[[DT**3 / 6], [DT**2 / 2], [DT]], W=[[4.0]],
                    H=[[1, 0, 0], [0, 1, 0]], V=np.diag([0.25, 0.04]),
                    M0=np.diag([9.0, 1.0, 0.25]), x0=[0.0, 2.0, 0.0],
                    every=4, n_epochs=30, dt=DT, states=("p", "v", "a"),
                    measurements=("p", "v"))


@pytest.fixture(scope="module")
def table():
    return compare(MODEL, seed=4, repeat=1)


def test_every_form_is_within_rounding_of_the_exact_answer(table):
    assert [r.name for r in table.rows] == list(FORMS)
    for row in table.rows:
        assert row.problem is None, row
        assert row.errors.dx_sigma < 1e-10 and row.errors.dP_rel < 1e-11, row
    assert table.floor.dx_sigma < 1e-14 and table.kappa > 1
    assert "seed 4" in str(table) and "square-root" in str(table)


def test_the_exact_answer_is_the_epoch_recursion():
    z = MODEL.simulate(np.random.default_rng(4), 1)[0][0]
    z[7:10] = np.nan                    # an outage: those epochs only propagate
    z[12, 1] = np.nan                   # and one velocity missing
    exact = exact_filter(MODEL, z)
    assert np.array_equal(exact.P[7], exact.M[7]) and not np.array_equal(exact.P[6], exact.M[6])
    full = MODEL.simulate(np.random.default_rng(4), 1)[0]
    x, P = LinearCatalogue(MODEL).build().apply(full)          # the float64 epoch recursion
    e = errors(exact_filter(MODEL, full[0]), x[0], P)
    assert e.dx_sigma < 1e-11 and e.dP_rel < 1e-12


def test_a_wrong_filter_is_far_from_the_exact_answer():
    cat = LinearCatalogue(MODEL)
    wrong = next(m for m in cat.covariance_mistakes() if m.code == "phi-transposed")

    def kalman_filter(z):
        x, P = cat.build((wrong,)).apply(z[None])
        return x[0], P

    row = compare(MODEL, "joseph", filters={"phi-transposed": kalman_filter}, seed=4,
                  repeat=1).row("phi-transposed")
    assert row.errors.dP_rel > 1e-3


def test_measurements_are_needed_where_the_model_cannot_draw_them():
    class NoSimulate:
        pass

    with pytest.raises(ValueError, match="z must be given"):
        compare(NoSimulate(), "joseph", repeat=1)


def test_no_form_changes_the_model_it_is_built_from():
    """filterpy's square-root filter updated x in place, and its x was a view of the model's x0:
    a comparison moved the registered tracker's x0 to 2.42, and every later check of that problem
    in the process graded a correct filter wrong (0.18 σ at t = 0).  The model now holds its own
    read-only copies, and the forms copy what they are given."""
    model = LinearModel(Phi=MODEL.Phi, Gamma=MODEL.Gamma, W=MODEL.W, H=MODEL.H, V=MODEL.V,
                        M0=MODEL.M0, x0=np.array([0.5, 2.0, 0.0]), every=4, n_epochs=30, dt=DT)
    before = {k: np.array(getattr(model, k)) for k in ("Phi", "Gamma", "W", "H", "V", "M0", "x0")}
    compare(model, *FORMS, seed=3, repeat=1)
    for k, v in before.items():
        np.testing.assert_array_equal(getattr(model, k), v, err_msg=k)
        assert not getattr(model, k).flags.writeable, k
