r"""What a graded question is: what it reads from the box, and how the grader scores it outside.

A :class:`Question` never runs in the student's box.  Its :attr:`~Question.reads` say what to
bring back (functions to call on data drawn from the grading run's seed, variables to read); the
box returns, for each read, an :class:`Answer`: a status (the student's function was missing,
raised, returned the wrong shape ...) and arrays of exactly the declared shapes.  Only after the
box is empty does :attr:`~Question.grade` compute the reference and compare, with the checkers of
:mod:`gpsaccel.check` or the homework's own, to which the answers are handed as :func:`replay`
functions (they return what the student's function returned on those arguments, and refuse any
other call).

Fresh data.  Every draw comes from :class:`Draw`: ``seed`` (the grading run's, mixed with the
question's name and the student's id, so no two students get the same data and nothing a
classmate's box saw is of use) and ``variant`` (the student's own numbers, from
:func:`variant_number`: an HMAC of the student's id under the instructor's secret).
"""

from __future__ import annotations

import hashlib
import hmac
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from gpsaccel._untrusted import clean
from gpsaccel.assignments.notebook import MAX_NDIM, STATUSES, Read
from gpsaccel.check.report import Report


@dataclass(frozen=True)
class Draw:
    """The randomness of one question for one student: ``seed`` (fresh data; never shown to the
    student) and ``variant`` (the student's numbers; shown to them in their notebook).

    Examples
    --------
    >>> draw = Draw(seed=7, variant={"sigma_a": 0.3})
    >>> x = draw.rng().normal(size=4)     # the same numbers for the box's read and the grade
    """

    seed: int
    variant: dict = field(default_factory=dict)

    def rng(self) -> np.random.Generator:
        return np.random.default_rng(self.seed)


@dataclass(frozen=True)
class Answer:
    """What the box returned for one read.

    status : one of :data:`gpsaccel.assignments.notebook.STATUSES`, or ``not-run`` (the box
        stopped before this read: a timeout, a crash, a limit).
    message : the student's exception text (``exception``, ``not-a-matrix``), sanitised.
    values : the declared arrays (only when status is ``ok``).
    which : for ``shape``/``not-a-matrix``, which output of a tuple was wrong.
    shape : for ``shape``, what the student returned.
    """

    status: str
    message: str = ""
    values: tuple[np.ndarray, ...] = ()
    which: int = -1
    shape: tuple[int, ...] | None = None


def answer_from(result: dict[str, np.ndarray] | None, n_outputs: int) -> Answer:
    """An :class:`Answer` from one call's frames (None: the call never came back)."""
    if result is None:
        return Answer("not-run")
    status = result["status"]
    code = int(status[0])
    name = STATUSES[code] if 0 <= code < len(STATUSES) else "exception"
    message = text(result["message"])
    if name != "ok":
        ndim = int(status[2])
        shape = tuple(int(s) for s in status[3:3 + ndim]) if 0 < ndim <= MAX_NDIM else None
        return Answer(name, message, (), int(status[1]), shape if name == "shape" else None)
    return Answer("ok", message, tuple(result[f"out{k}"] for k in range(n_outputs)))


def text(data: np.ndarray) -> str:
    """A message array from the box as printable text (NUL-padded UTF-8; control, bidi and
    zero-width characters dropped: :func:`gpsaccel._untrusted.clean`)."""
    raw = bytes(np.asarray(data, dtype=np.uint8)).split(b"\0", 1)[0]
    return clean(raw.decode("utf-8", errors="replace"))[:300]


class StudentError(Exception):
    """Raised by a :func:`replay` where the student's function raised (its text is the message)."""


