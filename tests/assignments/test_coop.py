"""The coop homework: graded in the sandbox (solved, blank, a wrong Jacobian element, the DT
model's mistakes, an unwrapped residual); the checks on their own."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from gpsaccel import CoopModel
from gpsaccel.assignments import coop
from gpsaccel.assignments.generate import student_package_dir
from gpsaccel.classrun import grade
from gpsaccel.coop import model as cm
from gpsaccel.coop.filters import run_ekf

from .conftest import write_variant

C_ROW = "C[row, [0, 1, 3, 4]] = [deta / r2, -dxi / r2, -deta / r2, dxi / r2]"
B_32 = "B[2, 0], B[2, 1] = np.tan(u[1]) / L, u[0] / (L * np.cos(u[1]) ** 2)"
WRAP = "r[[0, 2]] = wrap(r[[0, 2]])"
F_EULER = "F = np.eye(6) + dt * jacobian_A(x, u)"
#: the notebook's own run of its EKF on the course log: the grader calls ekf itself (q3's reads),
#: so only the solved notebook keeps it (an EKF run is a quarter of a box's CPU)
OWN_RUN = ("x_hat, P = ekf(y_log, model.x0, model.P0, model.Qtrue, model.Rtrue)",
           "pass  # not run here")
G_EULER = "G = dt * jacobian_B(x, u)"


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    sub = tmp_path_factory.mktemp("class")
    write_variant("coop", sub / "solved" / "coop.ipynb")
    write_variant("coop", sub / "blank" / "coop.ipynb", [OWN_RUN], last_cell=(
        "jacobian_A = jacobian_B = jacobian_C = dt_linearization = ekf = ..."))
    write_variant("coop", sub / "wrong C, no wrap" / "coop.ipynb",
                  [(C_ROW, "C[row, [0, 1, 3, 4]] = [-deta / r2, dxi / r2, deta / r2, -dxi / r2]"),
                   (WRAP, "pass  # residual not wrapped"), OWN_RUN])
    write_variant("coop", sub / "one wrong B" / "coop.ipynb",
                  [(B_32, "B[2, 0], B[2, 1] = np.tan(u[1]) / L, u[0] / L"), OWN_RUN])
    write_variant("coop", sub / "F without I" / "coop.ipynb",
                  [(F_EULER, "F = dt * jacobian_A(x, u)"), OWN_RUN])
    # only its q2 is asked about: no EKF of its own in the box, none of the grader's after it
    write_variant("coop", sub / "zoh" / "coop.ipynb", [(G_EULER, (
        "G = (dt * np.eye(6) + dt**2 / 2 * jacobian_A(x, u)) @ jacobian_B(x, u)")), OWN_RUN],
        last_cell="ekf = ...")
    released = sub / "released" / "coop.ipynb"  # what the wheel hands out, run as it is
    released.parent.mkdir()
    shutil.copy(student_package_dir() / "coop" / "coop.ipynb", released)
    grades = grade(sub, "coop", out=sub.parent / "coop-grades", jobs=2, timeout=120, seed=11)
    return {g.student: g for g in grades}


def test_solution_full_marks_blank_zero(graded):
    assert graded["solved"].scores == {"q1": 3.0, "q2": 2.0, "q3": 5.0}
    blank = graded["blank"]
    assert blank.status == "graded" and blank.total == 0
    assert blank.codes["q3"] == ["not-defined"]


def test_the_released_notebook_run_as_handed_out_gets_findings_not_grader_errors(graded):
    """Its functions are defined with bodies `...` (they return None): each question says so
    to the student; none of them is a grader-error (q1 was, when check.jacobians resolved to the
    module of that name: TypeError)."""
    g = graded["released"]
    assert g.status == "graded" and g.total == 0, g.feedback
    assert g.codes == {"q1": ["returns-none"], "q2": ["returns-none"], "q3": ["returns-none"]}
    assert "grader-error" not in g.feedback and "A(x, u) returned None" in g.feedback


def test_mistakes_lose_exactly_their_questions_and_name_the_codes(graded):
    a = graded["wrong C, no wrap"]
    assert a.scores == {"q1": 2.0, "q2": 2.0, "q3": 0.0}, a.feedback  # C is one of q1's parts
    assert a.codes["q1"] == ["jacobian-C"] and a.codes["q3"] == ["no-angle-wrap"]
    b = graded["F without I"]  # F is one of q2's parts (1 of 2 points)
    assert b.scores == {"q1": 3.0, "q2": 1.0, "q3": 5.0} and b.codes["q2"] == ["dt-linearization"]


def test_one_wrong_B_element_costs_only_the_jacobian_question(graded):
    g = graded["one wrong B"]
    assert g.scores == {"q1": 2.0, "q2": 2.0, "q3": 5.0}, g.feedback  # A and C are right
    assert g.codes["q1"] == ["jacobian-B"] and "B₃₂" in g.feedback


def test_an_exact_zero_order_hold_G_is_named(graded):
    g = graded["zoh"]
    assert g.scores["q2"] == 1.5 and g.codes["q2"] == ["zero-order-hold"]  # G's half point
    assert "zero-order-hold" in g.feedback


def test_feedback_names_elements_without_expected_values(graded):
    text = graded["one wrong B"].feedback
    assert "should be …" in text or "should be" not in text
    assert "6.12323e-18" not in text


# ------------------------------------------------------------------ the checks on their own
def test_jacobian_checks_call_the_checker_and_name_the_element():
    assert coop.jacobians(cm.jacobian_A, cm.jacobian_B, cm.jacobian_C).passed

    def B_no_cos2(x, u):  # ∂θ̇g/∂φg without the 1/cos²
        B = cm.jacobian_B(x, u).copy()
        B[2, 1] = u[0] / 0.5
        return B
    r = coop.jacobians(cm.jacobian_A, B_no_cos2, cm.jacobian_C)
    assert r.codes == ["jacobian-B"] and "B₃₂" in str(r)
    assert coop.jacobians(cm.jacobian_A, cm.jacobian_B, lambda x: 1 / 0).codes == ["exception"]
    assert coop.jacobians(None, cm.jacobian_B, cm.jacobian_C).codes == ["not-defined"]
    r = coop.jacobians(cm.jacobian_A, lambda x, u: None, cm.jacobian_C)  # a body still `...`
    assert r.codes == ["returns-none"] and "B(x, u) returned None" in str(r)


def test_dt_linearization_grades_G_against_the_students_own_B():
    dt = CoopModel().dt

    def B_bad(x, u):
        B = cm.jacobian_B(x, u).copy()
        B[2, 1] += 1.0
        return B

    def lin(x, u, dt, B=B_bad):
        return np.eye(6) + dt * cm.jacobian_A(x, u), dt * B(x, u), cm.jacobian_C(x)
    assert not coop.dt_linearization(lin).passed  # against the right B alone: wrong
    r = coop.dt_linearization(lin, jacobian_A=cm.jacobian_A, jacobian_B=B_bad,
                              jacobian_C=cm.jacobian_C)
    assert r.passed and "uses-own-jacobian" in [f.code for f in r.findings]
    assert dt == 0.1


def test_a_wrong_dt_matrix_costs_only_its_part():
    """q2's F, G, H are parts (1, 0.5, 0.5), as q1's A, B, C: the packaged homeworks' one rule
    (the calibration homework's); a slip keeps nothing. At main q2 was all or nothing (0 / 2)."""
    from gpsaccel.assignments.grading import assignment_module
    from gpsaccel.assignments.questions import Answer, Draw

    q2 = assignment_module("coop").graded_questions()[1]
    draw = Draw(3, {})
    own = {"jacobian_A": cm.jacobian_A, "jacobian_B": cm.jacobian_B, "jacobian_C": cm.jacobian_C}

    def score(F=None, G=None, H=None, raises=False):
        def lin(x, u, dt):
            if raises:
                raise ZeroDivisionError
            A, B, C = cm.jacobian_A(x, u), cm.jacobian_B(x, u), cm.jacobian_C(x)
            return ((np.eye(6) + dt * A) if F is None else F(A, dt), dt * B if G is None else
                    G(B, dt), C if H is None else H(C, dt))
        answers = []
        for r in q2.reads(draw):
            fn = own.get(r.name, lin)
            try:
                out = fn(*r.args)
            except ZeroDivisionError:
                answers.append(Answer("exception", "ZeroDivisionError"))
                continue
            answers.append(Answer("ok", values=tuple(np.asarray(a, float) for a in (
                out if isinstance(out, tuple) else (out,)))))
        report = q2.grade(draw, answers)
        return q2.score(report), report.codes

    assert score() == (2.0, [])
    assert score(F=lambda A, dt: dt * A) == (1.0, ["dt-linearization"])
    assert score(G=lambda B, dt: B) == (1.5, ["dt-linearization"])
    assert score(H=lambda C, dt: dt * C) == (1.5, ["dt-linearization"])
    assert score(F=lambda A, dt: A, H=lambda C, dt: dt * C) == (0.5, ["dt-linearization"])
    assert score(raises=True) == (0.0, ["exception"])


def test_the_homework_grades_with_the_package_ekf_and_recognises_each_mistake():
    from dataclasses import replace

    from gpsaccel.coop.mistakes import ingredients

    model = CoopModel()
    y = model.log()
    ref = run_ekf(model, y, Q=model.Qtrue)
    assert coop.ekf(lambda y, x0, P0, Q, R: (ref.x_hat, ref.P), y).passed
    assert [(m.code, m.variant) for m in coop.ekf_mistakes()] == [
        ("no-angle-wrap", "residual y − h(x̄) not wrapped"),
        ("euler-propagation", "one Euler step per sample"),
        ("jacobian-point", "H at the previous posterior x̂_k"),
        ("returns-a-priori", "x̄ and M returned")]
    for m in coop.ekf_mistakes():
        def student(y, x0, P0, Q, R, m=m):
            out = run_ekf(model, y, Q, R, x0, P0, ingredients=ingredients((m,)))
            return out.x_hat, out.P
        assert coop.ekf(student, y).codes == [m.code]
    # returns-a-priori is x̄, M of the right filter
    prior = run_ekf(model, y, Q=model.Qtrue, ingredients=replace(ingredients(), output="prior"))
    np.testing.assert_array_equal(prior.x_hat, ref.x_bar)
    np.testing.assert_array_equal(prior.P, ref.M)


def test_packaged_q2_check_passes_a_right_answer_through_otter():
    """The student's ``grader.check("q2")`` as otter runs it (its test file a module of its own,
    the notebook's variables passed by name): a right dt_linearization passes; one whose G is
    built from a wrong B passes when that B is the notebook's own jacobian_B (question 1 pays for
    it) and fails when the notebook's jacobian_B is right."""
    import json

    from otter.test_files import ExceptionTestFile

    nb = json.loads((student_package_dir() / "coop" / "coop.ipynb").read_text(encoding="utf-8"))
    source = nb["metadata"]["otter"]["tests"]["q2"]

    def wrong_b(x, u):
        return 2 * cm.jacobian_B(x, u)

    def run(b_in_g, own_b):
        def dt_linearization(x, u, dt):
            return np.eye(6) + dt * cm.jacobian_A(x, u), dt * b_in_g(x, u), cm.jacobian_C(x)
        env = {"dt_linearization": dt_linearization, "jacobian_A": cm.jacobian_A,
               "jacobian_B": own_b, "jacobian_C": cm.jacobian_C}
        test = ExceptionTestFile.from_string(source, path="q2.py")
        test.run(env)
        return test.passed_all, test.summary()

    assert run(cm.jacobian_B, cm.jacobian_B)[0]
    assert run(wrong_b, wrong_b)[0]
    passed, summary = run(wrong_b, cm.jacobian_B)
    assert not passed and "NameError" not in summary and "AssertionError" in summary
