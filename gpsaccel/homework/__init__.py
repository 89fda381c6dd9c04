r"""Your own homework: everything its ``graded.py`` needs, in one public module.

A homework of your own is a folder named after it, ``NAME/``, holding

* ``NAME.ipynb``, the master notebook in otter-grader's assign format (``# BEGIN QUESTION``
  cells with each question's name and points, ``# BEGIN SOLUTION``, ``# BEGIN TESTS``); a code
  cell whose first line is ``# your variant`` is replaced by each student's own numbers;
* ``graded.py``, which defines ``graded_questions()`` (a tuple of :class:`Question`),
  ``DEFAULT_VARIANT`` (the public notebook's numbers) and ``variant(number) -> dict`` (a
  student's numbers: :class:`Variants`), and may define ``warm()`` (modules to import once
  before a class is graded);
* what the master hands out beside the notebook (``files:`` in its assignment config), such as
  ``problems.py``, your problem for :func:`load_problem` and ``gpsaccel check``.

``gpsaccel assignment --example DIR`` writes a complete one, ``DIR/cv2d`` (:func:`write_example`;
a target in the plane at near-constant velocity); then ``gpsaccel assignment DIR/cv2d --out hw``
hands it out and ``gpsaccel grade CLASS --assignment DIR/cv2d`` grades a class of it, exactly
as the package's own homework: every notebook in the sandbox, every score computed outside it,
feedback that names each mistake and never the expected value.

How a question is graded.  A :class:`Question` declares what to *read* from the student's
notebook, which runs in the sandbox: variables (:func:`variable`) and calls of the student's
functions on fresh data (:func:`function`, drawn from the question's :class:`Draw`).  The box
sends back only arrays of the declared shapes and a status per read (an :class:`Answer`).  Once
the box is empty, the question's ``grade(draw, answers)`` computes the reference and returns a
:class:`~gpsaccel.check.report.Report` of findings: :func:`value` and :func:`replay` turn the
answers back into the student's variable or function, :func:`call` calls it safely,
:func:`compare` names the elements that differ, :func:`matrices_answer` names the mistake of a
model's matrices with the catalogue of linear-filter mistakes.  A question answered in a file
(``%%writefile kalman_filter.py``) is graded from the cell's text by :func:`filter_question`.

Partial credit.  A question's ``parts`` (``{"Phi": 0.5, "V": 0.5, ...}``) split its points;
every finding names the part it concerns, and a part without an error keeps its points.
``credit`` maps a catalogue code to the fraction of a part it keeps when that is the part's only
mistake (``{"std-as-variance": 0.5}``).  :func:`matrices_question` makes each matrix a part.

Examples
--------
The example's ``graded.py`` (``gpsaccel assignment --example DIR`` writes it) in short::

    from pathlib import Path

    from gpsaccel import homework as hw

    HERE = Path(__file__).resolve().parent
    PROBLEMS = hw.load_module(HERE / "problems.py")          # your own module, by path
    PROBLEM = hw.load_problem(HERE / "problems.py", "cv2d")  # its problem, registered

    DEFAULT_VARIANT = {"sigma_a": 0.5, "sigma_p": 3.0}
    variant = hw.Variants({"sigma_a": (0.2, 0.3, 0.4), "sigma_p": (1.0, 2.0, 3.0)},
                          DEFAULT_VARIANT)

    def variant_model(v):
        return hw.problem_model(PROBLEM, **PROBLEMS.model(0.1, v["sigma_a"], v["sigma_p"]))

    def graded_questions():
        return (hw.matrices_question("q1", variant_model, {"Phi": 1, "Gamma": 0.5, "Q": 1,
                                                           "H": 0.5, "V": 0.5, "M0": 0.5},
                                     credit={"std-as-variance": 0.5}),
                hw.filter_question("q2", 4, "kalman_filter.py", PROBLEM))
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gpsaccel import registry
from gpsaccel.assignments._answers import call
from gpsaccel.assignments.linear import MATRICES, compare, matrices_answer, shapes
from gpsaccel.assignments.notebook import Read
from gpsaccel.assignments.questions import Answer, Draw, Question, replay, value
from gpsaccel.assignments.variants import expected_shared_pairs, pick, size
from gpsaccel.check import own
from gpsaccel.check.report import Report
from gpsaccel.kalman.linear_model import LinearModel

if TYPE_CHECKING:
    import os
    import types

__all__ = [
    "EXAMPLE", "MATRICES", "Answer", "Draw", "LinearModel", "Question", "Read", "Report",
    "Variants", "call", "compare", "example", "filter_question", "function", "load_module",
    "load_problem", "matrices_answer", "matrices_question", "problem_model", "replay",
    "value", "variable", "write_example",
]

#: The name of the shipped example homework (:func:`example`).
EXAMPLE = "cv2d"


# ------------------------------------------------------------------------ what a question reads
def variable(name: str, shape: tuple[int, ...]) -> Read:
    """Read the student's variable ``name``, an array of ``shape``, after the notebook has run.

    Examples
    --------
    >>> hw.variable("Phi", (4, 4))      # doctest: +SKIP
    """
    return Read(_identifier("name", name), (), (_shape("shape", shape),), value=True)


def function(name: str, *args: object, returns: tuple[int, ...] | Sequence[tuple[int, ...]]
             ) -> Read:
    """Call the student's function ``name(*args)`` in the box; it must return one array of shape
    ``returns``, or a tuple of arrays of the shapes ``returns`` lists.

    ``args`` are arrays (numbers become 0-d arrays): draw them from the question's
    :class:`Draw` so that every student gets fresh data.  The answer comes back as an
    :class:`Answer`; :func:`replay` makes it a function again for the grade.

    Examples
    --------
    >>> rng = draw.rng()                                          # doctest: +SKIP
    >>> hw.function("predict", rng.normal(size=4), np.eye(4), np.array(3),
    ...             returns=[(4,), (4, 4)])                       # doctest: +SKIP
    """
    shapes_: tuple[tuple[int, ...], ...]
    if isinstance(returns, tuple) and all(isinstance(s, int) for s in returns):
        shapes_ = (_shape("returns", returns),)
    else:
        shapes_ = tuple(_shape("returns", s) for s in returns)
        if not shapes_:
            raise ValueError(f"returns must be a shape or a list of shapes, got {returns!r}")
    arrays = tuple(np.array(a, dtype=float) for a in args)
    return Read(_identifier("name", name), arrays, shapes_)


def _identifier(what: str, name: object) -> str:
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"{what} must be a Python name (the student's variable or function), "
                         f"got {name!r}")
    return name


def _shape(what: str, shape: object) -> tuple[int, ...]:
    try:
        out = tuple(int(s) for s in shape)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a shape, a tuple of sizes, got {shape!r}") from None
    if any(s < 0 for s in out) or len(out) > 6:
        raise ValueError(f"{what} must be a shape of at most 6 sizes >= 0, got {shape!r}")
    return out


# ---------------------------------------------------------------------------------- problems
def load_module(path: str | os.PathLike) -> types.ModuleType:
    """Run your Python file ``path`` once and return it as a module (kept for the process, so
    grading's forked processes find it; never a student's file).

    Examples
    --------
    >>> PROBLEMS = hw.load_module(Path(__file__).parent / "problems.py")  # doctest: +SKIP
    """
    return own.load_module(Path(path))  # the module load_problem runs: the file runs once


def load_problem(path: str | os.PathLike, name: str | None = None) -> str:
    """Register the problem ``name`` that your file ``path`` defines (a
    ``check.Problem.linear(name, ...)`` call, or a variable ``name`` holding a problem) and return
    its registered name, for :func:`filter_question`, ``check.submission(..., problem=...)`` and
    :func:`problem_model`.  ``path`` may also be ``"FILE.py:NAME"``.  ValueError naming what is
    wrong.

    Examples
    --------
    >>> PROBLEM = hw.load_problem(Path(__file__).parent / "problems.py", "cv2d")  # doctest: +SKIP
    """
    spec = str(path) if name is None else f"{path}:{name}"
    if not own.is_file_spec(spec):
        raise ValueError(f"problem: expected a Python file and a problem's name (FILE.py, NAME "
                         f"or 'FILE.py:NAME'), got {spec!r}")
    return own.load_problem(spec)


def problem_model(problem: str, **changes: object) -> LinearModel:
    """The :class:`~gpsaccel.kalman.linear_model.LinearModel` of the registered linear problem
    ``problem`` (:func:`load_problem`), with ``changes`` (Phi, Gamma, W, H, V, M0, x0, every,
    n_epochs, dt, ...) replaced: a student's variant of it.  ValueError for a problem that is not
    linear, or a change the model refuses.

    Examples
    --------
    >>> hw.problem_model(PROBLEM, W=0.3**2 * np.eye(2), V=2.0**2 * np.eye(2))  # doctest: +SKIP
    """
    model = getattr(registry.problem(problem), "model", None)
    if not isinstance(model, LinearModel):
        raise ValueError(f"problem: {problem!r} is not a linear problem of your own (made with "
                         f"check.Problem.linear)")
    return replace(model, **changes)  # type: ignore[arg-type]  # LinearModel checks each


# ---------------------------------------------------------------------------------- variants
@dataclass(frozen=True)
class Variants:
    """Every student's own numbers: a grid of values per parameter (``axes``), never the public
    notebook's point (``public``, the ``DEFAULT_VARIANT``).  Assign it to ``variant`` in
    ``graded.py``: ``variant(number)`` is a student's point (``number``: an HMAC of the student's
    id under your secret, :func:`gpsaccel.assignments.questions.variant_number`).

    Examples
    --------
    >>> variant = hw.Variants({"sigma_a": (0.2, 0.5), "sigma_p": (1.0, 3.0)},
    ...                       {"sigma_a": 0.5, "sigma_p": 3.0})
    >>> variant(0), variant.size
    ({'sigma_a': 0.2, 'sigma_p': 1.0}, 4)
    """

    axes: Mapping[str, Sequence]
    public: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        axes = {str(k): tuple(v) for k, v in dict(self.axes).items()}
        if not axes or any(not v for v in axes.values()):
            raise ValueError(f"axes must map each parameter to its values (at least one), got "
                             f"{self.axes!r}")
        if self.public and set(self.public) != set(axes):
            raise ValueError(f"public must give every parameter of axes ({', '.join(axes)}), "
                             f"got {dict(self.public)!r}")
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "public", dict(self.public))
        if self.size < 2 and self._public_on_grid():
            raise ValueError("axes: a grid of one point, the public one, leaves no variant")

    def _public_on_grid(self) -> bool:
        return bool(self.public) and all(self.public[k] in v for k, v in self.axes.items())

    def __call__(self, number: int) -> dict:
        """The student's point for ``number`` (>= 0)."""
        return pick(int(number), self.axes, self.public)

    @property
    def size(self) -> int:
        """Points of the grid (the public one included)."""
        return size(self.axes)

    def shared_pairs(self, n_students: int) -> float:
        """Expected pairs of students with the same numbers in a class of ``n_students``."""
        return expected_shared_pairs(n_students, self.size - self._public_on_grid())


