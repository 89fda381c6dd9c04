"""The lessons' self-checks: right or wrong, the direction and rough size of a miss, a hint.

A student's check cell is one line, ``self_check("03.1", answer_1, hint="...")``.  The expected value
is never printed and is not in the notebook: it sits in :mod:`gpsaccel.exercises.answers`, written
by ``python -m gpsaccel.lessons measure`` from the master's own solution (the value the solution
assigns to ``answer_…``), so the check and the solution cannot disagree.  Every checked answer is
deterministic (seeded, independent of ``GPSACCEL_LESSON_RUNS``); the tests run the solutions and
require ✓ under every check.

Tolerance: an answer is right when it agrees with the expected value to ``digits`` significant
digits (3 unless the lesson says otherwise), i.e. the rounding a lesson prints is accepted:
``|a − e| ≤ ½·10^(⌊log₁₀|e|⌋ − digits + 1)``.  An expected integer (a count) must be matched exactly.
"""

from __future__ import annotations

import json
import os
import textwrap

import numpy as np

from gpsaccel._feedback import describe_miss
from gpsaccel._taught import taught

#: When set (by ``python -m gpsaccel.lessons measure``), :func:`self_check` appends each key and the
#: answer it was given to this JSON-lines file instead of checking it.
RECORD_VARIABLE = "GPSACCEL_RECORD_ANSWERS"

#: The width a self-check's verdict is wrapped at: a hint on one long line made JupyterLab's output
#: area scroll sideways at 1400 px; continuation lines are indented two spaces.
WIDTH = 88

def _expected(key: str):
    from gpsaccel.exercises.answers import ANSWERS

    if key not in ANSWERS:
        raise KeyError(f"check: no recorded answer for exercise {key!r} "
                       "(run `python -m gpsaccel.lessons measure` on its lesson)")
    return ANSWERS[key]


def tolerance(expected: np.ndarray, digits: int = 3) -> np.ndarray:
    """Half a unit in the ``digits``-th significant digit of each expected value (0 → 0)."""
    e = np.abs(np.asarray(expected, dtype=float))
    with np.errstate(divide="ignore"):
        exponent = np.where(e > 0, np.floor(np.log10(np.where(e > 0, e, 1.0))), 0.0)
    return np.where(e > 0, 0.5 * 10.0 ** (exponent - digits + 1) * (1 + 1e-9), 0.0)


def self_check(key: str, answer, *, hint: str = "", name: str | None = None, digits: int = 3) -> None:
    """Print whether ``answer`` is right for exercise ``key`` (``"NN.k"``); returns nothing.

    ✓ when it agrees to ``digits`` significant digits (a count exactly); otherwise ✗ with what is
    wrong (shape, sign, direction and rough size), ``hint`` and the lesson section to read again
    (:mod:`gpsaccel._taught`), never the expected value.
    """
    label = name or f"exercise {key}"
    record = os.environ.get(RECORD_VARIABLE)
    if record:
        value = np.asarray(answer).tolist() if answer is not None else None
        with open(record, "a", encoding="utf-8") as f:
            f.write(json.dumps({"key": key, "value": value, "digits": digits}) + "\n")
        print(f"(recorded the answer of {label})")
        return
    line = _verdict(label, answer, _expected(key), hint, digits)
    section = taught(key)
    if line.startswith("✗") and section is not None:
        line += ("" if line.endswith(".") else ".") + f" Read again: {section.cite()}."
    print(wrapped(line))


def wrapped(line: str, width: int = WIDTH) -> str:
    """``line`` broken at spaces into lines of at most ``width`` characters (a word longer than
    that, e.g. a path, stays whole), the continuation lines indented by two spaces."""
    return textwrap.fill(line, width=width, subsequent_indent="  ", break_long_words=False,
                         break_on_hyphens=False)


def _verdict(label: str, answer, expected, hint: str, digits: int) -> str:
    """The verdict :func:`self_check` prints (on one line, before :func:`wrapped`)."""
    if answer is None:
        return f"… {label}: not answered yet (replace the None with your answer, then run this cell)"
    try:
        a = np.asarray(answer, dtype=float)
    except (TypeError, ValueError):
        return f"✗ {label}: expected a number or an array of numbers, got {type(answer).__name__}"
    e = np.asarray(expected, dtype=float)
    if a.shape != e.shape:
        what = "a single number" if e.ndim == 0 else f"an array of shape {e.shape}"
        return f"✗ {label}: your answer has shape {a.shape}; the exercise asks for {what}"
    if not np.all(np.isfinite(a)):
        return f"✗ {label}: your answer contains NaN or inf"
    integer = np.issubdtype(np.asarray(expected).dtype, np.integer)
    wrong = (a != e) if integer else (np.abs(a - e) > tolerance(e, digits))
    tail = f" Hint: {hint}" if hint else ""
    if not wrong.any():
        return f"✓ {label}: right"
    if integer and e.ndim == 0:
        return f"✗ {label}: not this count ({'too many' if a > e else 'too few'}).{tail}"
    if e.ndim == 0:
        return f"✗ {label}: {describe_miss(float(a), float(e))}.{tail}"
    first = tuple(int(i) for i in np.argwhere(wrong)[0])
    return (f"✗ {label}: {int(wrong.sum())} of {a.size} entries wrong; the first, at {first}, "
            f"{describe_miss(float(a[first]), float(e[first]))}.{tail}")