def replay(reads: list[Read], answers: list[Answer], name: str, pick: int | None = None
           ) -> Callable | None:
    """A stand-in for the student's function ``name``: called with the arguments of one of its
    reads, it gives back what the box returned for that read (output ``pick`` of a tuple, or all).

    None when the student did not define it (the checkers report that as not defined).  A call
    with arguments no read had is a bug of the grader: RuntimeError.

    Examples
    --------
    In a question's grade, with the reads it declared::

        predict = replay(reads, answers, "predict")
        out = call(report, "predict(x, P)", predict, x, P)   # None, with a finding, if it failed
    """
    mine = [(r, a) for r, a in zip(reads, answers, strict=True) if r.name == name]
    if mine and all(a.status == "not-defined" for _, a in mine):
        return None

    def stand_in(*args: object) -> object:
        arrays = [np.asarray(a, dtype=float) for a in args]
        for r, a in mine:
            if len(r.args) == len(arrays) and all(
                    x.shape == np.shape(y) and np.array_equal(x, y, equal_nan=True)
                    for x, y in zip(arrays, r.args, strict=True)):
                return _give(a, pick, r, name)
        raise RuntimeError(f"grader bug: {name} was called with arguments no read of the box "
                           f"had")

    return stand_in


def _give(a: Answer, pick: int | None, r: Read, name: str) -> object:
    if a.status == "ok":
        return a.values[pick] if pick is not None else (
            a.values[0] if len(a.values) == 1 else tuple(a.values))
    if a.status == "returns-none":
        return None
    if a.status == "shape":
        bad = np.full(bounded(a.shape or (0,), r.shapes[max(a.which, 0) % len(r.shapes)]),
                      np.nan)
        if len(r.shapes) == 1:
            return bad
        out = [np.zeros(s) for s in r.shapes]
        out[a.which] = bad
        return out[pick] if pick is not None else tuple(out)
    if a.status == "return-value":
        return a.message or "something else"
    if a.status == "not-run":
        raise StudentError("it did not return: the notebook stopped before (see above)")
    raise StudentError(a.message or f"{name} could not be called ({a.status})")


#: How many times the declared size a wrong shape from the box may be allocated at (at least
#: :data:`MIN_ELEMENTS` elements): a shape is only a status the box declares, any size.
SHAPE_FACTOR = 16
MIN_ELEMENTS = 1 << 16


