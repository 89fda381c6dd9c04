"""The ship homework: otter assign, otter run on the solution, the blank and two mistake notebooks;
the update check on its own."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from gpsaccel.assignments import generate, grade, ship
from gpsaccel.kalman.update import joseph_update
from gpsaccel.ship.model import ShipModel

UPDATE = """    rows = np.flatnonzero(~np.isnan(z))
    if rows.size == 0:
        return x_bar.copy(), M.copy()
    Hr, Vr = H[rows], V[np.ix_(rows, rows)]
    K = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)
    x_hat = x_bar + K @ (z[rows] - Hr @ x_bar)
    A = np.eye(len(x_bar)) - K @ Hr
    return x_hat, A @ M @ A.T + K @ Vr @ K.T"""

ZEROED = """    missing = np.isnan(z)
    K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)
    K[:, missing] = 0.0
    r = np.where(missing, 0.0, z - H @ x_bar)
    A = np.eye(len(x_bar)) - K @ H
    return x_bar + K @ r, A @ M @ A.T + K @ V @ K.T"""

ACTUAL = "sigma_zeroed = float(np.sqrt(zeroed.P_actual[-1][0, 0]))"


@pytest.fixture(scope="module")
def graded(tmp_path_factory, make_variant):
    dist = generate("ship", tmp_path_factory.mktemp("dist") / "ship", run_tests=False)
    folder = tmp_path_factory.mktemp("class")
    shutil.copy(dist.solution, folder / "solved.ipynb")
    shutil.copy(dist.student, folder / "blank.ipynb")
    make_variant(dist.solution, folder / "mistake_q1.ipynb", [(UPDATE, ZEROED)])
    make_variant(dist.solution, folder / "mistake_q2.ipynb",
                 [(ACTUAL, ACTUAL.replace("P_actual", "P"))])
    grades = grade(folder, "ship", out=folder / "grades", autograder=dist.autograder, jobs=2,
                   timeout=300)
    return {g.submission: g for g in grades}


def test_solution_full_marks_blank_zero(graded):
    assert graded["solved.ipynb"].scores == {"q1": 6.0, "q2": 4.0}
    blank = graded["blank.ipynb"]
    assert blank.status == "graded" and blank.total == 0
    assert "returns-none" in blank.outputs["q1"] and "not-a-number" in blank.outputs["q2"]


def test_mistakes_lose_exactly_their_questions_and_name_the_codes(graded):
    a, b = graded["mistake_q1.ipynb"], graded["mistake_q2.ipynb"]
    assert a.scores == {"q1": 0.0, "q2": 4.0} and "zeroed-gain" in a.outputs["q1"]
    assert b.scores == {"q1": 6.0, "q2": 0.0} and "claimed-not-actual" in b.outputs["q2"]


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
    for code, (fun, _) in ship.MISTAKES.items():
        assert ship.update_answer(fun).codes == [code]

    def forgets_none(x_bar, M, z, H, V):  # breaks when nothing arrived
        rows = np.flatnonzero(~np.isnan(z))
        return ship.optimal_update(x_bar, M, z, H, V) if rows.size else (x_bar * 0, M)
    r = ship.update_answer(forgets_none)
    assert r.codes == ["update-mismatch"] and "nothing arrived" in str(r)


def test_cost_answer():
    want = ship.zeroed_gain_cost()
    assert ship.cost_answer(want["sigma_optimal"], want["sigma_actual"]).passed
    assert ship.cost_answer(want["sigma_optimal"] ** 2, want["sigma_actual"]).codes == [
        "std-as-variance"]
    assert ship.cost_answer(want["sigma_optimal"], want["sigma_claimed"]).codes == [
        "claimed-not-actual"]
