"""The coop homework: otter assign, otter run on the solution, the blank and two mistake notebooks;
the finite-difference and EKF checks on their own."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from gpsaccel import CoopModel
from gpsaccel.assignments import coop, generate, grade
from gpsaccel.coop import model as cm
from gpsaccel.coop.filters import run_ekf

C_ROW = "C[row, [0, 1, 3, 4]] = [deta / r2, -dxi / r2, -deta / r2, dxi / r2]"
WRAP = "r[[0, 2]] = wrap(r[[0, 2]])"
F_EULER = "F = np.eye(6) + dt * jacobian_A(x, u)"


@pytest.fixture(scope="module")
def graded(tmp_path_factory, make_variant):
    dist = generate("coop", tmp_path_factory.mktemp("dist") / "coop", run_tests=False)
    folder = tmp_path_factory.mktemp("class")
    shutil.copy(dist.solution, folder / "solved.ipynb")
    shutil.copy(dist.student, folder / "blank.ipynb")
    make_variant(dist.solution, folder / "mistakes_q1_q3.ipynb",
                 [(C_ROW, "C[row, [0, 1, 3, 4]] = [-deta / r2, dxi / r2, deta / r2, -dxi / r2]"),
                  (WRAP, "pass  # residual not wrapped"),
                  # question 2 on the course model's C, so that only q1 and q3 carry a mistake
                  ("    H = jacobian_C(x)\n    return F, G, H", "    H = model.C(x)\n    return F, G, H")])
    make_variant(dist.solution, folder / "mistake_q2.ipynb", [(F_EULER, "F = dt * jacobian_A(x, u)")])
    grades = grade(folder, "coop", out=folder / "grades", autograder=dist.autograder, jobs=2,
                   timeout=300)
    return {g.submission: g for g in grades}


def test_solution_full_marks_blank_zero(graded):
    assert graded["solved.ipynb"].scores == {"q1": 3.0, "q2": 2.0, "q3": 5.0}
    blank = graded["blank.ipynb"]
    assert blank.status == "graded" and blank.total == 0
    assert "returns-none" in blank.feedback


def test_mistakes_lose_exactly_their_questions_and_name_the_codes(graded):
    a, b = graded["mistakes_q1_q3.ipynb"], graded["mistake_q2.ipynb"]
    assert a.scores == {"q1": 0.0, "q2": 2.0, "q3": 0.0}
    assert "jacobian-sign" in a.outputs["q1"] and "innovation-not-wrapped" in a.outputs["q3"]
    assert b.scores == {"q1": 3.0, "q2": 0.0, "q3": 5.0}
    assert "dt-missing-identity" in b.outputs["q2"]


# ------------------------------------------------------------------ the checks on their own
def test_finite_differences_match_the_analytic_jacobians():
    for x, u in coop.points(seed=3, n=4):
        np.testing.assert_allclose(coop.fd_A(x, u), cm.jacobian_A(x, u), rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(coop.fd_B(x, u), cm.jacobian_B(x, u), rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(coop.fd_C(x), cm.jacobian_C(x), rtol=1e-7, atol=1e-8)


def test_jacobian_checks_name_the_element():
    assert coop.jacobians(cm.jacobian_A, cm.jacobian_B, cm.jacobian_C).passed

    def B_no_cos2(x, u):  # ∂θ̇g/∂φg without the 1/cos²
        B = cm.jacobian_B(x, u).copy()
        B[2, 1] = u[0] / 0.5
        return B
    r = coop.jacobians(cm.jacobian_A, B_no_cos2, cm.jacobian_C)
    assert r.codes == ["jacobian-element"] and "B₃₂" in str(r)
    assert coop.jacobians(cm.jacobian_A, cm.jacobian_B, lambda x: 1 / 0).codes == ["exception"]
    assert coop.jacobians(cm.jacobian_A, cm.jacobian_B, lambda x: np.zeros((6, 5))).codes == [
        "shape"]


def test_reference_ekf_equals_the_package_ekf_and_each_mistake_is_recognised():
    model = CoopModel()
    y = model.log()
    ref = run_ekf(model, y, Q=model.Qtrue)
    x, P = coop.reference_ekf(model, y, model.x0, model.P0, model.Qtrue, model.Rtrue)
    assert np.abs(cm.state_residual(x, ref.x_hat)).max() < 1e-9
    assert np.abs(P - ref.P).max() < 1e-9
    assert coop.ekf(lambda y, x0, P0, Q, R: (ref.x_hat, ref.P), y).passed
    for code in coop.EKF_MISTAKES:
        def student(y, x0, P0, Q, R, code=code):
            return coop.reference_ekf(model, y, x0, P0, Q, R, code)
        assert coop.ekf(student, y).codes == [code]
