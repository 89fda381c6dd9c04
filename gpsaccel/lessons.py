"""Running the Jupyter lessons: their ensemble size, executing them, rendering them to HTML.

A lesson reads its Monte Carlo size with :func:`lesson_runs`, so the test suite can execute every
notebook quickly (``GPSACCEL_LESSON_RUNS=50``) while a student gets the report's full size.
"""

from __future__ import annotations

import html
import json
import os
import re
import tempfile
from contextlib import contextmanager
from importlib import resources
from pathlib import Path

from gpsaccel._atomic import write_text

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


def copy_lessons(target: Path | str, solutions: bool = True) -> tuple[list[Path], list[Path]]:
    """Copy the lessons (and ``solutions/``) into ``target`` for a student to edit.

    A file already in ``target`` is never overwritten (it may hold the student's work): returns
    ``(copied, kept)``, the paths written and the paths left as they were.
    """
    import shutil

    target = Path(target)
    sources = sorted(lessons_dir().glob("*.ipynb"))
    if not sources:
        raise FileNotFoundError(f"no lesson found in {lessons_dir()}")
    if solutions:
        sources += sorted(solutions_dir().glob("*.ipynb"))
    copied, kept = [], []
    for src in sources:
        dest = target / src.relative_to(lessons_dir())
        if dest.exists():
            kept.append(dest)
            continue
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dest)
        copied.append(dest)
    return copied, kept


def lab_command(folder: Path | str, port: int | None = None, browser: bool = True) -> list[str]:
    """The command that opens JupyterLab on ``folder`` with this Python (so its kernel has
    gpsaccel); ``--allow-root`` when run as root (Jupyter refuses root otherwise)."""
    import importlib.util
    import sys

    if importlib.util.find_spec("jupyterlab") is None:
        raise ModuleNotFoundError("gpsaccel lab needs JupyterLab", name="jupyterlab")
    cmd = [sys.executable, "-m", "jupyterlab", f"--notebook-dir={folder}"]
    if port is not None:
        cmd.append(f"--port={port}")
    if not browser:
        cmd.append("--no-browser")
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-root")
    return cmd


def execute(path: Path | str, timeout: int = 600, runs: int | None = None):
    """Execute a notebook top to bottom in its own folder; returns the executed ``NotebookNode``.

    ``runs`` sets ``GPSACCEL_LESSON_RUNS`` for the kernel; ``GPSACCEL_HEADLESS`` tells slider cells
    that nobody can move them (:func:`sliders`).  A cell that raises raises
    ``nbclient.exceptions.CellExecutionError`` here.
    """
    import nbformat
    from nbclient import NotebookClient

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    env_before = os.environ.get(RUNS_VARIABLE)
    headless_before = os.environ.get(HEADLESS_VARIABLE)
    if runs is not None:
        os.environ[RUNS_VARIABLE] = str(runs)
    os.environ[HEADLESS_VARIABLE] = "1"
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        with _local_kernel() as km:
            NotebookClient(nb, km=km, timeout=timeout, kernel_name="python3",
                           resources={"metadata": {"path": str(path.parent)}}).execute()
    finally:
        if runs is not None:
            if env_before is None:
                os.environ.pop(RUNS_VARIABLE, None)
            else:
                os.environ[RUNS_VARIABLE] = env_before
        if headless_before is None:
            os.environ.pop(HEADLESS_VARIABLE, None)
        else:
            os.environ[HEADLESS_VARIABLE] = headless_before
    return nb


@contextmanager
def _local_kernel():
    """A kernel manager whose kernel talks over Unix sockets in a private temporary folder.

    The default TCP transport makes every kernel warn "Kernel is running over TCP without
    encryption" on the terminal of ``gpsaccel lessons``; the kernel runs on this machine only, so
    IPC sockets (readable by this user alone) are both quieter and safer.  The kernel is shut down
    and the folder removed on exit.
    """
    from jupyter_client.manager import KernelManager

    with tempfile.TemporaryDirectory(prefix="gpsaccel-kernel-") as folder:
        km = KernelManager(kernel_name="python3", transport="ipc", ip=os.path.join(folder, "kernel"))
        try:
            yield km
        finally:
            if km.has_kernel:
                km.shutdown_kernel(now=True)


