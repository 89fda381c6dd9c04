"""Per-student variants: a student's number (an HMAC of their id) -> their own numbers.

A homework's variant space is a grid of values per parameter (``axes``); a student's number picks
one point of it, mixed-radix, never the public notebook's point (a student with the public
numbers could hand in the worked public answer).  With |space| points and n students the expected
number of pairs sharing a variant is n(n − 1)/2 / (|space| − 1) (:func:`expected_shared_pairs`):
each homework's grid is chosen so that this is small for a class of 200 (docs/grading.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence


def size(axes: Mapping[str, Sequence]) -> int:
    """Points of the grid ``axes`` (name -> values)."""
    n = 1
    for values in axes.values():
        n *= len(values)
    return n


def pick(number: int, axes: Mapping[str, Sequence], public: Mapping[str, object]) -> dict:
    """The point of ``axes`` for a student's ``number`` (>= 0), skipping the ``public`` point
    (when it lies on the grid): every student's numbers differ from the public notebook's."""
    total = size(axes)
    index = [list(values).index(public[k]) if public.get(k) in values else None
             for k, values in axes.items()]
    on_grid = None not in index
    k = number % (total - 1 if on_grid else total)
    if on_grid:
        skip, stride = 0, 1
        for i, values in zip(index, axes.values(), strict=True):
            assert i is not None
            skip += i * stride
            stride *= len(values)
        k += k >= skip
    out = {}
    for name, values in axes.items():
        k, r = divmod(k, len(values))
        out[name] = values[r]
    return out


def expected_shared_pairs(n_students: int, points: int) -> float:
    """Expected pairs of students with the same variant: n(n − 1)/2 / points (uniform picks)."""
    return n_students * (n_students - 1) / 2 / points
