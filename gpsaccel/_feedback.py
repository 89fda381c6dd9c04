"""How a value misses the one it should be, in words, without that value: the wording the lessons'
self-checks and the checker share ("about 4× too small", "has the wrong sign").

Two steps, so that the words cannot carry the expected value: :func:`classify` compares the
answer with the expected value and keeps only a :class:`Miss` (which way, and a size class from
:data:`_SIZES`, never a number of the expected value); :func:`render` is the student's renderer
of a miss and receives the :class:`Miss` alone.  :func:`describe_miss` is the two together.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: (upper bound of the ratio |answer|/|expected|, phrase): the rough size of a miss, as data.
#: A ratio above the last bound is named by its power of ten ("about 100×").
_SIZES: tuple[tuple[float, Callable[[float], str]], ...] = (
    (1.01, lambda r: "slightly (under 1 %) too {way}: more digits, or check the rounding"),
    (1.10, lambda r: "a few per cent too {way}"),
    (1.50, lambda r: "10–50 % too {way}"),
    (9.5, lambda r: f"about {round(r)}× too {{way}}"),
)

#: kind -> the student's words (a :class:`Miss` of kind "size" is worded by :data:`_SIZES`).
_KINDS = {"zero-expected": "should be zero", "zero": "is zero, and should not be",
          "sign": "has the wrong sign",
          "overflow": "is so far off that its ratio to the right value overflows (it runs away)"}


@dataclass(frozen=True)
class Miss:
    """How an answer misses, as data: ``kind`` ("zero-expected", "zero", "sign", "size", or
    "overflow": the ratio is beyond floating point), ``way`` ("large"/"small") and ``size`` (the
    index in :data:`_SIZES`, or the rounded power of ten of the ratio beyond them, as a negative
    ``-power``)."""

    kind: str
    way: str = ""
    size: int = 0


def classify(answer: float, expected: float) -> Miss:
    """The :class:`Miss` of ``answer`` against ``expected`` (which it does not keep)."""
    if expected == 0:
        return Miss("zero-expected")
    if answer == 0:
        return Miss("zero")
    if np.sign(answer) != np.sign(expected):
        return Miss("sign")
    with np.errstate(over="ignore", divide="ignore"):
        r = abs(answer) / abs(expected)
    if not math.isfinite(r) or r == 0:
        return Miss("overflow")
    way = "large" if r > 1 else "small"
    r = max(r, 1 / r)
    for i, (bound, _) in enumerate(_SIZES):
        if r <= bound:
            return Miss("size", way, i if i < len(_SIZES) - 1 else 100 + round(r))
    return Miss("size", way, -round(math.log10(r)))


def render(miss: Miss, *, typed: bool = True) -> str:
    """The student's words for ``miss`` (``typed``: see :func:`describe_miss`)."""
    if miss.kind != "size":
        return _KINDS[miss.kind]
    if miss.size < 0:
        return f"about 10^{-miss.size}× too {miss.way} (units? a power of ten?)"
    if miss.size >= 100:  # the "about N×" class keeps its rounded factor
        text = _SIZES[-1][1](float(miss.size - 100)).format(way=miss.way)
    else:
        text = _SIZES[miss.size][1](0.0).format(way=miss.way)
    return text if typed else text.split(":")[0]


def describe_miss(answer: float, expected: float, *, typed: bool = True) -> str:
    """How ``answer`` misses ``expected``, without the expected value: sign, direction, size.

    ``typed``: the answer was typed by a student (a lesson's self-check), so a miss under 1 % is
    most likely its rounding; ``False`` for a value a program computed (the checker)."""
    return render(classify(answer, expected), typed=typed)
