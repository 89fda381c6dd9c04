"""Findings as data: the student's renderer never receives an expected value (issue 27 item 3).

Every catalogue code of every registered problem, and every code the checkers word, is rendered
with a canary as its expected value (a number and a string) and as the instructor's prose; the
canary must never reach any student output (the feedback file, a test cell's AssertionError,
``gpsaccel check``'s table and JSON, a lesson's self-check), and must reach the instructor's.
"""

from __future__ import annotations

import json

import pytest

from gpsaccel import registry
from gpsaccel._feedback import Miss, classify, describe_miss, render
from gpsaccel.assignments._answers import assert_report
from gpsaccel.assignments.scoring import Grade, _feedback_text
from gpsaccel.check import batch, findings
from gpsaccel.check.linear import FINDINGS, LinearProblem
from gpsaccel.check.report import Finding, Report, StudentFinding, brief
from gpsaccel.check.wording import STUDENT, UNWORDED

pytestmark = pytest.mark.usefixtures("warm_boxes")  # conftest.py: the course's zygote

CANARY = 987654.321
CANARY_TEXT = "CANARY-ANSWER-7Q"
SEEN = ("987654", "9.87654e", "987,654", CANARY_TEXT)


def _catalogue(problem) -> list:
    """The problem's catalogue entries, whatever system it checks."""
    if isinstance(problem, LinearProblem):
        return list(problem.catalogue().catalogue())
    if problem.name == "coop":
        from gpsaccel.coop import mistakes as cm

        return [m for kind in cm.KINDS for m in cm.catalogue(kind=kind)]
    if problem.name == "ship":
        from gpsaccel.ship import mistakes as sm

        return list(sm.catalogue())
    raise AssertionError(f"a registered problem without a known catalogue: {problem.name}")


def _problems():
    return [registry.problem(name) for name in registry.problems()]


def _student_outputs(report: Report) -> dict[str, str]:
    """Every student output a report reaches (module docstring)."""
    g = Grade("alice", "alice.ipynb", {"q1": 0.0}, {"q1": 1.0}, "graded")
    cell = ""
    try:
        assert_report(report)
    except AssertionError as exc:  # what grader.check shows in the student's notebook
        cell = str(exc)
    result = batch.student_result(report)  # gpsaccel check: its table's text and its JSON
    return {"feedback": _feedback_text(g, [], {"q1": report}, {}), "grader.check": cell,
            "check table": result["text"], "check json": json.dumps(result, ensure_ascii=False),
            "check first look": brief(result),
            "student json": json.dumps(report.to_dict(), ensure_ascii=False)}


def _assert_no_canary(report: Report) -> None:
    for where, text in _student_outputs(report).items():
        assert text, where
        for c in SEEN:
            assert c not in text, (where, c, text)
    instructor = report.instructor_text() + json.dumps(report.to_dict(instructor=True),
                                                       ensure_ascii=False)
    assert CANARY_TEXT in instructor and "987654" in instructor  # the test can see a leak


def _canary_expected() -> dict:
    return {"value": CANARY, "text": CANARY_TEXT, "matrix": [[CANARY, 1.0], [0.0, CANARY]]}


@pytest.mark.parametrize("problem", _problems(), ids=lambda p: p.name)
def test_every_catalogue_code_renders_without_the_expected_value(problem):
    entries = _catalogue(problem)
    assert entries and {m.code for m in entries} >= set(problem.codes()) - {"wrong-shape"}
    for m in entries:
        report = Report(f"{problem.name}: {m.code}")
        findings.mistake_finding(report, m, "kalman_filter: ")
        f = report.findings[-1]
        # the checker's own path, then the canary in the instructor's fields
        report.findings[-1] = Finding(f.code, f"{f.detail} should be {CANARY} ({CANARY_TEXT})",
                                      f.severity, f.text, f.where, f.observed,
                                      _canary_expected(), f.part)
        _assert_no_canary(report)
        student = report.findings[-1].for_student().message
        assert m.variant in student and student != UNWORDED.format(code=m.code)


def test_every_catalogue_code_has_its_own_student_wording():
    codes = {m.code for p in _problems() for m in _catalogue(p)}
    assert codes - set(STUDENT) == set()


