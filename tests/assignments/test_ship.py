"""The ship homework: graded in the sandbox (solved, blank, one mistake per question, a classmate's
number copied); the update and cost checks on their own."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.assignments import ship
from gpsaccel.assignments.grading import student_variant
from gpsaccel.classrun import grade
from gpsaccel.kalman.update import joseph_update
from gpsaccel.ship.model import ShipModel

from .conftest import write_variant

UPDATE = """    K = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)"""
ZEROED_K = """    K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
    K = K[:, rows]"""
ACTUAL = "sigma_zeroed = float(np.sqrt(zeroed.P_actual[-1][0, 0]))"
SIGMAS = "sigma_optimal = float(np.sqrt(optimal.P[-1][0, 0]))\n" + ACTUAL
VOYAGE = """voyage = simulate_ship(ship, np.random.default_rng(0))
schedule = ship.schedule()
z = voyage.measurements(schedule)
optimal = gpsaccel.run_multirate(ship, z, schedule=schedule, u=voyage.u)
zeroed = run_zeroed_gain(ship, z, schedule=schedule, covariance="report", u=voyage.u)"""
SECRET = b"ship-test-secret-0123456789"


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    sub = tmp_path_factory.mktemp("class")
    write_variant("ship", sub / "solved" / "ship.ipynb")
    # a voyage in the box costs half a notebook's CPU: only the notebook whose answers come
    # from it runs it (solved); the others type in their numbers
    write_variant("ship", sub / "blank" / "ship.ipynb",
                  [("def update(x_bar, M, z, H, V):\n", "def update(x_bar, M, z, H, V):\n"
                    "    return None\n"), (VOYAGE, "# the voyage is not run"),
                   (SIGMAS, "sigma_optimal = 0.4145\nsigma_zeroed = ...")])
    own = ship.zeroed_gain_cost(**student_variant("ship", "mistake_q1", SECRET))
    write_variant("ship", sub / "mistake_q1" / "ship.ipynb",
                  [(UPDATE, ZEROED_K), (VOYAGE, "# its own voyage's numbers, typed in below"),
                   (SIGMAS, f"sigma_optimal = {own['sigma_optimal']!r}\n"
                            f"sigma_zeroed = {own['sigma_actual']!r}")])
    # the zeroed gain's claimed σ (its P, not P_actual) of its own voyage, typed in: the grader
    # reads only the number, and the solved notebook runs the voyage in its box
    own = ship.zeroed_gain_cost(**student_variant("ship", "mistake_q2", SECRET))
    write_variant("ship", sub / "mistake_q2" / "ship.ipynb",
                  [(VOYAGE, "# its own voyage's numbers, the claimed σ for the actual one"),
                   (SIGMAS, f"sigma_optimal = {own['sigma_optimal']!r}\n"
                            f"sigma_zeroed = {own['sigma_claimed']!r}")])
    # the numbers of the public notebook's voyage (seed 0) typed in instead of its own voyage
    # (not run: half of a notebook's CPU): wrong for any other variant
    want = ship.zeroed_gain_cost()
    write_variant("ship", sub / "copied" / "ship.ipynb",
                  [(VOYAGE, "# the voyage is not run: its numbers are copied below"),
                   (SIGMAS, f"sigma_optimal = {want['sigma_optimal']!r}\n"
                            f"sigma_zeroed = {want['sigma_actual']!r}")])
    grades = grade(sub, "ship", out=sub.parent / "ship-grades", jobs=2, timeout=120, seed=3,
                   secret=SECRET)
    return {g.student: g for g in grades}


def test_solution_full_marks_blank_zero(graded):
    assert graded["solved"].scores == {"q1": 6.0, "q2": 4.0}
    blank = graded["blank"]
    assert blank.status == "graded" and blank.total == 0
    assert "returns-none" in blank.codes["q1"] and "not-defined" in blank.codes["q2"]


def test_mistakes_lose_exactly_their_questions_and_name_the_codes(graded):
    a, b = graded["mistake_q1"], graded["mistake_q2"]
    assert a.scores == {"q1": 0.0, "q2": 4.0} and a.codes["q1"] == ["zeroed-gain"]
    # the claimed σ for the actual one costs sigma_zeroed's part only
    assert b.scores == {"q1": 6.0, "q2": 2.0} and b.codes["q2"] == ["claimed-not-actual"]


def test_a_copied_number_is_wrong_for_the_students_own_variant(graded):
    assert student_variant("ship", "copied", SECRET) != student_variant("ship", "copied", None)
    g = graded["copied"]
    assert g.scores == {"q1": 6.0, "q2": 0.0} and g.codes["q2"] == ["sigma-value"]
    assert "mass_kg = " in g.feedback


def test_feedback_never_gives_the_expected_value(graded):
    want = ship.zeroed_gain_cost(**student_variant("ship", "mistake_q2", SECRET))
    text = graded["mistake_q2"].feedback
    for v in want.values():
        assert f"{v:.4g}" not in text and f"{v:.3g}" not in text


# ------------------------------------------------------------------ the checks on their own
def test_zeroed_update_is_the_package_zeroed_gain_and_differs_from_the_optimal():
    model = ShipModel()
    for _, (x_bar, M, z, H, V) in ship.cases(seed=1):
        x_opt, P_opt = ship.optimal_update(x_bar, M, z, H, V)
        x_z, P_z = ship.zeroed_update(x_bar, M, z, H, V)
        miss = np.isnan(z)
        K = np.linalg.solve(H @ M @ H.T + V, H @ M).T
        K[:, miss] = 0
        np.testing.assert_allclose(P_z, joseph_update(M, K, H, V), rtol=1e-12, atol=1e-15)
        if 0 < miss.sum() < 9:
            assert not np.allclose(x_opt, x_z, rtol=1e-8, atol=0)
        else:  # nothing or everything missing: the two updates agree
            np.testing.assert_allclose(x_z, x_opt, rtol=1e-10, atol=1e-12)
    assert model.H.shape == (9, 9)


def test_update_answer_names_each_mistake():
    assert ship.update_answer(ship.optimal_update).passed
    from gpsaccel.ship.mistakes import update

    for m in ship.update_mistakes():
        def fun(x_bar, M, z, H, V, m=m):
            return update(x_bar, M, z, H, V, (m,))
        assert ship.update_answer(fun).codes == [m.code]

    def forgets_none(x_bar, M, z, H, V):  # breaks when nothing arrived
        rows = np.flatnonzero(~np.isnan(z))
        return ship.optimal_update(x_bar, M, z, H, V) if rows.size else (x_bar * 0, M)
    r = ship.update_answer(forgets_none)
    assert r.codes == ["update-mismatch"] and "nothing arrived" in str(r)


def test_a_wrong_output_costs_only_its_part():
    """The packaged homeworks' one rule (the calibration homework's): q1's x̂ and P, q2's two σ,
    a part each; a mistake that changes both of q1's outputs (the zeroed gain) costs both. At
    main each question was all or nothing: 0 / 6 and 0 / 4 for every case below."""
    from gpsaccel.assignments.grading import assignment_module
    from gpsaccel.assignments.questions import Answer, Draw

    q1, q2 = assignment_module("ship").graded_questions()
    draw = Draw(7, {"mass_kg": 12.0, "gps_rate_hz": 1.0})

    def q1_score(update):
        answers = [Answer("ok", values=tuple(np.asarray(a, float) for a in update(*r.args)))
                   for r in q1.reads(draw)]
        report = q1.grade(draw, answers)
        return q1.score(report), report.codes

    def p_not_updated(x_bar, M, z, H, V):
        return ship.optimal_update(x_bar, M, z, H, V)[0], M

    def x_not_updated(x_bar, M, z, H, V):
        return x_bar, ship.optimal_update(x_bar, M, z, H, V)[1]

    assert q1_score(ship.optimal_update) == (6.0, [])
    assert q1_score(p_not_updated) == (3.0, ["update-mismatch"])
    assert q1_score(x_not_updated) == (3.0, ["update-mismatch"])
    assert q1_score(lambda x, M, z, H, V: (x, M)) == (0.0, ["update-mismatch"])
    assert q1_score(ship.zeroed_update) == (0.0, ["zeroed-gain"])
    want = ship.zeroed_gain_cost(**draw.variant)

    def q2_score(*values):
        answers = [Answer("ok", values=(np.asarray(v, float),)) if v is not None
                   else Answer("not-defined") for v in values]
        report = q2.grade(draw, answers)
        return q2.score(report), report.codes

    assert q2_score(want["sigma_optimal"], want["sigma_actual"]) == (4.0, [])
    assert q2_score(want["sigma_optimal"], want["sigma_actual"] ** 2) == (2.0, ["std-as-variance"])
    assert q2_score(want["sigma_optimal"], want["sigma_claimed"]) == (2.0, ["claimed-not-actual"])
    assert q2_score(want["sigma_optimal"], None) == (2.0, ["not-defined"])
    assert q2_score(1.0, 2.0) == (0.0, ["sigma-value"])


def test_q1_feedback_states_no_formula_of_the_optimal_update():
    """The student reads what their update does; the gain K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹ and
    x̂ = x̄ + K_r (...) (the answer) are the instructor's."""
    from gpsaccel.ship.mistakes import update

    said = []
    for m in ship.update_mistakes():
        r = ship.update_answer(lambda x_bar, M, z, H, V, m=m: update(x_bar, M, z, H, V, (m,)))
        said.append((r, str(r)))
    r = ship.update_answer(lambda x_bar, M, z, H, V: (ship.optimal_update(x_bar, M, z, H, V)[0],
                                                       M))
    said.append((r, str(r)))
    assert r.findings[0].part == "P" and "your P differs" in str(r)
    for report, text in said:
        assert not report.passed
        for formula in ("K_r =", "(H_r M H_rᵀ + V_r)⁻¹", "x̂ = x̄ + K", "x̂ = x̄ and P = M"):
            assert formula not in text, (formula, text)
        assert "K_r = M H_rᵀ" in report.instructor_text() or report.codes != ["update-mismatch"]