def render_html(paths: list[Path], out: Path | str, runs: int | None = None,
                index: bool = True) -> list[Path]:
    """Execute ``paths`` and write each as HTML (figures embedded) into ``out``.

    Math is typeset by the MathJax copied into ``out/mathjax`` (no network needed).
    Solutions and self-checks are collapsed (``<details>``) as they are in JupyterLab; every
    markdown cell that walks through a report's figure gets an anchor ``r{report}-fig{number}``.
    With ``index``, ``out/index.html`` links every lesson rendered so far (in ``out``) and every
    figure the reports list to the lesson that shows it.
    """
    import nbformat
    from nbconvert import HTMLExporter

    from gpsaccel import _mathjax

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    exporter = HTMLExporter(extra_template_basedirs=[str(Path(__file__).parent / "templates")],
                            template_name="gpsaccel-lesson",
                            mathjax_url=_mathjax.copy_to(out))  # math typeset offline
    written = []
    for path in paths:
        nb = execute(path, runs=runs)
        for cell in nb.cells:
            if cell.cell_type == "markdown":
                anchors = "".join(f'<a id="r{r}-fig{n}"></a>' for r, n in _mentions(cell.source))
                if anchors:
                    cell.source = anchors + "\n\n" + cell.source
        nb.metadata["title"] = _title(nbformat.read(path, as_version=4)) or Path(path).stem
        body, _ = exporter.from_notebook_node(
            nb, resources={"gpsaccel_mathjax_config": _mathjax.config_script()})
        target = out / (Path(path).stem + ".html")
        write_text(target, body)  # whole or not at all
        written.append(target)
    if index:
        write_index(out)
    return written


#: Every figure each report lists (/work/shared/seeds/README.md): the numbers a lesson must walk
#: through.  Report 001 has two figures 10 (the gains, the ensemble-average error).
REPORT_FIGURES: dict[str, tuple[str, ...]] = {
    "000": ("1", "2", "3", "3b", "4", "5", "6", "7"),
    "001": tuple(str(i) for i in range(1, 13)),
    "003": tuple(str(i) for i in range(1, 7)),
    "002": tuple(str(i) for i in range(1, 20)),
    "004": tuple(str(i) for i in range(1, 12)),
}

_MENTION = re.compile(
    r"[Rr]eport (\d{3}),? figures? ((?:\d+[a-z]?(?:\s*[–-]\s*\d+[a-z]?)?(?:,\s*|\s+and\s+|\s*/\s*)?)+)")


def _mentions(text: str) -> list[tuple[str, str]]:
    """(report, figure) pairs a markdown text walks through: "Report 004, figures 1–3 and 9"."""
    found = []
    for report, numbers in _MENTION.findall(text):
        for part in re.split(r",\s*|\s+and\s+|\s*/\s*", numbers.strip()):
            if not part:
                continue
            lo, _, hi = re.split(r"\s*([–-])\s*", part) if re.search("[–-]", part) \
                else (part, "", "")
            if hi:
                found += [(report, str(i)) for i in range(int(lo), int(hi) + 1)]
            else:
                found.append((report, lo.lstrip("0") or "0"))
    return list(dict.fromkeys(found))


def figure_mentions(path: Path | str) -> list[tuple[str, str]]:
    """Every (report, figure) a lesson's markdown cells walk through, in order."""
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    found = []
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown":
            found += _mentions("".join(cell["source"]))
    return list(dict.fromkeys(found))


def _title(nb) -> str:
    for cell in nb.cells:
        if cell.cell_type == "markdown" and cell.source.startswith("# "):
            return cell.source.splitlines()[0][2:].strip()
    return ""


def write_index(out: Path | str) -> Path:
    """``out/index.html``: the lessons rendered in ``out`` and, per report, which lesson shows
    each listed figure (links to the figure's place in the lesson)."""
    import nbformat

    out = Path(out)
    rendered = {p.stem for p in out.glob("*.html") if p.name != "index.html"}
    lessons = [p for p in sorted(lessons_dir().glob("*.ipynb")) if p.stem in rendered]
    shows: dict[tuple[str, str], list[Path]] = {}
    parts = ["<!doctype html><meta charset='utf-8'><title>gpsaccel lessons</title>",
             "<style>body{font-family:sans-serif;max-width:1000px;margin:auto;line-height:1.5}"
             "td,th{padding:0.2em 0.8em;text-align:left;vertical-align:top}</style>",
             "<h1>gpsaccel: the lessons, with their outputs</h1>",
             "<p>Rendered by <code>make lessons-html</code>; to run and change them, "
             "<code>make lab</code>.</p><h2>Lessons</h2><ol>"]
    for p in lessons:
        title = _title(nbformat.read(p, as_version=4)) or p.stem
        parts.append(f"<li><a href='{p.stem}.html'>{html.escape(title)}</a></li>")
        for key in figure_mentions(p):
            shows.setdefault(key, []).append(p)
    parts.append("</ol><h2>The reports' figures, and the lesson that walks through each</h2>")
    for report, numbers in REPORT_FIGURES.items():
        parts.append(f"<h3>Report {report}</h3><table><tr><th>figure</th><th>lesson</th></tr>")
        for n in numbers:
            links = ", ".join(f"<a href='{p.stem}.html#r{report}-fig{n}'>{p.stem}</a>"
                              for p in shows.get((report, n), []))
            parts.append(f"<tr><td>{n}</td><td>{links or '(not rendered)'}</td></tr>")
        parts.append("</table>")
    target = out / "index.html"
    target.write_text("\n".join(parts) + "\n", encoding="utf-8")
    return target