@pytest.mark.parametrize("table", ["STUDENT", "FINDINGS", "box MESSAGES"])
def test_every_worded_code_renders_without_the_expected_value(table):
    templates = {"STUDENT": STUDENT, "FINDINGS": FINDINGS, "box MESSAGES": findings.MESSAGES}[
        table]
    for code, template in templates.items():
        report = Report(code)
        # a prose-only finding (its student text is the code's wording) and a templated one
        report.add(code, f"{code} should be {CANARY}; {CANARY_TEXT}", expected=_canary_expected())
        report.add(code, text=template, where="Φ₁₃", observed={"name": "x_hat"},
                   expected=_canary_expected())
        _assert_no_canary(report)


def test_the_student_projection_has_no_expected_field():
    f = Finding("phi-sign", "Φ₁₃ should be −1.25e-05", text="Φ₁₃ = {v:g} has the wrong sign.",
                where="Φ₁₃", observed={"v": 1.25e-05}, expected={"Φ₁₃": -1.25e-05})
    s = f.for_student()
    assert isinstance(s, StudentFinding)
    assert not hasattr(s, "expected") and not hasattr(s, "detail")
    assert s.message == "Φ₁₃ = 1.25e-05 has the wrong sign."
    assert "-1.25e-05" in f.for_instructor() and "−1.25e-05" in f.for_instructor()


def test_a_template_naming_a_field_it_was_not_given_falls_back_to_the_codes_wording():
    # e.g. a template that asks for an expected value: it is never filled from one
    f = Finding("phi-sign", text="Φ₁₃ should be {value}", expected={"value": CANARY})
    assert f.for_student().message == STUDENT["phi-sign"]
    g = Finding("no-such-code", text="{value}", expected={"value": CANARY})
    assert g.for_student().message == UNWORDED.format(code="no-such-code")


def test_student_text_is_data_never_a_template():
    # a student's exception text with braces is shown as it is, never formatted
    r = Report("x")
    r.add("exception", text="{where} raised {error}", where="f(...)",
          observed={"error": "KeyError: '{where.__class__}' {0} {expected}'"})
    assert "KeyError: '{where.__class__}' {0} {expected}'" in str(r)


def test_lessons_self_check_words_carry_no_expected_value():
    miss = classify(1.0, CANARY)
    assert isinstance(miss, Miss) and CANARY not in vars(miss).values()
    for answer in (0.0, -1.0, 1.0, CANARY * 1.05, CANARY * 3, CANARY * 1.001, CANARY * 1e4):
        text = describe_miss(answer, CANARY)
        assert text == render(classify(answer, CANARY))
        assert "987654" not in text and "9.87" not in text
    assert describe_miss(4.0, 1.0) == "about 4× too large"
    assert describe_miss(1.0, 1000.0) == "about 10^3× too small (units? a power of ten?)"
    assert describe_miss(-1.0, 1.0) == "has the wrong sign"


def test_partial_parts_of_a_report():
    r = Report("q3")
    r.add("nees-sum", text="x", part="average_nees")
    assert r.failed_parts() == {"average_nees"} and not r.passed
    r.add("not-run", text="y")
    assert r.failed_parts() == {"average_nees", ""}


# ============================================ no expected matrix, structure or formula (item 6)
# The canary above proves that nothing of a finding's ``expected`` field reaches a student. The
# feedback can still state the answer in its own words: "H = [I₂ 0]: GPS measures δp and δv",
# "N·ε̄ ~ χ²(3·N)". Below, every wording table and catalogue, and the real checks of every matrix
# question on wrong answers (each element negated, scaled, transposed, σ for σ², the catalogue's
# mistakes ...), are rendered for the student; no student text may hold
#
# * a matrix's block structure or a covariance's formula, in any notation the package writes
#   (:data:`STRUCTURE`: I₂, 0₂ₓ₁, [I₂ 0], diag(...)), nor a χ² with its degrees of freedom;
# * an expected matrix of the question, in any notation (:func:`notations`: numpy's print, lists,
#   rows, diag(...) of its values), nor an expected formula the finding declares (Φ₁₃'s "−Δt²/2"),
#   nor the DT model's right forms (F = I + ΔT·A ...) in a DT question's feedback.

import re  # noqa: E402

import numpy as np  # noqa: E402

#: A matrix's structure (an identity or zero block: I₂, 0₂ₓ₁; a block row [I₂ 0]; a covariance's
#: diag(...)), a χ² with its degrees of freedom (χ²(3·N), χ²₃, "... degrees of freedom"), or a
#: derivative stated with its value (∂γ/∂θ = −1: an element of a Jacobian, the answer).
STRUCTURE = re.compile(r"(?<![A-Za-z_])[I0][₀-₉]|\[\s*I\b|\bdiag\(|χ²\s*[(_{₀-₉]|chi2\(|"
                       r"degrees of freedom|∂[^=;:]{1,30}/∂\S{1,12}\s*=(?!=)")


