r"""A homework's grade of one notebook, as an item of a class's run (``gpsaccel grade``).

The model (issue 19).  A student's notebook is data.  :mod:`gpsaccel.assignments.notebook` turns
its code cells into one module; :func:`gpsaccel.sandbox.run` imports that module in a box
(bubblewrap namespaces where they work) and calls, one frame each, the cells in order and then
the *reads* every question declares (:mod:`gpsaccel.assignments.questions`): the student's
functions called on data drawn from this run's seed, the variables it must define.  What comes
back is arrays of the declared shapes and a status, nothing else.  Only once the box is empty
does the grader draw the reference answers and score each question.  The hidden checks, the
reference answers, the masters' solutions, the run's seed and the instructor's secret are never
in the box (the box may import gpsaccel's models, simulations and filters, not
``gpsaccel.check`` or ``gpsaccel.assignments``; see ``docs/grading.md``).

A question graded from a file the notebook writes (calibration q2, ``%%writefile
kalman_filter.py``) is graded from the cell's text, in a box of its own without gpsaccel, by
:func:`gpsaccel.check.submission`.

Grading one notebook is :mod:`gpsaccel.assignments.scoring` (:func:`grade_notebook`,
:class:`Grade`, the feedback); this module is what a class's run asks of it for one student
(:func:`grade_item`, the grade of a submission that could not be run, :func:`grader_error`),
what every notebook's process needs imported first (:func:`warm`), how long one may take
(:func:`deadline`), the instructor's secret (:func:`read_secret`), and whether a notebook
declares a variant of its own (:func:`declares_variant`).  The class run itself
(the walk of the export, the seed, the pool, ``grades.csv``, feedback, the gradebooks and the
similarity report) is :mod:`gpsaccel.classrun`.  Scoring's public names stay reachable here.
"""

from __future__ import annotations

import ast
import os
from dataclasses import asdict
from pathlib import Path

from gpsaccel import _untrusted
from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments.boxcalls import is_variant_cell
from gpsaccel.assignments.scoring import BOX_MEMORY as BOX_MEMORY
from gpsaccel.assignments.scoring import BOX_PROCESSES as BOX_PROCESSES
from gpsaccel.assignments.scoring import SKIP_MARK as SKIP_MARK
from gpsaccel.assignments.scoring import SLACK as SLACK
from gpsaccel.assignments.scoring import TIMEOUT as TIMEOUT
from gpsaccel.assignments.scoring import VARIANT_MARK as VARIANT_MARK
from gpsaccel.assignments.scoring import Grade as Grade
from gpsaccel.assignments.scoring import _possible
from gpsaccel.assignments.scoring import assignment_module as assignment_module
from gpsaccel.assignments.scoring import grade_notebook as grade_notebook
from gpsaccel.assignments.scoring import is_otter_cell as is_otter_cell
from gpsaccel.assignments.scoring import questions_of as questions_of
from gpsaccel.assignments.scoring import student_variant as student_variant
from gpsaccel.assignments.scoring import unusable as unusable

#: Environment variable holding the instructor's secret (or use ``secret_file``).
SECRET_ENV = "GPSACCEL_GRADING_SECRET"


def possible_of(name: str) -> dict[str, float]:
    """Question -> its points, of homework ``name``: what every grade, table and gradebook of
    the class is out of."""
    return _possible(questions_of(name))


def deadline(timeout: float) -> float:
    """Seconds one notebook's process may take in all: its box's ``timeout``, the file
    question's box (as long again), 60 s of parsing and feedback, and :data:`SLACK`."""
    return 2 * timeout + 60 + SLACK


def warm(name: str) -> None:
    """Import here what grading a notebook of homework ``name`` imports on first use (IPython's
    input transformer, the registered problems a question checks a file against), so each
    notebook's forked process inherits it instead of importing it again (what that saves a
    notebook: ``python benchmarks/grading.py --profile``), and what the homework's ``warm``
    makes (modules, inputs of its reads: never a reference answer, which exists only once a
    notebook's box is empty).  Nothing of a student's runs here."""
    questions_of(name)
    nbm.transform("%time x = 1\n!true")
    from gpsaccel import registry
    from gpsaccel.check.batch import warm as warm_check

    registry.problems()
    # what the questions' references import on first use, since `import gpsaccel` imports
    # nothing: scipy.stats and filterpy (the check's warm-up), scipy.integrate (CoopModel's truth)
    warm_check(registry.assignment(name).problem or "calibration")
    import scipy.integrate  # noqa: F401

    # the homework's own (graded.py's optional ``warm``): the modules its references import
    # (filterpy, scipy.stats: benchmarks/imports.py) and the inputs its reads share
    homework_warm = getattr(assignment_module(name), "warm", None)
    if callable(homework_warm):
        homework_warm()


