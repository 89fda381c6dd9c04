"""A student's first look at ``gpsaccel check FILE`` (issue 40 item 3): each finding's first line
— where and what, never the expected value — with the lesson section that teaches its fix, and
that ``-v`` gives the whole report; a class stays the instructor's table, with which lesson
teaches each mistake the class made."""

from __future__ import annotations

import argparse
from pathlib import Path
from types import SimpleNamespace

from gpsaccel._taught import taught
from gpsaccel.check import batch
from gpsaccel.check.report import Report, brief, see
from gpsaccel.classrun.writing import Terminal
from gpsaccel.cli import main
from gpsaccel.cli.checking import _check_report

SUBMISSIONS = Path(__file__).resolve().parents[1] / "submissions"


def _report(subject: str = "alice.py") -> Report:
    r = Report(subject)
    r.add("std-as-variance", "V₂₂ should be 0.0016", text="{where} = {v:g}: a σ where σ² belongs.",
          where="V₂₂", observed={"v": 0.04}, expected={"V₂₂": 0.0016})
    r.add("exception", text="kalman_filter(...) raised an exception on run 2; the traceback "
          "ends with:\n      ZeroDivisionError: boom", where="run 2")
    r.add("inconsistent", severity="warning", text="Your P does not describe your errors at "
          "{where}.", where="t = 1.6 s")
    r.add("matches-optimal", severity="note", text="Right on {n} runs.", observed={"n": 10})
    r.tables.append("against the optimal filter: max |ΔP|/(σσ) = 23.1")
    return r


def test_the_first_look_is_each_findings_line_and_where_the_course_teaches_it():
    text = brief(batch.student_result(_report()))
    assert text.splitlines() == [
        "alice.py: FAILED (std-as-variance, exception)",
        "  - [error] std-as-variance: V₂₂ = 0.04: a σ where σ² belongs.",
        "    → lesson 06, 'Report 003: variances and standard deviations mixed up'",
        "  - [error] exception: kalman_filter(...) raised an exception on run 2; the traceback "
        "ends with",
        "    ZeroDivisionError.",
        "    → lesson 08, 'Step 5: when the check cannot run your code'",
        "  - [warning] inconsistent: Your P does not describe your errors at t = 1.6 s.",
        "    → lesson 08, 'The consistency test: NEES and its bounds' (exercise 2)",
        "  - [note] matches-optimal: Right on 10 runs.",
        "    → lesson 08, 'Step 3: fix and check again'"]
    assert "0.0016" not in text and "boom" not in text and "23.1" not in text


def test_the_first_look_names_the_exception_a_traceback_ends_with():
    """``raise NotImplementedError`` has no message: the first look said "the traceback ends
    with:" and nothing (red team, from the wheel).  It names the type; with no traceback to
    read, the clause goes."""
    intro = "kalman_filter(...) raised an exception on run 0; the traceback ends with:"
    tb = ('\n      File "/box/alice.py", line 2, in kalman_filter\n        raise '
          'NotImplementedError\n      NotImplementedError')
    cases = {tb: f"{intro[:-1]} NotImplementedError.",
             "\n      numpy.linalg.LinAlgError: Singular matrix":
                 f"{intro[:-1]} numpy.linalg.LinAlgError.",
             "": "kalman_filter(...) raised an exception on run 0.",
             "\n      not an exception line!": "kalman_filter(...) raised an exception on run 0."}
    for rest, want in cases.items():
        r = Report("alice.py")
        r.add("exception", text=intro + rest, where="run 0")
        lines = brief(batch.student_result(r)).splitlines()[1:-1]  # wrapped; the lesson last
        assert " ".join(line.strip() for line in lines) == f"- [error] exception: {want}"


def test_the_full_report_and_the_json_say_it_too():
    result = batch.student_result(_report())
    assert see("std-as-variance") in result["text"] and "ZeroDivisionError" in result["text"]
    f = result["findings"][0]
    assert f["taught"] == taught("std-as-variance").to_dict()
    assert f["taught"]["anchor"] == "report-003-variances-and-standard-deviations-mixed-up"
    assert "expected" not in f and "0.0016" not in str(result)
    assert batch.checker_error("x.py", "died")["findings"][0].get("taught") is None
    assert brief(batch.checker_error("x.py", "died")).splitlines()[1:] == [
        "  - [error] checker-error: died",
        "    → lesson 08, 'Step 5: when the check cannot run your code'"]