# --------------------------------------------------------------------------------------------------
# Exercises: a self-check a student runs on their own answer

#: Set in the kernel's environment by :func:`execute`: the notebook runs without a front end, so a
#: slider cell draws its default once instead of showing widgets nobody can move.
HEADLESS_VARIABLE = "GPSACCEL_HEADLESS"


def check_answer(answer, expected, *, name: str = "your answer", rtol: float = 1e-6,
                 atol: float = 0.0, why: str = "") -> bool | None:
    """Say whether ``answer`` (a number or an array) equals ``expected`` within ``rtol``/``atol``.

    Prints one line a student can act on: ✓, or ✗ with the shape or the largest difference (where,
    by how much) and ``why`` (the hint: what the right answer depends on).  ``None`` means not
    answered yet.  Returns True, False, or None when there is no answer.
    """
    import numpy as np

    if answer is None:
        print(f"… {name}: not answered yet (replace the None above with your answer)")
        return None
    try:
        a = np.asarray(answer, dtype=float)
    except (TypeError, ValueError):
        print(f"✗ {name}: expected a number or an array of numbers, got {type(answer).__name__}")
        return False
    e = np.asarray(expected, dtype=float)
    if a.shape != e.shape:
        print(f"✗ {name}: shape {a.shape}, expected {e.shape}")
        return False
    if not np.all(np.isfinite(a)):
        print(f"✗ {name}: contains NaN or inf")
        return False
    diff = np.abs(a - e)
    tol = atol + rtol * np.abs(e)
    if np.all(diff <= tol):
        print(f"✓ {name}: right" + (f" ({_short(a)})" if a.size <= 4 else ""))
        return True
    k = np.unravel_index(np.argmax(diff - tol), diff.shape) if diff.ndim else ()
    where = f" at {tuple(int(i) for i in k)}" if k else ""
    print(f"✗ {name}: {_short(a[k])}{where}, expected {_short(e[k])} "
          f"(off by {diff[k]:.3g}, tolerance {tol[k]:.3g})" + (f". Hint: {why}" if why else ""))
    return False


def _short(x) -> str:
    import numpy as np

    x = np.asarray(x)
    if x.ndim == 0:
        return f"{float(x):.6g}"
    return np.array2string(x, precision=4, separator=", ")


# --------------------------------------------------------------------------------------------------
# Sliders: ipywidgets in JupyterLab, the default drawn once when there is no front end

def sliders(callback, **controls):
    """An interactive cell: ``controls`` are ipywidgets (or ``interact`` abbreviations).

    In JupyterLab the sliders appear and every change re-runs ``callback(**values)``.  Without a
    front end (``gpsaccel lessons``, the tests, the HTML pages; :data:`HEADLESS_VARIABLE` set)
    ``callback`` runs once with the default values, so its figure and text are in the output.
    Either way the time of the default call is printed: a slider should answer within a second.
    """
    import time

    defaults = {k: getattr(c, "value", c) for k, c in controls.items()}
    if os.environ.get(HEADLESS_VARIABLE):
        t0 = time.perf_counter()
        result = callback(**defaults)
        values = ", ".join(f"{k} = {v}" for k, v in defaults.items())
        print(f"(sliders in JupyterLab; here drawn once with {values}: "
              f"{time.perf_counter() - t0:.2f} s)")
        return _display(result)
    import ipywidgets

    return ipywidgets.interact(callback, **controls)


def _display(result):
    """Show a matplotlib Figure returned by a callback (Figures made with ``Figure()`` do not
    show themselves)."""
    if result is None:
        return None
    from IPython.display import display

    display(result)
    return None