def notebook_in(folder: Path, name: str) -> tuple[Path | None, tuple[str, str] | None]:
    """The notebook a student's ``folder`` holds, or ``(status, message)`` why there is none:
    any ``.ipynb`` (any case) found breadth first within the checker's depth and entry limits,
    without following a link (:func:`gpsaccel._untrusted.walk`); ``NAME.ipynb`` among several.
    A class's walk and Gradescope's container look for it so."""
    who = _untrusted.shown(folder.name)
    try:
        found = sorted(folder / rel for rel, f in _untrusted.walk(folder, skip=_untrusted.hidden)
                       if f.name.lower().endswith(".ipynb") and f.is_file(follow_symlinks=False))
    except _untrusted.WalkLimit as exc:
        what = (f"more than {exc.limit} levels deep" if exc.kind == "depth" else
                f"more than {exc.limit} files and folders")
        return None, ("file-limit", f"The folder {who}/ is {what}: hand in the homework's "
                      f"notebook in a folder of a few files. Nothing was graded.")
    except OSError as exc:
        return None, ("unreadable", f"The folder {who}/ cannot be read ({exc.strerror}).")
    if len(found) > 1:
        named = [p for p in found if p.stem.lower() == name.lower()]
        found = named if len(named) == 1 else found
    if not found:
        return None, ("no-notebook", f"No .ipynb file in {who}/: hand in the homework's "
                      f"notebook.")
    if len(found) > 1:
        names = ", ".join(_untrusted.shown(os.path.relpath(p, folder)) for p in found[:10])
        return None, ("ambiguous", f"Several notebooks in {who}/ ({names}) and none named "
                      f"{name}.ipynb: hand in one.")
    return found[0], None


def grade_item(path: Path, student: str, file: str, sid: str, settings: dict) -> dict:
    """One student's notebook graded (:func:`grade_notebook`) as plain data, in the item's
    process.  ``settings``: the homework's ``name``, the run's ``seed``, the ``secret``, the
    ``sandbox`` backend and the box's ``timeout``; ``file``: the notebook as the class lists it;
    ``sid``: the student's id."""
    return asdict(grade_notebook(path, settings["name"], student, settings["seed"],
                                 settings["secret"], settings["sandbox"], settings["timeout"],
                                 file, sid))


def not_run(name: str, student: str, sid: str, status: str, message: str) -> dict:
    """The grade of a submission that could not be run (no notebook, several, a collision)."""
    return asdict(unusable(name, student, "", status, message, sid))


def grader_error(name: str, student: str, file: str, sid: str, why: str) -> dict:
    """The grade of a notebook whose process gave none (``why``: the sandbox's words): not the
    student's; it is graded again."""
    return asdict(unusable(name, student, file, "grader-error", f"The grader could not finish "
                           f"this notebook ({why}); it was not graded. Tell your instructor.",
                           sid))


def read_secret(secret_file: str | os.PathLike | None) -> bytes | None:
    """The instructor's secret: the file's bytes, else ``$GPSACCEL_GRADING_SECRET``, else None."""
    if secret_file is not None:
        data = Path(secret_file).read_bytes().strip()
        if len(data) < 16:
            raise ValueError(f"secret_file: {secret_file} must hold at least 16 bytes (e.g. "
                             f"`python -c 'import secrets; print(secrets.token_hex(32))'`)")
        return data
    env = os.environ.get(SECRET_ENV, "").encode()
    return env or None


def declares_variant(path: str | os.PathLike, name: str) -> bool | None:
    """Whether the notebook at ``path`` declares numbers of its own: a variant cell
    (:func:`~gpsaccel.assignments.boxcalls.is_variant_cell`) assigning ``VARIANT`` a literal
    dict other than the public notebook's (``DEFAULT_VARIANT``), as every notebook
    :func:`gpsaccel.assignments.generate.personalize` writes does.  What tells a class handed
    per-student variants (:func:`gpsaccel.classrun.grading.grade_class`); a grade never depends
    on it (the grader computes each student's variant from the secret).  The student's bytes are
    read as text, never run, in a child under :func:`~gpsaccel.assignments.notebook.load`'s
    limits; None where they cannot be read within them (not a notebook, too large, too deep)."""
    from gpsaccel import sandbox as sb

    public = dict(assignment_module(name).DEFAULT_VARIANT)
    out = sb.in_child(_declares, Path(path), public, cpu=nbm.LOAD_CPU, memory=nbm.LOAD_MEMORY,
                      wall=nbm.LOAD_WALL, max_bytes=4096)
    return out.value if out.ok and isinstance(out.value, bool) else None


def _declares(path: Path, public: dict) -> bool | None:
    """In the child: :func:`declares_variant`'s answer."""
    try:
        cells = nbm.read(path).cells
    except nbm.NotebookError:
        return None
    declared = [_assigned_variant(c.source) for c in cells if is_variant_cell(c.source)]
    return any(v is not None and v != public for v in declared)


def _assigned_variant(source: str) -> dict | None:
    """The literal dict a cell's last top-level ``VARIANT = ...`` assigns, else None."""
    try:
        body = ast.parse(source).body
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        return None
    value = None
    for node in body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "VARIANT"
                                                for t in node.targets):
            try:
                value = ast.literal_eval(node.value)
            except (ValueError, TypeError, SyntaxError, RecursionError, MemoryError):
                value = None
    return value if isinstance(value, dict) else None
