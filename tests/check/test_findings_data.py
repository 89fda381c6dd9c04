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
from gpsaccel.assignments.grading import Grade, _feedback_text
from gpsaccel.check import batch, findings
from gpsaccel.check.linear import FINDINGS, LinearProblem
from gpsaccel.check.report import Finding, Report, StudentFinding
from gpsaccel.check.wording import STUDENT, UNWORDED

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
