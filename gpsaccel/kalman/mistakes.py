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


@dataclass(frozen=True, eq=False)
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
    where : where the mistake shows in the student's output, for an entry that always shows in
        the same place ("every measurement time", "the last epoch (t = 20 s)"); "" otherwise.
    combined : the largest combination of entries it is matched in (3 for the entries a report
        combines, 2 for the ideas every system shares: the candidates a linear diagnosis builds
        grow as the cube of the entries otherwise).

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
    where: str = ""
    combined: int = 3

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

    @property
    def fields(self) -> frozenset:
        """The ingredients it changes, whole or in part (an element's field too)."""
        return frozenset(c[0] for c in self.changes)

    def overlaps(self, other: Mistake) -> bool:
        """Whether the two change a same ingredient: the same element, or one changes a field
        whole that the other changes in part (M0 × 10 and M0₁₁ = σ do not combine)."""
        whole = {c[0] for c in self.changes if len(c) == 2}
        other_whole = {c[0] for c in other.changes if len(c) == 2}
        return bool(self.touches & other.touches or whole & other.fields
                    or other_whole & self.fields)

    def __str__(self) -> str:
        return f"{self.code} ({self.variant})"

    def _key(self) -> tuple:
        return (self.code, self.variant, self.message, self.kinds)

    def __eq__(self, other: object) -> bool:
        """Two entries are the same mistake when code, title, message and filters agree (their
        changes may hold arrays, which do not compare to one truth value)."""
        return isinstance(other, Mistake) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


def combinations(mistakes: Sequence[Mistake], size: int) -> Iterator[tuple[Mistake, ...]]:
    """All ``size``-tuples of ``mistakes`` that change disjoint ingredients (so they can co-occur:
    :meth:`Mistake.overlaps`), of entries that are matched in combinations that large
    (:attr:`Mistake.combined`; never an ``alone`` one)."""
    if size > 1:
        mistakes = [m for m in mistakes if not m.alone and m.combined >= size]
    index = {id(m): i for i, m in enumerate(mistakes)}
    clash = [[a.overlaps(b) for b in mistakes] for a in mistakes]   # each pair once
    for combo in itertools.combinations(mistakes, size):
        idx = [index[id(m)] for m in combo]
        if not any(clash[a][b] for a, b in itertools.combinations(idx, 2)):
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
