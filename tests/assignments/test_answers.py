"""gpsaccel/assignments/_answers.py: reading a student's answer safely."""

from __future__ import annotations

import numpy as np

from gpsaccel.assignments._answers import call
from gpsaccel.assignments.notebook import Read
from gpsaccel.assignments.questions import Answer, replay
from gpsaccel.check.report import Report


def test_a_replayed_function_that_raised_is_told_in_the_students_terms():
    """A question's grade calls the student's function back through :func:`replay`, which raises
    the box's account of the call: the finding showed the grader's exception class
    ("average_nees(...) raised gpsaccel.assignments.questions.StudentError: cell 14, line 3:
    NameError: ..."), tried from the wheel with a notebook whose ``import numpy`` failed. It
    names the student's error and where, and nothing of the grader."""
    x = np.zeros(2)
    for answer, said in ((Answer("exception", "cell 14, line 3: NameError: name 'np' is not "
                                 "defined"),
                          "f(x) failed: cell 14, line 3: NameError: name 'np' is not defined"),
                         (Answer("not-run"), "f(x) failed: it did not return: the notebook "
                                             "stopped before (see above)")):
        report = Report("q3")
        f = replay([Read("f", (x,), ((2,),))], [answer], "f")
        assert call(report, "f(x)", f, x) is None and report.codes == ["exception"]
        text = report.for_student().findings[0].message
        assert text == said and "gpsaccel" not in text and "StudentError" not in text, text


def test_a_function_that_raises_is_named_with_its_exception():
    report = Report("q")
    assert call(report, "f(x)", lambda x: 1 / x, 0) is None
    assert report.for_student().findings[0].message == \
        "f(x) raised ZeroDivisionError: division by zero"
