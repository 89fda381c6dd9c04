"""How a value misses the one it should be, in words, without that value: the wording the lessons'
self-checks and the checker share ("about 4× too small", "has the wrong sign")."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: (upper bound of the ratio |answer|/|expected|, phrase): the rough size of a miss, as data.
#: A ratio above the last bound is named by its power of ten ("about 100×").
_SIZES: tuple[tuple[float, Callable[[float], str]], ...] = (
    (1.01, lambda r: "slightly (under 1 %) too {way}: more digits, or check the rounding"),
    (1.10, lambda r: "a few per cent too {way}"),
    (1.50, lambda r: "10–50 % too {way}"),
    (9.5, lambda r: f"about {round(r)}× too {{way}}"),
)


def describe_miss(answer: float, expected: float, *, typed: bool = True) -> str:
    """How ``answer`` misses ``expected``, without the expected value: sign, direction, size.

    ``typed``: the answer was typed by a student (a lesson's self-check), so a miss under 1 % is
    most likely its rounding; ``False`` for a value a program computed (the checker)."""
    if expected == 0:
        return "should be zero"
    if answer == 0:
        return "is zero, and should not be"
    if np.sign(answer) != np.sign(expected):
        return "has the wrong sign"
    r = abs(answer) / abs(expected)
    way = "large" if r > 1 else "small"
    r = max(r, 1 / r)
    for bound, phrase in _SIZES:
        if r <= bound:
            text = phrase(r).format(way=way)
            return text if typed else text.split(":")[0]
    return f"about 10^{round(math.log10(r))}× too {way} (units? a power of ten?)"