def _args(tmp_path, n: int, verbose: bool = False) -> argparse.Namespace:
    return argparse.Namespace(json=None, verbose=verbose, runs=None, seed=1, problem="calibration",
                              paths=[Path(f"s{i}.py") for i in range(n)])


#: What _check_report reads of the class run's plan (gpsaccel.classrun.checking.CheckPlan).
PLAN = SimpleNamespace(seed=1, seed_drawn=False, backend="bwrap", settings={})


def _report_out(args, results) -> int:
    return _check_report(args, Terminal(), results, PLAN, 1.0)


def test_one_file_gets_the_first_look_and_is_told_of_v(tmp_path, capsys):
    result = batch.student_result(_report("s0.py"))
    assert _report_out(_args(tmp_path, 1), [result]) == 1
    out = capsys.readouterr().out
    assert out.startswith(brief(result) + "\n")
    assert "gpsaccel check -v s0.py prints the whole report" in out
    assert "submission  passed" not in out and "boom" not in out
    assert "1 submission, problem calibration" in out
    assert _report_out(_args(tmp_path, 1, verbose=True), [result]) == 1
    out = capsys.readouterr().out
    assert "ZeroDivisionError" in out and "max |ΔP|/(σσ) = 23.1" in out


def test_a_note_carries_its_lesson_in_the_text_as_in_the_json():
    """A note (a correct filter's statistics) says where the course explains it, in the text as
    its JSON's ``taught`` does; it said so only in the JSON."""
    result = batch.student_result(_report())
    note = next(f for f in result["findings"] if f["severity"] == "note")
    assert note["taught"] == taught("matches-optimal").to_dict()
    line = "    → " + taught("matches-optimal").cite()
    for text in (result["text"], brief(result), _report().instructor_text()):
        lines = text.splitlines()
        at = next(i for i, ln in enumerate(lines) if "[note] matches-optimal" in ln)
        assert lines[at + 1] == line, lines[at:at + 2]


def test_a_class_gets_the_table_and_which_lesson_teaches_each_mistake(tmp_path, capsys):
    results = [batch.student_result(_report(f"s{i}.py")) for i in range(3)]
    ok = Report("s3.py")
    ok.add("matches-optimal", severity="note", text="Right.")
    busy = Report("s4.py")
    busy.add("machine-busy", text="Too busy.")
    results += [batch.student_result(ok), batch.student_result(busy)]
    assert _report_out(_args(tmp_path, 5), results) == 1
    out = capsys.readouterr().out
    assert "submission  passed" in out and "1 of 5 passed" in out
    assert "machine-busy`" not in out  # the machine's, no one's mistake
    assert "  3 submissions: `exception` → lesson 08, 'Step 5: when the check cannot run your " \
           "code'" in out
    assert "  3 submissions: `std-as-variance` → lesson 06, 'Report 003: variances and " \
           "standard deviations mixed up'" in out
    assert "inconsistent" not in out.split("mistakes, and where", 1)[1]  # a warning is none


def test_the_command_on_a_wrong_filter(capsys):
    """From the command line, in the sandbox: the first look names the mistake, where it shows
    (V₂₂) and the lesson, and never the variance it should be."""
    assert main(["check", str(SUBMISSIONS / "mutant_std_as_variance.py"), "--runs", "2",
                 "--seed", "0", "--workers", "1"]) == 1
    out = capsys.readouterr().out
    lines = out.splitlines()
    first = next(i for i, ln in enumerate(lines) if "[error] std-as-variance" in ln)
    assert any("V₂₂" in ln for ln in lines[first:first + 4]), out
    words = " ".join(out.split())  # the -v sentence is wrapped at 100 columns
    assert see("std-as-variance") in words and "mutant_std_as_variance.py prints the whole " \
        "report" in words and "gpsaccel check -v" in words
    assert "0.0016" not in out and "max |ΔP|" not in out


def test_the_graders_class_summary_names_where_each_mistake_is_taught():
    from gpsaccel.assignments.scoring import Grade
    from gpsaccel.classrun.writing import grade_mistakes

    possible = {"q1": 3.0, "q3": 3.0}
    grades = [Grade(s, "", {}, possible, "graded", codes={"q1": codes, "q3": ["nees-sum"]})
              for s, codes in (("a", ["phi-sign", "phi-sign"]), ("b", ["phi-sign"]),
                               ("c\x1b[2J", []))]
    assert grade_mistakes(grades) == [
        "q1: 2 students: `phi-sign` → lesson 02, 'The derivation' (exercise 5)",
        "q3: 3 students: `nees-sum` → lesson 08, 'The consistency test: NEES and its bounds' "
        "(exercise 2)"]