# ---------------------------------------------------------------------------------- questions
def matrices_question(name: str, model: LinearModel | Callable[[dict], LinearModel],
                      points: float | Mapping[str, float], *,
                      matrices: Sequence[str] = MATRICES, credit: Mapping[str, float] | None = None,
                      title: str = "") -> Question:
    """A question "build the model's matrices for your variant": it reads the student's
    variables ``matrices`` (of Phi, Gamma, Q, H, V, M0 and W) and checks them with
    :func:`matrices_answer`, which names a wrong matrix by the catalogue's mistakes (Φᵀ, Q
    without Γ, σ where σ² belongs, M0 in another order, a sign of Φ ...), in your problem's own
    state names, or names its wrong elements (never the value they should have).

    Parameters
    ----------
    name : the question's name in the master (``q1``).
    model : the problem's :class:`~gpsaccel.kalman.linear_model.LinearModel`, or a function of
        the student's variant (a dict) giving theirs (:func:`problem_model`).
    points : the question's points, all or nothing; or matrix -> points, each matrix a part of
        its own (partial credit), adding up to the question's points.
    matrices : the variables the question asks for, in its order.
    credit : mistake code -> fraction of a matrix's points kept when that is its only mistake
        (:class:`Question`'s ``credit``).
    title : the title of its feedback (default "question N: model matrices").

    Examples
    --------
    >>> hw.matrices_question("q1", variant_model, {"Phi": 1, "Gamma": 0.5, "Q": 1, "H": 0.5,
    ...                                            "V": 0.5, "M0": 0.5})  # doctest: +SKIP
    """
    names = tuple(matrices)
    unknown = sorted(set(names) - set(MATRICES) - {"W"})
    if unknown or not names or len(set(names)) != len(names):
        raise ValueError(f"matrices must be distinct names among {', '.join(MATRICES)}, W; got "
                         f"{names!r}")
    if isinstance(points, Mapping):
        parts = {str(k): float(v) for k, v in points.items()}
        if set(parts) != set(names):
            raise ValueError(f"points must give each of {', '.join(names)} its points, got "
                             f"{sorted(parts)}")
        total = math.fsum(parts.values())
    else:
        parts, total = {}, float(points)
    if not callable(model) and not isinstance(model, LinearModel):
        raise ValueError(f"model must be a LinearModel or a function of the variant giving one, "
                         f"got {type(model).__name__}")
    heading = title or f"question {name.removeprefix('q')}: model matrices"
    return Question(name, total, partial(_matrices_reads, model, names),
                    partial(_matrices_grade, model, names, heading), parts=parts,
                    credit=dict(credit or {}))