def test_cost_answer_accepts_six_digits_tells_the_filters_apart_without_the_answer():
    want = ship.zeroed_gain_cost()
    assert ship.cost_answer(want["sigma_optimal"], want["sigma_actual"]).passed
    six = [float(f"{want[k]:.6g}") for k in ("sigma_optimal", "sigma_actual")]
    assert ship.cost_answer(*six).passed
    # the three σ agree to 3 digits: "expected 0.4145" for two values was that; 6 digits part them
    assert f"{want['sigma_optimal']:.4g}" == f"{want['sigma_actual']:.4g}"
    assert ship.cost_answer(want["sigma_actual"], want["sigma_actual"]).codes == ["sigma-value"]
    r = ship.cost_answer(want["sigma_optimal"] ** 2, want["sigma_actual"])
    assert r.codes == ["std-as-variance"]
    assert ship.cost_answer(want["sigma_optimal"], want["sigma_claimed"]).codes == [
        "claimed-not-actual"]
    r = ship.cost_answer(1.0, 2.0)
    assert r.codes == ["sigma-value"]
    # no answer yet (None) is named as None, never read as nan
    r = ship.cost_answer(None, want["sigma_actual"])
    assert r.codes == ["not-a-number"] and "got None" in str(r) and "nan" not in str(r)
    assert all(f"{v:.4g}" not in str(r) for v in want.values())
