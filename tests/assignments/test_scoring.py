"""Grading one notebook (:mod:`gpsaccel.assignments.scoring`): the calls its box makes."""

from __future__ import annotations

import numpy as np

from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments import scoring


def test_module_wrappers_survive_the_students_cells(tmp_path):
    from gpsaccel import sandbox as sb

    nb = nbm.Notebook([nbm.Cell(1, "import numpy as np\ndef f(a):\n    return a * 2"),
                       nbm.Cell(2, "raise SystemExit(1)"), nbm.Cell(3, "np = None\ng = 1")])
    reads = [nbm.Read("f", (np.arange(3.0),), ((3,),)), nbm.Read("h", (), ((),), value=True),
             nbm.Read("g", (np.arange(3.0),), ((3,),))]
    (tmp_path / "notebook.py").write_text(nbm.module_source(nb, reads), encoding="utf-8")
    sub = sb.load_submission(tmp_path / "notebook.py", "_gpsaccel_cell")
    box = sb.run(sub, scoring._calls(3, reads), sb.Limits(time=60), allow_gpsaccel=True)
    assert box.failure is None, box.detail
    from gpsaccel.assignments.questions import answer_from
    cells = [answer_from(r, 0) for r in box.results[:3]]
    assert [c.status for c in cells] == ["ok", "exception", "ok"] and "SystemExit" in \
        cells[1].message and "cell 2" in cells[1].message
    f, h, g = (answer_from(r, 1) for r in box.results[3:])
    assert f.status == "ok" and f.values[0].tolist() == [0.0, 2.0, 4.0]
    assert (h.status, g.status) == ("not-defined", "not-callable")


def test_a_grader_that_raises_costs_that_question_and_shows_the_student_only_its_type(tmp_path):
    """Both ways a question is graded (its answers, or the file the notebook writes) turn a bug of
    the grader into one ``grader-error`` finding: the instructor reads the exception, the student
    only its type (the exception's text may hold the expected value)."""
    from gpsaccel.assignments.questions import Draw, Question

    def broken(*args):
        raise ValueError("expected 4.25")

    q = Question("q1", 1.0, grade=broken, file="f.py", grade_file=broken)
    nb = nbm.Notebook([nbm.Cell(1, "%%writefile f.py\ndef f():\n    return 1\n")])
    for rep in (scoring._safe_grade(q, Draw(0), []), scoring._grade_file(q, nb, Draw(0), 5.0)):
        assert rep.codes == ["grader-error"]
        assert "ValueError: expected 4.25" in rep.instructor_text()
        student = str(rep.for_student())
        assert "ValueError" in student and "4.25" not in student


def test_a_file_that_does_not_import_is_named_by_its_error_in_the_feedback():
    """The feedback keeps one line a finding: the import-error's "the traceback ends with:" was
    cut there and ended the student's line above nothing (a notebook whose ``%%writefile`` had a
    syntax error read "...; the traceback ends with:"). It names the error's type, as
    ``gpsaccel check``'s first look does."""
    from gpsaccel import sandbox as sb
    from gpsaccel.check import findings
    from gpsaccel.check.report import Report

    calls = [sb.Call("kalman_filter", (np.zeros((2, 2)),), (sb.Output("x_hat", (2, 3)),))]
    box = sb.BoxResult("bwrap", failure="import-error", problem={
        "kind": "import-error", "traceback": '  File "kalman_filter.py", line 30\n'
                                             "    return xs Ps\n              ^^\n"
                                             "SyntaxError: invalid syntax\n"})
    report = Report("q2")
    findings.box_findings(report, box, calls, sb.Limits(time=60))
    assert report.codes == ["import-error"]
    g = scoring.Grade("s", "s.ipynb", {"q2": 0.0}, {"q2": 4.0}, "graded")
    line = next(ln for ln in scoring._feedback_text(g, [], {"q2": report}, {}).splitlines()
                if "import-error" in ln)
    assert line.endswith("(before kalman_filter is called); the traceback ends with "
                         "SyntaxError."), line


def test_a_file_written_in_parts_is_graded_whole_as_jupyter_wrote_it():
    """``%%writefile -a`` (or ``--append``) appends, as IPython's magic does: a student who
    writes the file question's file in two cells was graded on the last cell alone (an honest,
    working calibration q2 scored 0 / 4: "kalman_filter is not defined"), while the similarity
    record read the file whole; both now read it as the student's Jupyter wrote it."""
    from gpsaccel.assignments.answercode import written_files
    from gpsaccel.assignments.questions import Draw, Question

    seen = []

    def grade_file(path, draw, timeout):
        seen.append(path.read_text(encoding="utf-8"))
        return scoring.Report("q2")

    q = Question("q2", 4.0, file="f.py", grade_file=grade_file)
    cells = ["%%writefile f.py\nimport numpy as np\n", "x = 1",
             "%%writefile -a f.py\ndef f(z):\n    return z\n",
             "%%writefile --append  f.py\ndef g(z):\n    return 2 * z\n",
             "%%writefile other.py\ny = 2\n"]
    whole = "import numpy as np\ndef f(z):\n    return z\ndef g(z):\n    return 2 * z\n"
    nb = nbm.Notebook([nbm.Cell(i + 1, c) for i, c in enumerate(cells)])
    scoring._grade_file(q, nb, Draw(0), 5.0)
    assert seen == [whole]
    assert nb.writefile("f.py") == (nb.cells[3], whole)
    assert written_files(cells) == {"f.py": whole, "other.py": "y = 2\n"}
    # a later cell without -a writes the file anew
    nb.cells.append(nbm.Cell(6, "%%writefile f.py\nh = 3\n"))
    assert nb.writefile("f.py") == (nb.cells[5], "h = 3\n")