def _model(model: LinearModel | Callable[[dict], LinearModel], draw: Draw) -> LinearModel:
    made = model if isinstance(model, LinearModel) else model(dict(draw.variant))
    if not isinstance(made, LinearModel):
        raise TypeError(f"the question's model gave a {type(made).__name__}, not a LinearModel")
    return made


def _matrices_reads(model, names: tuple[str, ...], draw: Draw) -> list[Read]:
    want = shapes(_model(model, draw))
    return [Read(k, (), (want[k],), value=True) for k in names]


def _matrices_grade(model, names: tuple[str, ...], title: str, draw: Draw,
                    answers: list[Answer]) -> Report:
    """Each variable the box read (a finding of its part when it is missing or not a matrix),
    then the defined ones against the student's model."""
    report = Report(title)
    given = {k: value(report, k, a, k) for k, a in zip(names, answers, strict=True)}
    defined = {k: v for k, v in given.items() if v is not None}
    if defined:
        checked = matrices_answer(_model(model, draw), defined, title, tuple(defined))
        report.findings += checked.findings
    report.sort()
    return report


def filter_question(name: str, points: float, file: str, problem: str, *, n_runs: int = 10
                    ) -> Question:
    """A question answered by a filter the notebook writes to ``file`` (a ``%%writefile FILE``
    cell), graded as ``gpsaccel check`` grades a file: ``check.submission(file,
    problem=problem)`` on ``n_runs`` fresh realizations (the question's seed), in a box of its
    own without gpsaccel, its mistakes named by the problem's catalogue.  All or nothing.

    Examples
    --------
    >>> hw.filter_question("q2", 4, "kalman_filter.py", PROBLEM)  # doctest: +SKIP
    """
    registry.problem(problem)  # ValueError naming the registered problems
    if not isinstance(file, str) or not file.endswith(".py") or "/" in file:
        raise ValueError(f"file must be the name of a .py file the notebook writes, got "
                         f"{file!r}")
    n_runs = int(n_runs)
    if n_runs < 2:
        raise ValueError(f"n_runs must be at least 2, got {n_runs}")
    return Question(name, float(points), file=file,
                    grade_file=partial(_grade_filter, problem, n_runs))


