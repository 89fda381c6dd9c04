"""compare() and sweep(): every form against the exact answer, and which forms lose precision first."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import CalibrationModel, run_multirate
from gpsaccel.calibration.compare import (
    compare,
    form_filter,
    reference_filter,
    sweep,
    sweep_model,
    sweeps,
)
from gpsaccel.kalman.factory import FORMS

#: Every built-in form at the report's numbers is within this of the exact answer, in σ (x̂) and in
#: √(P_ii P_jj) (P).  Measured (seed 0 and 3): ≤ 4e-12 in x̂, ≤ 2.2e-13 in P.
TOLERANCE = 1e-10


@pytest.fixture(scope="module")
def table():
    return compare(seed=3, repeat=1)


def test_every_form_matches_the_exact_answer_at_the_reports_numbers(table):
    assert [r.name for r in table.rows] == list(FORMS)
    for r in table.rows:
        assert r.problem is None
        e = r.errors
        assert e.dx_sigma < TOLERANCE and e.dP_rel < TOLERANCE and e.asymmetry < TOLERANCE, r.name
        assert e.min_eig == pytest.approx(table.exact_min_eig, rel=1e-9)
        assert r.seconds > 0
    # the floor: the exact answer stored in float64 (half an ulp of x̂ in σ, of P in √(PiiPjj))
    assert table.floor.dx_sigma < 1e-13 and table.floor.dP_rel < 2e-16
    assert table.kappa == pytest.approx(626.0, rel=1e-12)  # 1 + M0_vv / V_vv at t = 0
    text = str(table)
    assert "exact (mpmath)" in text and "square-root" in text and "min eig" in text


def test_report_000_as_any_linear_model_gives_the_same_table(table):
    """The comparison is the core's (kalman.compare), for any LinearModel: report 000 written as
    one (Φ, Γ, W, H, V, M0, x0, a fix every 40 steps) gives the same errors, to the last bit."""
    from gpsaccel.calibration.simulation import simulate
    from gpsaccel.kalman import compare as core
    from gpsaccel.kalman.linear_model import LinearModel

    m = CalibrationModel()
    linear = LinearModel(m.Phi, m.Gamma, m.W, m.H, m.V, m.M0, m.x0, m.gps_every, m.n_gps, m.dt)
    z = simulate(m, np.random.default_rng(3), "error-model").z
    other = core.compare(linear, z=z, seed=3, repeat=1)
    assert [r.errors for r in other.rows] == [r.errors for r in table.rows]
    assert other.floor == table.floor and other.kappa == table.kappa


def test_kinematic_truth_too():
    t = compare("joseph", "information", seed=1, truth="kinematic", repeat=1)
    assert all(r.errors.dx_sigma < TOLERANCE and r.errors.dP_rel < TOLERANCE for r in t.rows)


def test_a_mistaken_filter_shows_up_and_a_correct_one_does_not():
    wrong = CalibrationModel(W=0.0004**0.5)  # a standard deviation where a variance belongs

    def student(z):
        res = run_multirate(wrong, z)
        return res.x_hat, res.P

    t = compare("joseph", filters={"student": student,
                                   "same": reference_filter(CalibrationModel()),
                                   "joseph again": form_filter("joseph", CalibrationModel())},
                repeat=1)
    assert t.row("student").errors.dP_rel > 0.1 and t.row("student").errors.dx_sigma > 0.1
    assert t.row("same").errors == t.row("joseph").errors == t.row("joseph again").errors


def test_form_filter_is_run_form_to_the_bit():
    """A comparison runs each form at the epochs only (no fast grid, no guard): the same x̂ and P as
    the multirate driver's, for every form, at the report's numbers and with the prior sweep's last
    point, with an outage and a lost component (the information form's P is formed when read)."""
    import warnings

    from gpsaccel.calibration.simulation import simulate
    from gpsaccel.kalman.multirate import run_form

    for model, data in (sweep_model("prior", 1.0), sweep_model("prior", 1e12)):
        model, data = model.replace(duration=8.0), data.replace(duration=8.0)  # 41 fixes
        z = simulate(data, np.random.default_rng(0), "error-model").z
        z[10:13, 1] = np.nan
        z[20] = np.nan
        for name in FORMS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = run_form(name, model, z)
            x_hat, P = form_filter(name, model)(z)
            assert x_hat.tobytes() == res.x_hat.tobytes() and P.tobytes() == res.P.tobytes(), name


def test_a_filter_that_breaks_down_is_a_row_not_an_exception():
    def raises(z):
        raise np.linalg.LinAlgError("Singular matrix")

    def nan(z):
        return np.full((z.shape[0], 3), np.nan), np.full((z.shape[0], 3, 3), np.nan)

    t = compare(filters={"raises": raises, "nan": nan}, repeat=1)
    assert t.row("raises").errors is None and "LinAlgError: Singular matrix" in t.row("raises").problem
    assert t.row("nan").errors.dx_sigma == np.inf and t.row("nan").errors.min_eig == -np.inf
    assert "failed: LinAlgError" in str(t)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match=r"filters\['x'\] must be callable"):
        compare(filters={"x": 3}, repeat=1)
    with pytest.raises(ValueError, match=r"short: x_hat must have shape \(151, 3\)"):
        compare(filters={"short": lambda z: (np.zeros((3, 3)), np.zeros((151, 3, 3)))}, repeat=1)
    with pytest.raises(ValueError, match="return"):
        compare(filters={"one": lambda z: np.zeros((151, 3))}, repeat=1)
    with pytest.raises(ValueError, match="forms must be one of"):
        compare("ud")
    with pytest.raises(ValueError, match="own name"):
        compare("joseph", filters={"joseph": form_filter("joseph", CalibrationModel())})
    with pytest.raises(ValueError, match="truth"):
        compare(truth="euler")
    with pytest.raises(ValueError, match="kind"):
        sweep("noise")
    with pytest.raises(ValueError, match="factor"):
        sweep_model("gps", -1.0)