def test_the_structure_rule_sees_what_it_must():
    for leak in ("H = [I₂ 0]: GPS measures δp and δv", "N·ε̄ ~ χ²(3·N)", "Q = σ²I₄",
                 "Γ = [0₂ₓ₁; I]", "V = diag(σ_p², σ_v²)", "χ² with n·N degrees of freedom",
                 "[I, 0]", "so ∂γ/∂θ = −1", "∂ρ/∂ξa = +Δξ/ρ",
                 "∂(vg tan φg / L)/∂φg = vg / (L cos² φg)"):
        assert STRUCTURE.search(leak), leak
    for fine in ("Your H's row 1 measures δp; the GPS measures δp and δv, not the bias.",
                 "state [δp, δv, b]", "Φ₁₃ = 1.25e-05", "M0₁₁", "95 % χ² bounds", "x̄₀ = Φ x0",
                 "Φ₁₀ and Φ₂₀", "V₁₁ = 3", "eᵀ P⁻¹ e", "A = ∂f/∂x", "C = ∂h/∂x, with Δξ = ξa − ξg",
                 "the continuous-time Jacobian ∂f/∂u of ẋ = f(x, u)"):
        assert not STRUCTURE.search(fine), fine


def notations(value: object) -> set[str]:
    """The ways the package (and numpy) writes a matrix of two or more numbers."""
    E = np.asarray(value, dtype=float)
    if E.size < 2:
        return set()
    out = {np.array2string(E), str(E), str(E.tolist()), np.array2string(E, precision=6)}
    for row in np.atleast_2d(E):
        if row.size > 1 and np.any(row != row[0]):  # "[0, 0]" says nothing of a matrix
            out |= {str(row.tolist()), "[" + ", ".join(f"{v:g}" for v in row) + "]",
                    "[" + " ".join(f"{v:g}" for v in row) + "]"}
    if E.ndim == 2 and E.shape[0] == E.shape[1]:
        out.add("diag(" + ", ".join(f"{v:g}" for v in np.diag(E)) + ")")
    return out


def _formulas(value: object) -> set[str]:
    """The formulas an expected field holds ("−Δt²/2 = -1.25e-05" -> "−Δt²/2")."""
    if isinstance(value, str):
        head = value.split(" = ")[0].strip()
        return {head} if re.search(r"[^\d\s.,eE+\-−()]", head) and len(head) >= 3 else set()
    if isinstance(value, (list, tuple)):
        return set().union(*(_formulas(v) for v in value)) if value else set()
    return set()


def leaks(report: Report, answers: tuple[str, ...] = ()) -> list[tuple[str, str, str]]:
    """(output, what, text) for every student output of ``report`` that states its structure,
    an expected matrix or formula of its findings, or one of ``answers``."""
    expected: set[str] = set(answers)
    for f in report.findings:
        for v in f.expected.values():
            expected |= _formulas(v)
            if not isinstance(v, str):
                try:
                    expected |= notations(v)
                except (TypeError, ValueError):
                    pass
    out = []
    for where, text in _student_outputs(report).items():
        for m in STRUCTURE.finditer(text):
            out.append((where, m.group(), text))
        out += [(where, e, text) for e in expected if e and e in text]
    return out


def _no_leaks(reports: list[tuple[str, Report, tuple[str, ...]]]) -> None:
    found = [(case, *leak) for case, report, answers in reports
             for leak in leaks(report, answers) if not report.passed]
    assert not found, "\n".join(f"{case} [{where}]: {what!r} in {text[:300]!r}"
                                for case, where, what, text in found[:8])


