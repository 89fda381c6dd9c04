r"""The one mechanism for a known mistake, in every system: an entry that changes ingredients.

Every system describes its filter by the ingredients a student chooses (a frozen dataclass: the
calibration's and any linear model's :class:`~gpsaccel.kalman.linear_model.LinearIngredients`,
the ship's update switches, the coop EKF's :class:`gpsaccel.coop.filters.Ingredients`), and
each known mistake as a :class:`Mistake`: its code, a title (``variant``), the instructor's
message, the hint said only when the evidence is this mistake, and the ingredients it changes.
:func:`with_changes` applies the changes; the system's one filter runs the result.  A system's
catalogue is a tuple of these, and the checker, the lessons and the homework read that one tuple.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from gpsaccel.kalman.epochs import EpochFilter


@dataclass(frozen=True)
class Mistake:
    """One entry of a catalogue.

    code : the stable code students and instructors see (``"phi-sign"``).
    variant : which form of the mistake (``"V[2,2] = 0.04"``); a code can have several.
    message : what is wrong, what it should be and the likely cause, for the student.
    changes : the ingredients it changes, ``(field, value)`` or ``(field, (row, col), value)``.
    hint : where to look, said only when the evidence is this mistake (may be empty).
    alone : True for an entry matched only on its own, never combined with others (its filter
        has its own loop: update-every-step).
    kinds : the filters of the system it applies to (coop: ``"ekf"``, ``"lkf"``; the ship:
        ``"filter"``, ``"update"``); empty: every one.
    informational : a finding of it is a note (the filter is right, written less robustly).
    checker : False for an entry only the homework tries (its question's contract differs).
    homework : True for an entry the homework names (in catalogue order).

    Every system's catalogue (calibration, ship, coop, any linear model) is a tuple of these:
    the checker, the lessons and the homework read the same entries.
    """

    code: str
    variant: str
    message: str
    changes: tuple[tuple, ...]
    hint: str = ""
    alone: bool = False
    kinds: tuple[str, ...] = ()
    informational: bool = False
    checker: bool = True
    homework: bool = False

    @property
    def title(self) -> str:
        """The entry's title: which form of the mistake (its ``variant``)."""
        return self.variant

    def applies(self, kind: str) -> bool:
        """Whether the entry is a mistake of the filter ``kind``."""
        return not self.kinds or kind in self.kinds

    @property
    def touches(self) -> frozenset:
        """The ingredients (and elements) it changes; mistakes that share one do not combine."""
        return frozenset(c[0] if len(c) == 2 else (c[0], c[1]) for c in self.changes)

    def __str__(self) -> str:
        return f"{self.code} ({self.variant})"


def combinations(mistakes: Sequence[Mistake], size: int) -> Iterator[tuple[Mistake, ...]]:
    """All ``size``-tuples of ``mistakes`` that touch disjoint ingredients (so they can co-occur)."""
    for combo in itertools.combinations(mistakes, size):
        if size > 1 and any(m.alone for m in combo):
            continue
        touched = [m.touches for m in combo]
        if all(a.isdisjoint(b) for a, b in itertools.combinations(touched, 2)):
            yield combo


def with_changes(ingredients: Any, changes: tuple[tuple, ...]) -> Any:
    """A copy of the dataclass ``ingredients`` with ``(field, value)`` or ``(field, (row, col),
    value)`` changes applied (see :class:`Mistake`)."""
    kw: dict[str, object] = {}
    for change in changes:
        if len(change) == 2:
            kw[change[0]] = change[1]
        else:
            name, idx, value = change
            arr = np.array(kw.get(name, getattr(ingredients, name)), dtype=float)
            arr[idx] = value
            kw[name] = arr
    return replace(ingredients, **kw)


def apply(ingredients: Any, mistakes: Iterable[Mistake]) -> Any:
    """The ingredients of a filter that makes ``mistakes``: every entry's changes in turn."""
    for m in mistakes:
        ingredients = with_changes(ingredients, m.changes)
    return ingredients


class Catalogue(Protocol):
    """What the diagnosis of a linear filter needs from a system's catalogue of mistakes."""

    def covariance_mistakes(self) -> tuple[Mistake, ...]:
        """Mistakes that change P (and, through the gains, x̂)."""
        ...

    def mean_mistakes(self) -> tuple[Mistake, ...]:
        """Mistakes that change only x̂."""
        ...

    def build(self, mistakes: tuple[Mistake, ...] = ()) -> EpochFilter:
        """The epoch filter that makes ``mistakes`` (none: the optimal filter)."""
        ...