# ------------------------------------------------------------------------------------ the sweeps
@pytest.fixture(scope="module")
def prior():
    return sweep("prior", factors=[1.0, 1e6, 1e12])


@pytest.fixture(scope="module")
def gps():
    return sweep("gps", factors=[1.0, 1e-6, 1e-12])


def test_sweep_condition_number_is_the_closed_form(prior, gps):
    """κ = 1 + M0_vv f / V_vv (prior) or 1 + M0_vv / (V_vv f) (gps), from the first update."""
    assert np.allclose(prior.kappa, 1 + 625 * prior.factors, rtol=1e-12)
    assert np.allclose(gps.kappa, 1 + 625 / gps.factors, rtol=1e-12)


def test_prior_sweep_standard_form_fails_first_square_root_holds(prior):
    """Measured (seed 0), max|ΔP|/√(PiiPjj) at M0 × 10⁶ and × 10¹²:
    standard 1.5e-8, 46 (P not positive definite); joseph 3.9e-11, 4.2e-5; filterpy-information
    5.8e-11, 5.6e-5; square-root 2.8e-11, 1.1e-8; the hand-written information form, which
    carries M⁻¹ instead of forming M (kalman.information), 3e-14 at 1e12."""
    dP = {f: prior.dP(f) for f in FORMS}
    # at the report's numbers every form is exact to 1e-12
    assert all(dP[f][0] < 1e-12 for f in FORMS)
    # at 1e6 the standard form has lost 100x more than any other form
    assert 1e-10 < dP["standard"][1] < 1e-6
    assert all(dP["standard"][1] > 100 * dP[f][1] for f in FORMS if f != "standard")
    # at 1e12 it has no digit left and P is not a covariance any more
    assert dP["standard"][2] > 1 and prior.min_eig("standard")[2] < 0
    assert prior.dx("standard")[2] > 0.1
    for f in ("joseph", "filterpy-information"):
        assert 1e-6 < dP[f][2] < 1e-3, f
        assert prior.min_eig(f)[2] > 0
    assert dP["information"][2] < 1e-12 and prior.dx("information")[2] < 1e-10
    assert 1e-10 < dP["square-root"][2] < 1e-7
    assert all(dP["square-root"][2] < dP[f][2] / 100 for f in FORMS
               if f not in ("square-root", "information"))


def test_gps_sweep_joseph_and_information_hold_square_root_drifts(gps):
    """Measured (seed 0), max|ΔP|/√(PiiPjj) at V × 10⁻⁶ and × 10⁻¹²:
    standard 5.4e-8, 6.0e-2; joseph 5.8e-13, 5.5e-13; information 3.3e-11 at 1e-12;
    filterpy-information 7.5e-14, 1.9e-11; square-root 1.3e-11, 1.2e-8."""
    dP = {f: gps.dP(f) for f in FORMS}
    assert 1e-9 < dP["standard"][1] < 1e-6 and 1e-4 < dP["standard"][2] < 1
    assert all(dP["standard"][i] > 100 * dP[f][i] for i in (1, 2) for f in FORMS
               if f != "standard")
    assert dP["joseph"][2] < 1e-11
    # the information form carries M⁻¹ (exact for diffuse priors); with V × 1e-12 that holds 1e12
    # next to O(1) and its prediction's Woodbury subtraction rounds to ~3e-11 (5.6e-13 when it
    # formed M)
    assert dP["information"][2] < 1e-10
    assert dP["filterpy-information"][2] < 1e-9
    assert 1e-10 < dP["square-root"][2] < 1e-6
    assert dP["square-root"][2] > 1000 * dP["joseph"][2]
    assert all(gps.min_eig(f)[2] > 0 for f in FORMS)
    text = str(gps)
    assert "max |dP_ij|" in text and "1e-12" in text


