"""The sandbox's outcomes are worded in one table: the checker's findings, the homework grader's
stop clause and a class run's lost items (a check, a notebook) all read
gpsaccel.sandbox.outcomes.OUTCOMES."""

from __future__ import annotations

from pathlib import Path

from gpsaccel import sandbox as sb
from gpsaccel.assignments import scoring
from gpsaccel.check import batch, findings
from gpsaccel.classrun import running
from gpsaccel.classrun.checking import CheckPlan, _Check
from gpsaccel.classrun.entries import Entry
from gpsaccel.classrun.grading import _Grade
from gpsaccel.sandbox.outcomes import OUTCOMES

#: Every failure a box reports (gpsaccel.sandbox's docstring and the runner's problems).
FAILURES = ("timeout", "memory-limit", "output-limit", "file-limit", "process-limit",
            "uses-checker", "result-refused", "crashed", "import-error", "no-function",
            "exception", "return-value", "not-numeric", "wrong-shape", "machine-busy")


def test_every_failure_has_its_wording_and_the_checker_reads_it():
    for code in FAILURES:
        assert OUTCOMES[code].finding, code
        assert findings.MESSAGES[code] == OUTCOMES[code].finding, code


def test_the_grader_stops_with_the_tables_clause():
    stops = {c for c, o in OUTCOMES.items() if o.stop}
    assert stops == {"timeout", "memory-limit", "process-limit", "output-limit", "file-limit",
                     "crashed", "result-refused", "uses-checker", "machine-busy"}
    for code in stops:
        assert scoring._STOPS[code] == OUTCOMES[code].stop


def test_a_lost_check_and_a_lost_notebook_are_worded_by_the_table():
    check = _Check(CheckPlan((), (), "calibration", None, 1, False, 30.0, "basic"))
    notebook = _Grade(Path("class"), {"name": "calibration", "timeout": 30.0})
    entry = Entry("alice", Path("class/alice.ipynb"), id="alice")
    assert (check.deadline, notebook.deadline) == (30.0 + batch.CHECK_SLACK,
                                                   2 * 30.0 + 60 + scoring.SLACK)
    for task in (check, notebook):
        for reason in ("error", "not-a-report", "too-long", "died"):
            why = running.lost_text(sb.Lost(reason, "signal SIGKILL"), task)
            out = task.lost(entry, why)
            want = OUTCOMES[f"lost.{reason}"].finding.format(
                detail="signal SIGKILL", limit=task.deadline, slack=task.deadline - 30.0,
                doer=task.doer, doing=task.doing)
            assert why == want and want in str(out), (reason, out)
            # each in its own words: a lost notebook never says "check", a lost file "grade"
            other = ("grad", "notebook") if task is check else ("check", " file")
            assert not any(w in why.lower() for w in other), why
            assert out["status" if task is notebook else "codes"] in ("grader-error",
                                                                      ["checker-error"])


def test_an_emptied_traceback_is_said_to_be_empty_never_left_blank(tmp_path):
    """The student's code shares the runner's interpreter: a file that empties the traceback
    module's output made "the traceback ends with:" end the finding above nothing.  It says none
    came back, the first look drops the clause, and a box killed at a limit (no traceback)
    still ends its sentence with "." before the advice."""
    import dataclasses

    import numpy as np

    from gpsaccel.check.report import Report, first_line

    (tmp_path / "s.py").write_text(
        "import traceback\n"
        "traceback.format_list = lambda *a, **k: []\n"
        "traceback.format_exception_only = lambda *a, **k: []\n"
        "def f(z):\n    raise ValueError('hidden')\n", encoding="utf-8")
    calls = [sb.Call("f", (np.zeros(2),), (sb.Output("y", (2,)),))]
    limits = sb.Limits(time=60)
    box = sb.run(sb.load_submission(tmp_path / "s.py", "f"), calls, limits, backend="basic")
    assert box.failure == "exception" and not (box.problem or {}).get("traceback", "").strip()
    report = Report("p")
    findings.box_findings(report, box, calls, limits)
    text = report.findings[-1].for_student().message
    assert text.endswith("the traceback ends with:\n      " + findings.NO_TRACEBACK), text
    assert first_line(text) == "f(...) raised an exception on call 1 of 1.", first_line(text)

    report = Report("p")
    findings.box_findings(report, dataclasses.replace(box, failure="memory-limit", problem=None),
                          calls, limits)
    text = report.findings[-1].message
    assert "traceback" not in text and "(after 0 of 1 calls). A filter needs" in text, text