def _wrong(E: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Wrong answers for the matrix E, as students write them."""
    E = np.atleast_2d(np.asarray(E, dtype=float))
    out = [("×1.7", 1.7 * E), ("negated", -E), ("zeros", np.zeros_like(E)),
           ("σ for σ²", np.sqrt(np.abs(E))), ("squared", E**2)]
    if E.shape[0] == E.shape[1]:
        out += [("transposed", E.T), ("identity", np.eye(E.shape[0]))]
    if E.shape[0] > 1:
        out.append(("rows swapped", E[::-1]))
    for idx in zip(*np.nonzero(E), strict=True):
        one = E.copy()
        one[idx] = -one[idx]
        out.append((f"{idx} negated", one))
        one = E.copy()
        one[idx] += 1.0
        out.append((f"{idx} + 1", one))
    return [(k, v) for k, v in out if not np.array_equal(v, E)]


def _calibration_reports() -> list[tuple[str, Report, tuple[str, ...]]]:
    from gpsaccel.calibration.model import CalibrationModel, gamma, phi
    from gpsaccel.check import model_matrices
    from gpsaccel.kalman.update import epoch_transition

    m = CalibrationModel()
    one = gamma(m.dt) @ gamma(m.dt).T * m.W
    out = []
    for dt, Q in ((m.dt, one), (m.gps_interval, epoch_transition(phi(m.dt), one, m.gps_every)[1])):
        right = {"Phi": phi(dt), "Gamma": gamma(dt), "H": m.H, "V": m.V, "W": m.W, "M0": m.M0,
                 "Q": Q}
        for name, E in right.items():
            wrongs = _wrong(E)
            if name in ("Phi", "Gamma"):  # built for the other step
                wrongs.append(("another step", {"Phi": phi, "Gamma": gamma}[name](
                    m.gps_interval + m.dt - dt)))
            if name == "M0":
                wrongs.append(("swapped", np.diag(np.diag(E)[[1, 0, 2]])))
            for label, W in wrongs:
                report = model_matrices(**{**right, name: W}, dt=dt, model=m)
                out.append((f"calibration dt={dt:g} {name} {label}", report, ()))
    return out


def _linear_reports() -> list[tuple[str, Report, tuple[str, ...]]]:
    from gpsaccel import homework as hw
    from gpsaccel.assignments.linear import matrices_answer
    from gpsaccel.assignments.tracker import variant_model
    from gpsaccel.kalman.linear_model import LinearIngredients

    I2, O2 = np.eye(2), np.zeros((2, 2))
    cv2d = hw.LinearModel(Phi=np.block([[I2, 0.1 * I2], [O2, I2]]),
                          Gamma=np.vstack([0.005 * I2, 0.1 * I2]), W=0.25 * I2,
                          H=np.hstack([I2, O2]), V=9.0 * I2, M0=np.diag([100.0, 100, 1, 1]),
                          x0=np.zeros(4), every=10, n_epochs=31, dt=0.1,
                          states=("px", "py", "vx", "vy"))
    out = []
    for label, model in (("tracker", variant_model(20, 0.5, 3.0)), ("cv2d", cv2d)):
        from gpsaccel.assignments.linear import MATRICES, matrices

        right = {k: np.array(v) for k, v in matrices(LinearIngredients.correct(model)).items()
                 if k in MATRICES}
        for name, E in right.items():
            for case, W in _wrong(E) + [("σ²I", model.W[0, 0] * np.eye(model.n))]:
                if W.shape == E.shape:
                    out.append((f"{label} {name} {case}",
                                matrices_answer(model, {**right, name: W}), ()))
    return out


def _nees_reports() -> list[tuple[str, Report, tuple[str, ...]]]:
    from scipy import stats

    from gpsaccel.assignments.calibration import nees_answer, nees_data, nees_reference

    N = 30
    x_true, x_hat, P = nees_data(np.random.default_rng(4), N)
    eps, (lo, hi) = nees_reference(x_true, x_hat, P)
    out = []
    for label, value, bounds in (
            ("one run's bounds", eps, tuple(stats.chi2.ppf([0.025, 0.975], 3))),
            ("N degrees of freedom", eps, tuple(stats.chi2.ppf([0.025, 0.975], N) / N)),
            ("other bounds", eps, (lo * 0.9, hi * 1.1)), ("sum", N * eps, (lo, hi)),
            ("per state", eps / 3, (lo, hi)), ("not two numbers", eps, (lo,))):
        out.append((f"nees {label}", nees_answer(value, bounds, N, x_true, x_hat, P), ()))
    return out


def _dt_model_reports() -> list[tuple[str, Report, tuple[str, ...]]]:
    from gpsaccel.check import dt_model
    from gpsaccel.check.dt_model import DT_RIGHT
    from gpsaccel.check.jacobians import analytic
    from gpsaccel.coop.model import CoopModel

    m = CoopModel()
    X, U = m.x0[None], m.u0[None]
    A, B, C = (analytic(k, X, U, m)[0] for k in "ABC")
    right = {"F": np.eye(6) + m.dt * A, "G": m.dt * B, "H": C}
    slips = {"F": [("A", A), ("ΔT·A", m.dt * A), ("I + A", np.eye(6) + A)],
             "G": [("B", B)], "H": [("ΔT·C", m.dt * C)]}
    answers = tuple(v for k, v in DT_RIGHT.items() if k in right)
    out = []
    for name, E in right.items():
        for label, W in slips[name] + _wrong(E)[:8]:
            out.append((f"dt_model {name} {label}", dt_model(**{**right, name: W}, x=m.x0,
                                                             u=m.u0), answers))
    return out


def _coop_answers() -> tuple[str, ...]:
    """The coop homework's right forms of question 2 (F = I + ΔT·A, G = ΔT·B, H = C): an answer
    in the feedback of any of its questions."""
    from gpsaccel.check.dt_model import DT_RIGHT

    return tuple(DT_RIGHT[k] for k in "FGH")


def _jacobian_slips() -> list[tuple[str, dict]]:
    """Wrong Jacobian functions as students write them: each element that is not identically
    zero negated, zeroed, off by one; a whole matrix for the DT step; C's vehicles swapped; a
    finite difference through the wrapped h."""
    from gpsaccel.check.jacobians import FORMULAS
    from gpsaccel.coop.model import h, jacobian_A, jacobian_B, jacobian_C, wrap_measurement

    dt = 0.1
    right = {"A": lambda x, u: jacobian_A(x, u), "B": lambda x, u: jacobian_B(x, u, 0.5),
             "C": lambda x: jacobian_C(x)}

    def edited(name, idx, how):
        def f(*args):
            out = np.array(right[name](*args), dtype=float)
            out[idx] = how(out[idx])
            return out
        return f

    out = []
    for name, formulas in FORMULAS.items():
        for idx in formulas:
            for label, how in (("negated", lambda v: -v), ("zero", lambda v: 0.0 * v),
                               ("+ 1", lambda v: v + 1.0)):
                out.append((f"{name}{idx} {label}", {name: edited(name, idx, how)}))

    def fd_C(x):
        C = np.empty((5, 6))
        for j in range(6):
            d = np.zeros(6)
            d[j] = 1e-6
            C[:, j] = wrap_measurement(h(x + d) - h(x - d)) / 2e-6
        return C
    out += [("A = I + ΔT·A", {"A": lambda x, u: np.eye(6) + dt * jacobian_A(x, u)}),
            ("A = ΔT·A", {"A": lambda x, u: dt * jacobian_A(x, u)}),
            ("B = ΔT·B", {"B": lambda x, u: dt * jacobian_B(x, u, 0.5)}),
            ("C's vehicles swapped", {"C": lambda x: jacobian_C(x)[:, [3, 4, 5, 0, 1, 2]]}),
            ("A heading columns negated", {"A": edited("A", (slice(None), [2, 5]),
                                                       lambda v: -v)}),
            ("C by a finite difference through the wrapped h", {"C": fd_C})]
    return out


def _coop_reports() -> list[tuple[str, Report, tuple[str, ...]]]:
    """The coop Jacobian checks (``check.jacobians``, the homework's question 1) and the coop
    homework's questions 2 and 3 on wrong answers."""
    from gpsaccel.assignments import coop as hw_coop
    from gpsaccel.check.jacobians import jacobians
    from gpsaccel.coop.model import jacobian_A, jacobian_B, jacobian_C

    answers = _coop_answers()
    out = []
    for label, given in _jacobian_slips():
        out.append((f"check.jacobians {label}", jacobians(**given, n_random=10), answers))
    q1 = hw_coop.jacobians(jacobian_A, lambda x, u: 0.1 * jacobian_B(x, u), None, n_random=5)
    out.append(("homework q1: B = ΔT·B, C not defined", q1, answers))

    def lin(F=None, G=None, H=None):
        def f(x, u, dt_):
            A, B, C = jacobian_A(x, u), jacobian_B(x, u), jacobian_C(x)
            return ((np.eye(6) + dt_ * A) if F is None else F(A, B, C, dt_),
                    dt_ * B if G is None else G(A, B, C, dt_), C if H is None else H(A, B, C, dt_))
        return f
    for label, fn in (
            ("F = A", lin(F=lambda A, B, C, t: A)), ("F = ΔT·A", lin(F=lambda A, B, C, t: t * A)),
            ("F = I + A", lin(F=lambda A, B, C, t: np.eye(6) + A)),
            ("F without its heading column", lin(F=lambda A, B, C, t: np.eye(6) + 0 * A)),
            ("F's A₁₃ negated", lin(F=lambda A, B, C, t: np.eye(6) + t * A * np.where(
                np.arange(36).reshape(6, 6) == 2, -1, 1))),
            ("G = B", lin(G=lambda A, B, C, t: B)),
            ("G the exact zero-order hold", lin(G=lambda A, B, C, t: (
                t * np.eye(6) + t**2 / 2 * A) @ B)),
            ("G = 2ΔT·B", lin(G=lambda A, B, C, t: 2 * t * B)),
            ("H = ΔT·C", lin(H=lambda A, B, C, t: t * C)),
            ("H's bearing rows negated", lin(H=lambda A, B, C, t: C * np.array(
                [[-1], [1], [-1], [1], [1]])))):
        out.append((f"homework q2 {label}", hw_coop.dt_linearization(fn, n_random=2), answers))
    return out + _coop_ekf_reports(answers)


def _coop_ekf_reports(answers: tuple[str, ...]) -> list[tuple[str, Report, tuple[str, ...]]]:
    """The homework's question 3: each EKF mistake it names, and one it does not."""
    from gpsaccel.assignments import coop as hw_coop
    from gpsaccel.coop.filters import run_ekf
    from gpsaccel.coop.mistakes import ingredients
    from gpsaccel.coop.model import CoopModel

    model = CoopModel()
    y = model.log()
    out = []
    for m in hw_coop.ekf_mistakes():
        def student(y, x0, P0, Q, R, m=m):
            res = run_ekf(model, y, Q, R, x0, P0, ingredients=ingredients((m,)))
            return res.x_hat, res.P
        out.append((f"homework q3 {m.code}", hw_coop.ekf(student, y), answers))

    def doubled_q(y, x0, P0, Q, R):
        res = run_ekf(model, y, 2 * Q, R, x0, P0)
        return res.x_hat, res.P
    out.append(("homework q3 Q doubled", hw_coop.ekf(doubled_q, y), answers))
    return out


def test_no_coop_question_states_an_earlier_questions_answer():
    """A question may state what to compute; it never states another question's expected
    result: the hand-out's question 3 (the EKF) names question 2's F and H, not their forms."""
    import json

    from gpsaccel.assignments.generate import student_package_dir

    nb = json.loads((student_package_dir() / "coop" / "coop.ipynb").read_text(encoding="utf-8"))
    texts = ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown"]
    q3 = [t for t in texts if t.startswith("**Question 3")]
    assert q3 and "question 2" in q3[0]
    found = [(a, t[:80]) for t in texts if "Question 2 " not in t for a in _coop_answers()
             if a in t]
    assert not found, found


@pytest.mark.parametrize("source", ["calibration", "linear", "nees", "dt_model", "coop"])
def test_no_check_of_a_matrix_or_a_formula_states_the_answer(source):
    reports = {"calibration": _calibration_reports, "linear": _linear_reports,
               "nees": _nees_reports, "dt_model": _dt_model_reports,
               "coop": _coop_reports}[source]()
    assert sum(not r.passed for _, r, _ in reports) >= 6  # the test sees failing checks
    _no_leaks(reports)


def test_no_wording_table_or_catalogue_states_a_structure():
    from gpsaccel.check.matrices import _ELEMENT_ADVICE
    from gpsaccel.check.report import ARRAY_TEXT
    from gpsaccel.sandbox.outcomes import OUTCOMES

    tables = {"STUDENT": STUDENT, "FINDINGS": FINDINGS, "box MESSAGES": findings.MESSAGES,
              "ARRAY_TEXT": ARRAY_TEXT, "matrices advice": _ELEMENT_ADVICE,
              "OUTCOMES": {k: o.finding for k, o in OUTCOMES.items()}}
    bad = [(table, code, m.group()) for table, words in tables.items()
           for code, text in words.items() for m in STRUCTURE.finditer(text)]
    for problem in _problems():
        for m in _catalogue(problem):
            report = Report(problem.name)
            findings.mistake_finding(report, m, "kalman_filter: ")
            text = report.findings[-1].for_student().message
            bad += [(problem.name, str(m), hit.group()) for hit in STRUCTURE.finditer(text)]
    assert not bad, bad