def _grade_filter(problem: str, n_runs: int, path: Path, draw: Draw, timeout: float) -> Report:
    from gpsaccel.check import submission

    return submission(path, problem=problem, n_runs=n_runs, seed=draw.seed % 2**32,
                      timeout=timeout)


# ---------------------------------------------------------------------------------- the example
def example() -> Path:
    """The folder of the example homework shipped in the package (``cv2d``: its master
    notebook, ``graded.py`` and ``problems.py``); :func:`write_example` copies it."""
    return Path(__file__).resolve().parent / "example" / EXAMPLE


#: The example's files (what :func:`write_example` copies).
_EXAMPLE_FILES = (f"{EXAMPLE}.ipynb", "graded.py", "problems.py")


def write_example(folder: str | os.PathLike) -> Path:
    """Copy the example homework into ``folder/cv2d`` and return that folder: its master
    notebook, ``graded.py`` and ``problems.py``, yours to change.  ValueError when
    ``folder/cv2d`` already exists (nothing of yours is replaced)."""
    target = Path(folder).expanduser().resolve() / EXAMPLE
    if target.exists():
        raise ValueError(f"example: {target} already exists; remove it or give another folder")
    src = example()
    missing = [f for f in _EXAMPLE_FILES if not (src / f).is_file()]
    if missing:
        raise FileNotFoundError(f"the example's {', '.join(missing)} are missing from {src} (a "
                                f"broken installation of gpsaccel: reinstall it)")
    target.mkdir(parents=True)
    for f in _EXAMPLE_FILES:
        shutil.copyfile(src / f, target / f)
    return target