def bounded(shape: tuple[int, ...], declared: tuple[int, ...]) -> tuple[int, ...]:
    """``shape`` (what the box says the student returned) cut down, before anything is
    allocated, to at most :data:`SHAPE_FACTOR` times the ``declared`` shape's size (at least
    :data:`MIN_ELEMENTS`): each size clipped to ``[0, limit]``, then the trailing ones halved
    until the product fits.  An honest wrong shape within that is kept as it is."""
    limit = max(SHAPE_FACTOR * math.prod(declared), MIN_ELEMENTS)
    out = [min(max(int(d), 0), limit) for d in shape[:MAX_NDIM]]
    k = len(out) - 1
    while math.prod(out) > limit and k >= 0:
        out[k] = max(out[k] // 2, 1) if out[k] > 1 else out[k]
        k = k - 1 if out[k] <= 1 else k
    return tuple(out)


def value(report: Report, name: str, a: Answer, part: str = "") -> np.ndarray | None:
    """The variable ``name`` the box read, or None with a finding (not defined, wrong shape,
    not numbers) of ``part`` (partial credit).

    Examples
    --------
    In a question's grade, one answer per read::

        V = value(report, "V", answers[0], part="V")   # None: the finding is in the report
    """
    if a.status == "ok":
        return a.values[0]
    if a.status in ("not-defined", "not-run"):
        report.add("not-defined", text="{where} is not defined (or still `...`) after the "
                   "notebook has run.", where=name, part=part)
    elif a.status == "shape":
        report.add("shape", text="{where} has shape {shape}; see the question for its shape.",
                   where=name, observed={"shape": a.shape}, part=part)
    else:
        report.add("not-a-matrix", text="{where} must be numbers; np.array({where}, "
                   "dtype=float) fails ({error}).", where=name, observed={"error": a.message},
                   part=part)
    return None


@dataclass(frozen=True)
class Question:
    """One graded question of a homework.

    name, points : as in the master's ``# BEGIN QUESTION`` cell.
    parts : the separately gradable parts of the question (two functions, several matrices) with
        their points, ``{part: points}`` or ``((part, points), ...)``, adding up to ``points``:
        :meth:`score` gives each part's points when no error of the report
        (:attr:`gpsaccel.check.report.Finding.part`) concerns that part.  Empty: all or nothing.
    credit : mistake code -> the fraction (0 to 1) of a part's points it keeps when every error
        of that part is a mistake of these codes (a recognised slip, such as
        ``{"std-as-variance": 0.5}``: half the part for σ where σ² belongs).  The catalogue names
        the mistake; the instructor decides what it is worth.  Without parts, the question is
        one part.  Empty: a part with an error keeps nothing.
    reads : the reads for a draw (empty for a file question).
    grade : the report from the draw and the answers (run outside the box, after it is empty).
    file : a question graded from the file the notebook writes with ``%%writefile FILE`` (its
        text, read from the notebook, runs in a box of its own without gpsaccel); then
        ``grade_file(path, draw, timeout)`` gives the report.

    Examples
    --------
    >>> q = Question("q3", 2, parts={"x_bar": 1, "M": 1}, credit={"process-noise-interval": 0.5})
    >>> report = Report("q3")
    >>> _ = report.add("process-noise-interval", text="M adds one step's noise.", part="M")
    >>> q.score(report)                   # x̄ right (1), M a credited slip (0.5 · 1)
    1.5
    """

    name: str
    points: float
    reads: Callable[[Draw], list[Read]] = lambda draw: []
    grade: Callable[[Draw, list[Answer]], Report] | None = None
    file: str | None = None
    grade_file: Callable[..., Report] | None = None
    parts: tuple[tuple[str, float], ...] | Mapping[str, float] = ()
    credit: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        parts = tuple((str(n), float(p)) for n, p in (
            self.parts.items() if isinstance(self.parts, Mapping) else self.parts))
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "credit", dict(self.credit))
        if parts and not math.isclose(sum(p for _, p in parts), self.points):
            raise ValueError(f"parts of {self.name} must add up to its {self.points:g} points, "
                             f"got {parts}")
        if len({n for n, _ in parts}) != len(parts):
            raise ValueError(f"parts of {self.name} must have distinct names, got {parts}")
        if any(p < 0 for _, p in parts):
            raise ValueError(f"parts of {self.name} must have points >= 0, got {parts}")
        bad = {c: f for c, f in self.credit.items()
               if not isinstance(c, str) or not 0.0 <= float(f) <= 1.0}
        if bad:
            raise ValueError(f"credit of {self.name} maps mistake codes to fractions between 0 "
                             f"and 1, got {bad}")

    def score(self, report: Report) -> float:
        """The points ``report`` earns: all of them when it passes; with :attr:`parts`, the
        points of every part without an error, and :attr:`credit`'s fraction of a part whose
        errors are all credited mistakes; none when an error concerns the whole question (a
        finding without a part, or of a part not declared)."""
        if report.passed:
            return float(self.points)
        codes: dict[str, set[str]] = {}
        for f in report.findings:
            if f.severity == "error":
                codes.setdefault(f.part if self.parts else "", set()).add(f.code)
        parts = cast("tuple[tuple[str, float], ...]", self.parts) or (("", float(self.points)),)
        names = {n for n, _ in parts}
        if not codes.keys() <= names:
            return 0.0
        return float(sum(p * self._kept(codes.get(n, set())) for n, p in parts))

    def _kept(self, codes: set[str]) -> float:
        """The fraction of a part kept with errors of ``codes`` (1 without any)."""
        return min((float(self.credit.get(c, 0.0)) for c in codes), default=1.0)


def variant_number(secret: bytes, assignment: str, student: str) -> int:
    """The student's variant: HMAC-SHA256(secret, assignment ␀ student id), as a 63-bit integer.

    Without the secret nobody can derive anyone's variant; with it, the instructor always gets
    the same one for the same student.
    """
    key = f"{assignment}\0{student}".encode("utf-8", "surrogateescape")  # any name's bytes
    mac = hmac.new(secret, key, hashlib.sha256).digest()
    return int.from_bytes(mac[:8], "big") >> 1


def question_seed(seed: int, assignment: str, question: str, student: str) -> int:
    """The seed of one question's fresh data for one student, from the grading run's seed."""
    key = f"{seed}\0{assignment}\0{question}\0{student}".encode("utf-8", "surrogateescape")
    digest = hashlib.sha256(key).digest()
    return int.from_bytes(digest[:8], "big") >> 1
