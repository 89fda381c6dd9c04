"""What a lesson calls: its ensemble size, its sliders, where the lessons are installed.

A lesson reads its Monte Carlo size with :func:`lesson_runs`, so the test suite can execute every
notebook quickly (``GPSACCEL_LESSON_RUNS=50``) while a student gets the report's full size.

This module is what a student's notebook imports (``from gpsaccel.lessons import lesson_runs,
sliders``), so it imports nothing heavy.  The tooling around the lessons lives in modules of its
own, each one job, and its public names stay reachable from here (loaded on first use,
:mod:`gpsaccel._lazy`):

* :mod:`~gpsaccel.lessons.kernel`: executing a notebook in a private kernel;
* :mod:`~gpsaccel.lessons.lab`: a student's own copy, and JupyterLab on it;
* :mod:`~gpsaccel.lessons.render`: the HTML pages and their index;
* :mod:`~gpsaccel.lessons.release`: masters to student and solutions versions;
* :mod:`~gpsaccel.lessons.measurement`: running time, printed text and answers of each master;
* :mod:`~gpsaccel.lessons.numbers`: every number a lesson's text states, against what it prints;
* :mod:`~gpsaccel.lessons.__main__`: ``python -m gpsaccel.lessons release|measure|check``.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from gpsaccel import _lazy

#: The environment variable that overrides every lesson's ensemble size.
RUNS_VARIABLE = "GPSACCEL_LESSON_RUNS"


def lesson_runs(default: int) -> int:
    """The lesson's Monte Carlo size: ``$GPSACCEL_LESSON_RUNS`` if set, else ``default``."""
    raw = os.environ.get(RUNS_VARIABLE)
    if raw is None or raw == "":
        return default
    try:
        n = int(raw)
    except ValueError:
        raise ValueError(f"{RUNS_VARIABLE} must be an integer, got {raw!r}") from None
    if n < 2:
        raise ValueError(f"{RUNS_VARIABLE} must be >= 2, got {n}")
    return n


def lessons_dir() -> Path:
    """The student versions of the lessons, as installed with the package.

    Read with :mod:`importlib.resources`: ``gpsaccel/_lessons`` is a link to the repository's
    top-level ``lessons/`` (where a student who clones finds them), so an editable install reads
    the checkout and a wheel or an sdist its own copy.  The solutions are in ``solutions/`` below it
    (:func:`solutions_dir`).
    """
    folder = Path(str(resources.files("gpsaccel") / "_lessons"))
    if not folder.is_dir():
        raise FileNotFoundError(f"the lessons are not installed with gpsaccel (no folder {folder})")
    return folder


def solutions_dir() -> Path:
    """The lessons with their solutions filled in (``lessons/solutions/`` of the checkout)."""
    return lessons_dir() / "solutions"


#: Set in the kernel's environment by :func:`execute`: the notebook runs without a front end, so a
#: slider cell draws its default once instead of showing widgets nobody can move.
HEADLESS_VARIABLE = "GPSACCEL_HEADLESS"


# --------------------------------------------------------------------------------------------------
# Sliders: ipywidgets in JupyterLab, the default drawn once when there is no front end

def sliders(callback, **controls) -> None:
    """An interactive cell: ``controls`` are ipywidgets, each opening at the lesson's number.

    In JupyterLab the sliders appear (labels in full: ``description_width: initial``) and every
    change re-runs ``callback(**values)``; nothing else is printed (no ``<function …>`` repr: the
    cell's value is None).  Without a front end (``gpsaccel lessons``, the tests, the HTML pages;
    :data:`HEADLESS_VARIABLE` set) ``callback`` runs once with the default values, so its figure
    and text are in the output.  A control whose widget would open elsewhere than the callback's
    default (a log slider's steps miss 4e-4 and show 3.98e-4) is refused: use a SelectionSlider
    whose options include the lesson's number.
    """
    import inspect
    import time

    defaults = {k: p.default for k, p in inspect.signature(callback).parameters.items()
                if p.default is not inspect.Parameter.empty}
    for k, c in controls.items():
        value = _opens_at(c)
        if k in defaults and value != defaults[k]:
            raise ValueError(f"sliders: control {k!r} opens at {value!r}, but {callback.__name__}'s "
                             f"default (the lesson's number) is {defaults[k]!r}")
        if hasattr(c, "style") and hasattr(c.style, "description_width"):
            c.style.description_width = "initial"
    values = {k: getattr(c, "value", c) for k, c in controls.items()}
    if os.environ.get(HEADLESS_VARIABLE):
        t0 = time.perf_counter()
        result = callback(**values)
        shown = ", ".join(f"{k} = {v}" for k, v in values.items())
        print(f"(sliders in JupyterLab; here drawn once with {shown}: "
              f"{time.perf_counter() - t0:.2f} s)")
        _display(result)
        return None
    import ipywidgets

    ipywidgets.interact(callback, **controls)
    return None


def _opens_at(control):
    """The value a slider shows when the front end draws it: JupyterLab snaps a slider's value to
    its steps (a FloatLogSlider to base**(min + k·step)), and sends the snapped value back."""
    import math

    value = getattr(control, "value", control)
    step, lo = getattr(control, "step", None), getattr(control, "min", None)
    if not step or lo is None or not isinstance(value, int | float) or isinstance(value, bool):
        return value
    base = getattr(control, "base", None)
    position = (math.log(value, base) - lo) / step if base else (value - lo) / step
    if abs(position - round(position)) < 1e-9:
        return value
    snapped = lo + round(position) * step
    return float(f"{base ** snapped if base else snapped:.6g}")


def _display(result):
    """Show a matplotlib Figure returned by a callback (Figures made with ``Figure()`` do not
    show themselves)."""
    if result is None:
        return None
    from IPython.display import display

    display(result)
    return None


# The tooling's names, as ``gpsaccel.lessons.NAME`` (the CLI, the tests, the Makefile's pre-save
# hook ``gpsaccel.lessons.pre_save`` and benchmarks/ read them here).
__getattr__, __dir__ = _lazy.attach(
    __name__,
    submodules=("kernel", "lab", "measurement", "numbers", "release", "render"),
    attributes={
        "kernel": ("execute",),
        "lab": ("copy_lessons", "lab_command"),
        "render": ("render_html", "html_exporter", "remote_scripts", "report_figures",
                   "figure_mentions", "write_index"),
        "release": ("SOLUTION", "ANSWER", "CHECK", "PRINTED", "LAB_METADATA", "NBFORMAT_MINOR",
                    "SLOW_CELL", "SOLUTION_LINE", "solution_label", "exercise_of", "exercise_prompts",
                    "masters_dir",
                    "masters", "measured",
                    "code_digest", "student_version", "solutions_version", "running_time_line",
                    "lab_text", "released", "lessons_table", "docs_page", "taught_table",
                    "checker_page", "release", "pre_save"),
        "measurement": ("measure", "answers_text"),
        "numbers": ("STATED", "GIVEN", "untagged_numbers", "number_problems"),
        "__main__": ("main",),
    })