def test_sweep_figure_has_a_column_per_sweep(prior, gps):
    from gpsaccel import plots

    fig = plots.form_sweep([prior, gps])
    axes = [ax for ax in fig.axes if ax.get_ylabel()]
    assert len(axes) == 4
    assert all(ax.get_yscale() == "log" for ax in axes)
    lo, hi = axes[0].get_ylim()
    assert hi > prior.dP("standard").max() and lo < min(e.dP_rel for e in prior.floor)


def _points(sw, idx):
    """The sweep ``sw`` at its points ``idx`` only (what a sweep of those factors alone gives)."""
    import dataclasses

    return dataclasses.replace(
        sw, factors=sw.factors[idx], kappa=sw.kappa[idx], cond_P=sw.cond_P[idx],
        floor=tuple(sw.floor[i] for i in idx),
        errors={f: tuple(e[i] for i in idx) for f, e in sw.errors.items()},
        problems={f: tuple(p[i] for i in idx) for f, p in sw.problems.items()})


def test_sweep_on_a_process_pool_is_bit_identical(gps):
    """Each point is computed whole by one worker: the numbers do not depend on where it ran (one
    point, the GPS sweep's middle one, in a worker process against the same point in this one)."""
    from gpsaccel.executors import resolve_executor

    alone = _points(gps, [1])
    with resolve_executor("processes", max_workers=1) as pool:
        pooled = sweep("gps", factors=[1e-6], executor=pool)
    np.testing.assert_array_equal(pooled.kappa, alone.kappa)
    np.testing.assert_array_equal(pooled.cond_P, alone.cond_P)
    assert pooled.floor == alone.floor
    assert pooled.errors == alone.errors and pooled.problems == alone.problems
    assert str(pooled) == str(alone)


def test_sweep_refuses_a_bad_executor_or_factor_before_running():
    with pytest.raises(ValueError, match="executor"):
        sweep("gps", factors=[1.0], executor="no-such-pool")
    with pytest.raises(ValueError, match="factor"):
        sweep("gps", factors=[1.0, -1.0], executor="processes")


def test_sweeps_are_each_sweep_and_compute_factor_1_once(prior, gps):
    """Both sweeps at once equal each alone, bit for bit; the report's own problem (factor 1 in
    both) is computed once: three distinct points are submitted for four (each sweep's first and
    last point, against the same points of the sweeps run alone)."""
    from gpsaccel.executors import InProcessExecutor

    class Counting(InProcessExecutor):
        calls: list = []

        def submit(self, fn, /, *args, **kwargs):
            self.calls.append(args[:2])
            return super().submit(fn, *args, **kwargs)

    both = sweeps(("prior", "gps"), factors={"prior": [1.0, 1e12], "gps": [1.0, 1e-12]},
                  executor=Counting())
    assert Counting.calls == [("prior", 1.0), ("prior", 1e12), ("gps", 1e-12)]
    for alone, together in zip((_points(prior, [0, 2]), _points(gps, [0, 2])), both, strict=True):
        assert together.kind == alone.kind
        np.testing.assert_array_equal(together.factors, alone.factors)
        np.testing.assert_array_equal(together.kappa, alone.kappa)
        assert together.floor == alone.floor and together.errors == alone.errors
        assert together.problems == alone.problems
        assert str(together) == str(alone)


def test_compare_with_a_precomputed_exact_answer_is_the_same_table(table):
    from gpsaccel import simulate
    from gpsaccel.kalman.exact import exact_filter

    model = CalibrationModel()
    exact = exact_filter(model, simulate(model, np.random.default_rng(3)).z)
    again = compare(seed=3, repeat=1, exact=exact)
    assert [(r.name, r.errors) for r in again.rows] == [(r.name, r.errors) for r in table.rows]
    assert (again.floor, again.kappa) == (table.floor, table.kappa)
    with pytest.raises(ValueError, match="digits"):
        compare(seed=3, repeat=1, exact=exact, digits=30)
