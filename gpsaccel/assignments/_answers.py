"""Reading a student's answer safely and naming its wrong elements (shared by the homework checks).

Everything a student hands in is untrusted: a call may raise, return the wrong type or shape, NaN;
each becomes a :class:`~gpsaccel.check.report.Finding`, never an exception in the checker.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable

import numpy as np

from gpsaccel.check.report import Report

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")

#: Wrong elements listed in one finding (the rest are counted).
MAX_LISTED = 6


def element(name: str, idx: tuple[int, ...]) -> str:
    """Course notation, 1-based: A₁₃ (a 2-D index), r₂ (1-D)."""
    return name + "".join(str(i + 1) for i in idx).translate(_SUB)


def call(report: Report, what: str, func: object, *args: object) -> object | None:
    """``func(*args)``, or None with a finding (not defined, not callable, raised, returned
    nothing)."""
    if func is None or func is Ellipsis:
        report.add("not-defined", f"{what} is not defined yet (or still `...`).")
        return None
    if not callable(func):
        report.add("not-defined", f"{what} must be a function; it is a {type(func).__name__}.")
        return None
    try:
        out = func(*args)
    except Exception as exc:  # noqa: BLE001 - the student's code may raise anything
        tb = traceback.format_exception_only(type(exc), exc)[-1].strip()
        report.add("exception", f"{what} raised {tb}")
        return None
    if out is None:
        report.add("returns-none", f"{what} returned None: end it with a return statement.")
    return out


def array(report: Report, name: str, value: object, shape: tuple[int, ...]) -> np.ndarray | None:
    """``value`` as a finite float array of ``shape``, or None with a finding."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        report.add("not-a-matrix", f"{name} must be an array of numbers; np.array({name}, "
                   f"dtype=float) fails: {exc}")
        return None
    if arr.shape != shape:
        report.add("shape", f"{name} has shape {arr.shape}; it must be {shape}.")
        return None
    if not np.isfinite(arr).all():
        report.add("not-finite", f"{name} contains NaN or inf.")
        return None
    return arr


def wrong(actual: np.ndarray, expected: np.ndarray, rtol: float, atol: float) -> np.ndarray:
    """Boolean mask of the elements outside ``|a − e| ≤ atol + rtol·|e|``."""
    return ~(np.abs(actual - expected) <= atol + rtol * np.abs(expected))


def compare(report: Report, name: str, actual: np.ndarray, expected: np.ndarray, rtol: float,
            atol: float, where: str, code: str, meaning: Callable[[tuple[int, ...]], str]
            | None = None, sign_code: str | None = None) -> bool:
    """One finding listing the wrong elements of ``actual`` (True when all are right).

    ``sign_code``: when every wrong element is the expected one with its sign flipped, the finding
    gets this code instead of ``code``.
    """
    bad = wrong(actual, expected, rtol, atol)
    if not bad.any():
        return True
    idx = [tuple(int(i) for i in ix) for ix in zip(*np.nonzero(bad), strict=True)]
    flipped = sign_code is not None and not wrong(actual[bad], -expected[bad], rtol, atol).any()
    parts = []
    for ix in idx[:MAX_LISTED]:
        label = element(name, ix) + (f" ({meaning(ix)})" if meaning else "")
        parts.append(f"{label} = {actual[ix]:.6g}, should be {expected[ix]:.6g}")
    more = f" (and {len(idx) - MAX_LISTED} more)" if len(idx) > MAX_LISTED else ""
    text = "; ".join(parts) + more + f" {where}."
    if flipped:
        text = "wrong sign: " + text
    report.add(sign_code if flipped else code, text)
    return False


def assert_report(report: Report) -> Report:
    """For a test cell: AssertionError with the findings when the report fails."""
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
