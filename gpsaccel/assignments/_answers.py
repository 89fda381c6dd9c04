"""Reading a student's answer safely (shared by the homework checks).

Everything a student hands in is untrusted: a call may raise, return the wrong type or shape, NaN;
each becomes a :class:`~gpsaccel.check.report.Finding`, never an exception in the checker.
"""

from __future__ import annotations

import traceback
from typing import Any

import numpy as np

from gpsaccel.assignments.questions import StudentError
from gpsaccel.check.report import Report, as_array


def call(report: Report, what: str, func: object, *args: object, part: str = "") -> Any:
    """``func(*args)`` (whatever the student's function returned), or None with a finding (not
    defined, not callable, raised, returned nothing) about ``what`` (of ``part``: partial
    credit).

    Examples
    --------
    >>> from gpsaccel.check.report import Report
    >>> report = Report("q")
    >>> call(report, "f(x)", lambda x: 1 / x, 0) is None, report.codes
    (True, ['exception'])
    """
    if func is None or func is Ellipsis:
        report.add("not-defined", text="{where} is not defined yet (or still `...`).",
                   where=what, part=part)
        return None
    if not callable(func):
        report.add("not-defined", text="{where} must be a function; it is a {type}.", where=what,
                   observed={"type": type(func).__name__}, part=part)
        return None
    try:
        out = func(*args)
    except StudentError as exc:  # a replay: the box's account of the call, in words already
        report.add("exception", text="{where} failed: {error}", where=what,
                   observed={"error": str(exc)}, part=part)
        return None
    except Exception as exc:  # noqa: BLE001 - the student's code may raise anything
        tb = traceback.format_exception_only(type(exc), exc)[-1].strip()
        report.add("exception", text="{where} raised {error}", where=what,
                   observed={"error": tb}, part=part)
        return None
    if out is None:
        report.add("returns-none", text="{where} returned None: end it with a return "
                   "statement.", where=what, part=part)
    return out


def array(report: Report, name: str, value: object, shape: tuple[int, ...]) -> np.ndarray | None:
    """``value`` as a finite float array of ``shape``, or None with a finding
    (:func:`gpsaccel.check.report.as_array`)."""
    return as_array(report, name, value, shape)


def assert_report(report: Report) -> Report:
    """For a test cell: AssertionError with the findings when the report fails."""
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
