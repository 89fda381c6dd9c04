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
    assert b.scores == {"q1": 6.0, "q2": 0.0} and b.codes["q2"] == ["claimed-not-actual"]


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
    assert all(f"{v:.4g}" not in str(r) for v in want.values())
