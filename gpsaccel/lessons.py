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

    from gpsaccel import _mathjax

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    exporter = html_exporter(_mathjax.copy_to(out))  # math typeset offline
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


def html_exporter(mathjax_url: str):
    """nbconvert's HTML exporter with the lessons' template (``templates/gpsaccel-lesson``).

    The template drops every script nbconvert's lab template loads from elsewhere: require.js,
    the widgets' html-manager from a CDN and mermaid's module (a lesson has no diagram and no
    widget state to show offline); such a script fails silently without network and is one more
    thing fetched from a third party.  MathJax comes from ``mathjax_url``, the copy next to the
    pages (:mod:`gpsaccel._mathjax`).
    """
    from nbconvert import HTMLExporter

    return HTMLExporter(extra_template_basedirs=[str(Path(__file__).parent / "templates")],
                        template_name="gpsaccel-lesson", mathjax_url=mathjax_url)


#: What a rendered page may load: only files next to it (no scheme, no ``//host``).
_REMOTE = re.compile(r"""<script\b[^>]*\bsrc\s*=\s*["']?\s*(?:[a-z][a-z0-9+.-]*:|//)"""
                     r"""|\b(?:import|from)\s*(?:\(\s*)?["'](?:[a-z][a-z0-9+.-]*:|//)"""
                     r"""|<link\b[^>]*\bhref\s*=\s*["']?\s*(?:https?:|//)""", re.I)


def remote_scripts(page: str) -> list[str]:
    """The places in an HTML page that load a script (or a stylesheet) from another host."""
    return [m.group(0) for m in _REMOTE.finditer(page)]


def report_figures() -> dict[str, tuple[str, ...]]:
    """Every figure each report lists, the numbers a lesson must walk through (registered by each
    report's figure module: :func:`gpsaccel.registry.report_figures`)."""
    from gpsaccel import registry

    return registry.report_figures()


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
             "<p>Every lesson run at its full size, with its outputs. To run and change them "
             "yourself: <code>gpsaccel lessons --copy my-lessons</code>, then "
             "<code>gpsaccel lab my-lessons</code> (from a clone of the repository, "
             "<code>make lab</code>).</p><h2>Lessons</h2><ol>"]
    for p in lessons:
        title = _title(nbformat.read(p, as_version=4)) or p.stem
        parts.append(f"<li><a href='{p.stem}.html'>{html.escape(title)}</a></li>")
        for key in figure_mentions(p):
            shows.setdefault(key, []).append(p)
    parts.append("</ol><h2>The reports' figures, and the lesson that walks through each</h2>")
    for report, numbers in report_figures().items():
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
# The kernel without a front end (the self-checks are gpsaccel.exercises)

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


# --------------------------------------------------------------------------------------------------
# Release: one master, two versions (the way nbgrader and otter build a student release)
#
# lessons/masters/NN-topic.ipynb      the source; holds the solutions
# lessons/NN-topic.ipynb              the student version: no solution text, no outputs
# lessons/solutions/NN-topic.ipynb    the solutions version (the rendered site's source)
# lessons/measured/NN-topic.json      measured at the lesson's full size: running time, printed text
#
# Cell tags in a master: ``solution`` (code or markdown: removed from the student version),
# ``answer`` (the student's ``answer_… = None`` cell: removed from the solutions version, where the
# solution assigns ``answer_…``) and ``check`` (one ``check("NN.k", answer_k)`` line; in the
# solutions version it moves below the solution, so it shows ✓).

SOLUTION, ANSWER, CHECK = "solution", "answer", "check"

#: A number the text quotes from the lesson's own output is written ``[[0.687]]`` in the master
#: (``[[3.58 @04]]``: printed by lesson 04); the release writes it plainly, and
#: :func:`number_problems` finds it, digit for digit, in the measured output.
PRINTED = re.compile(r"\[\[([^\[\]@]+?)(?:\s*@(\w+))?\]\]")

#: A number as a lesson's text states a result: a decimal (0.687, 3.6, 2.6e-12, 1.25·10⁻⁵) or a
#: scientific one with a whole mantissa (4·10⁻⁵, 1e-13).  Plain whole numbers (counts, 40 steps,
#: 10⁻¹² as an order of magnitude) are not flagged: tag them where they are results.
STATED = re.compile(r"(?<![\w.])\d+(?:\.\d+(?:e[-+]?\d+|\s*[·×]\s*10[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)?"
                    r"|e[-+]?\d+|\s*[·×]\s*10[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)(?![\w.]*\d)")

#: What :data:`STATED` does not read: the tagged numbers, code (a span or a block: what a student
#: types) and the reports' section numbers.
_NOT_STATED = re.compile(r"\[\[[^\[\]]+\]\]|```.*?```|`[^`\n]*`|[Ss]ection \d+(?:\.\d+)+", re.S)

#: The numbers a lesson may state untagged: the problems' given constants (the reports' model
#: parameters, what an exercise sets, square roots of given variances) and numbers quoted from
#: the reports themselves.  Every other decimal in a master's text is a result: tag it.
GIVEN: dict[str, str] = {
    # calibration (reports 000, 001, 003)
    "0.005": "Δt, the accelerometer step (s)",
    "0.0004": "W, accelerometer noise variance ((m/s²)²)",
    "0.01": "M0₃₃ = σ_b² ((m/s²)²); the coop heading noise (rad²); 0.01 Hz, 0.01·δx0 (exercises)",
    "0.1": "σ_b (m/s²); ω = 0.1 (Hz, report 001; rad/s, report 000); T_s (s); δx0's 0.1 rad",
    "0.04": "σ of the GPS velocity (m/s); report 003 uses it as a variance",
    "0.0016": "V₂₂ = 0.04² ((m/s)²)",
    "1.0016": "M0₂₂ + V₂₂, the first velocity update's denominator",
    "0.2": "the GPS interval (s); V of the ship's velocities and heading",
    "0.63": "2π·0.1, report 001's angular frequency (rad/s)",
    "1.25·10⁻⁵": "Δt²/2 (s²)",
    "0.195": "39·Δt, the interval a loop of 39 predictions covers (s)",
    "0.4": "σ_v ten times larger (exercise, m/s)",
    "1.0": "M0₃₃ = 1.0 (exercise); 1.0 s",
    "0.001": "an example answer; the GPS variance of the ship's sweep (m²)",
    "1e-6": "the checker's tolerance (σ)",
    # the ship (report 004)
    "0.4462": "β_x, surge drag (1/s)",
    "0.0784": "β_y, sway drag (1/s)",
    "0.5": "σ of the random force (N); the wheelbase L (m); t = 0.5 s",
    "0.05": "σ of the random torque (N m); 1 − 0.95",
    "3.9": "√15, σ of the GPS position (m)",
    "0.45": "√0.2, σ of the ship's velocity and heading measurements",
    "0.007": "√4.9e-5, σ of the ship's accelerometers (m/s²)",
    # cooperative localization (report 002)
    "0.025": "P0's heading variances (rad²)",
    "0.95": "the 95 % level of the χ² bounds",
    # numbers the reports print (quoted, then measured against ours)
    "0.013": "report 000's max(P_ave − P)",
    "29.8": "report 000's r(30) r(29.8)ᵀ (s)",
    "0.0034": "report 000's r(30) r(29.8)ᵀ", "0.0005": "report 000's r(30) r(29.8)ᵀ",
    "0.0000": "report 000's r(30) r(29.8)ᵀ",
    "0.0486": "report 001's r(20) r(30)ᵀ", "0.0023": "report 001's r(20) r(30)ᵀ",
    "0.0002": "report 001's r(20) r(30)ᵀ",
    "5.8": "report 003's k = 30 (s)", "3.8": "report 003's k = 20 (s)",
    "0.0055": "report 003's r(k=30) r(k=20)ᵀ", "0.0077": "report 003's r(k=30) r(k=20)ᵀ",
    "0.0018": "report 003's r(k=30) r(k=20)ᵀ", "0.0006": "report 003's r(k=30) r(k=20)ᵀ",
}


def untagged_numbers(text: str) -> list[str]:
    """The results ``text`` (a master's markdown) states without a ``[[tag]]``: every
    :data:`STATED` number outside code and tags that is not a :data:`GIVEN` constant."""
    plain = _NOT_STATED.sub(lambda m: " " * len(m.group(0)), text)
    return [m.group(0) for m in STATED.finditer(plain)
            if re.sub(r"\s+", "", m.group(0)) not in GIVEN]


def _prints(text: str, number: str) -> bool:
    """Does ``text`` print ``number`` digit for digit (not as part of a longer number: 4 is not
    in 4.5 or 14, 0.5 not in 0.55)?"""
    return re.search(rf"(?<![\d.]){re.escape(number)}(?!\d|\.\d)", text) is not None


def number_problems(master: Path) -> list[str]:
    """What is wrong with the numbers a master's text states: each ``[[number]]`` must be printed,
    digit for digit, by the lesson (or the one ``@NN`` names) as measured at its full size on its
    current code; each other decimal must be :data:`GIVEN`.  Empty when all is well."""
    import nbformat

    problems, outputs = [], {}

    def printed(stem: str) -> str | None:
        if stem not in outputs:
            m = measured(stem)
            fresh = m is not None and m.get("runs") is None and \
                m.get("code_sha256") == code_digest(masters_dir() / f"{stem}.ipynb")
            outputs[stem] = "\n".join(m["printed"]) if m is not None and fresh else None
        return outputs[stem]

    for cell in nbformat.read(master, as_version=4).cells:
        if cell.cell_type != "markdown":
            continue
        where = f"{master.stem}, cell {cell.get('id', '?')}"
        for number in untagged_numbers(cell.source):
            problems.append(f"{where}: {number!r} is neither tagged [[{number}]] (a result the "
                            f"lesson prints) nor a given constant (gpsaccel.lessons.GIVEN)")
        for number, other in PRINTED.findall(cell.source):
            stem = master.stem
            if other:
                found = [p.stem for p in masters() if p.stem.split("-")[0] == other]
                if len(found) != 1:
                    problems.append(f"{where}: [[{number} @{other}]] names no single lesson")
                    continue
                stem = found[0]
            text = printed(stem)
            if text is None:
                problems.append(f"{where}: [[{number}]] quotes {stem}, which is not measured at "
                                f"its full size on its current code (python -m gpsaccel.lessons "
                                f"measure {stem.split('-')[0]})")
            elif not _prints(text, number.strip()):
                problems.append(f"{where}: the text quotes {number}, which {stem} does not print")
    return problems


#: The line the release writes (from lessons/measured/) under each lesson's title.
_TIME_LINE = re.compile(r"^\*Running time:.*\*$", re.M)

#: What JupyterLab 4 writes into a notebook's metadata on save (kernel ipykernel, Python).  The
#: interpreter's version, which Lab also writes, differs between machines: :func:`pre_save` drops
#: it, so a lesson saved from ``make lab`` is byte for byte what the release wrote.
LAB_METADATA = {
    "kernelspec": {"display_name": "Python 3 (ipykernel)", "language": "python", "name": "python3"},
    "language_info": {"codemirror_mode": {"name": "ipython", "version": 3}, "file_extension": ".py",
                      "mimetype": "text/x-python", "name": "python", "nbconvert_exporter": "python",
                      "pygments_lexer": "ipython3"},
}
NBFORMAT_MINOR = 5

_LESSON_NAME = re.compile(r"^(?:(?:masters|solutions)/)?\d\d[a-z]?-[\w.-]+\.ipynb$")


def masters_dir() -> Path:
    return lessons_dir() / "masters"


def _tags(cell) -> list[str]:
    return list(cell.get("metadata", {}).get("tags", []))


def _clean(cell, hidden: bool = False):
    """A copy of ``cell`` with no outputs, no execution count and the collapse flag set or gone."""
    import copy

    cell = copy.deepcopy(cell)
    if cell["cell_type"] == "code":
        cell["outputs"], cell["execution_count"] = [], None
    meta = cell.setdefault("metadata", {})
    jupyter = {k: v for k, v in meta.get("jupyter", {}).items() if k != "source_hidden"}
    if hidden:
        jupyter["source_hidden"] = True
    if jupyter:
        meta["jupyter"] = jupyter
    else:
        meta.pop("jupyter", None)
    meta.pop("collapsed", None)
    meta.pop("execution", None)
    return cell


#: A code cell that took at least this long (s) when measured says so in its first line.
SLOW_CELL = 5.0


def _fill_text(cell, stem: str, measured: dict | None):
    """Markdown: ``[[number]]`` written plainly; the first cell gets its running-time line.  Code:
    a cell measured at :data:`SLOW_CELL` seconds or more starts with ``# Slow cell: about N s``
    (in words: a clock glyph is an empty box without an emoji font)."""
    if cell["cell_type"] == "code":
        seconds = (measured or {}).get("cell_seconds", {}).get(cell.get("id", ""), 0.0)
        if seconds >= SLOW_CELL:
            note = f"# Slow cell: about {_rounded(seconds)} (measured); the output appears when it is done"
            cell["source"] = note + "\n" + cell["source"]
        return cell
    if cell["cell_type"] != "markdown":
        return cell
    source = PRINTED.sub(r"\1", "".join(cell["source"]) if isinstance(cell["source"], list)
                         else cell["source"])
    if source.startswith("# "):
        line = running_time_line(measured)
        title, _, rest = source.partition("\n")
        rest = _TIME_LINE.sub("", rest).lstrip("\n")
        source = f"{title}\n\n{line}\n\n{rest}".rstrip("\n")
    cell["source"] = source
    return cell


def running_time_line(measured: dict | None) -> str:
    """The sentence under a lesson's title, from its measurement."""
    if not measured:
        return "*Running time: not measured yet (`python -m gpsaccel.lessons measure`).*"
    s, runs = measured["seconds"], measured.get("runs")
    size = "" if runs is None else f" with `GPSACCEL_LESSON_RUNS={runs}`"
    full = "" if runs is None else "; the lesson's full size takes longer (not measured)"
    return (f"*Running time: about {_rounded(s)} for Run All{size}, measured {s:.0f} s on a shared "
            f"2-core machine at load {measured.get('load', 0):.1f} (an unloaded laptop is faster)"
            f"{full}.*")


def _rounded(seconds: float) -> str:
    """A duration as a lesson states it: 5 s steps up to 90 s, then minutes to one decimal."""
    return f"{max(5, 5 * round(seconds / 5)):.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


def _notebook(cells, nb):
    import nbformat

    out = nbformat.v4.new_notebook()
    out.cells = cells
    out.metadata = json.loads(json.dumps(LAB_METADATA))
    for key, value in nb.metadata.items():
        if key not in ("kernelspec", "language_info", "widgets"):
            out.metadata[key] = value
    out.nbformat, out.nbformat_minor = 4, NBFORMAT_MINOR
    return out


#: How a solution cell starts in the solutions version.  JupyterLab shows a collapsed code cell's
#: first line in its placeholder: this line is what shows, not the solution's first step.  A
#: markdown cell shows its rendered text even when its source is hidden, so a markdown solution is
#: wrapped in ``<details>``: closed until the student opens it (JupyterLab and the HTML pages).
SOLUTION_LINE = {"code": "# Solution (open once you have tried)",
                 "markdown": "<details><summary>Solution (open once you have tried)</summary>"}


def _solution_first_line(cell):
    if cell["cell_type"] == "markdown":
        cell["source"] = f"{SOLUTION_LINE['markdown']}\n\n{cell['source']}\n\n</details>"
    else:
        cell["source"] = f"{SOLUTION_LINE['code']}\n{cell['source']}"
    return cell


def student_version(nb, stem: str, measured: dict | None = None):
    """No cell tagged ``solution``; outputs cleared (a student's first Run All is theirs, and the
    committed file stays what ``git pull`` can update); nothing collapsed."""
    cells = [_fill_text(_clean(c), stem, measured) for c in nb.cells if SOLUTION not in _tags(c)]
    return _notebook(cells, nb)


def solutions_version(nb, stem: str, measured: dict | None = None):
    """Every cell but the ``answer`` ones; each ``check`` below the solution cells that follow it
    (so it checks the solution's ``answer_…``); solutions collapsed; outputs cleared."""
    cells, pending = [], []
    for c in nb.cells:
        tags = _tags(c)
        if ANSWER in tags:
            continue
        if CHECK in tags:
            pending.append(_fill_text(_clean(c), stem, measured))
            continue
        if SOLUTION not in tags and pending:
            cells += pending
            pending = []
        cell = _fill_text(_clean(c, hidden=SOLUTION in tags), stem, measured)
        cells.append(_solution_first_line(cell) if SOLUTION in tags else cell)
    return _notebook(cells + pending, nb)


def lab_text(nb) -> str:
    """The notebook as JupyterLab's server writes it: nbformat's JSON (indent 1, sorted keys,
    non-ASCII kept) and a trailing newline."""
    import nbformat

    text = nbformat.writes(nb, version=4)
    return text if text.endswith("\n") else text + "\n"


def measured(stem: str) -> dict | None:
    path = lessons_dir() / "measured" / f"{stem}.json"
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else None


def released(master: Path) -> dict[Path, str]:
    """What the release writes for ``master``: {target path: text}."""
    import nbformat

    nb = nbformat.read(master, as_version=4)
    stem, m = master.stem, measured(master.stem)
    return {lessons_dir() / master.name: lab_text(student_version(nb, stem, m)),
            lessons_dir() / "solutions" / master.name: lab_text(solutions_version(nb, stem, m))}


def masters(only: list[str] | None = None) -> list[Path]:
    """Every master (any ``NN-topic.ipynb`` in lessons/masters/), or those starting with ``only``."""
    paths = sorted(p for p in masters_dir().glob("*.ipynb") if _LESSON_NAME.match(p.name))
    if only:
        paths = [p for p in paths if any(p.name.startswith(o) for o in only)]
        if not paths:
            raise ValueError(f"no master in {masters_dir()} starts with {' or '.join(only)}")
    return paths


def lessons_table() -> str:
    """The table of docs/lessons.md: each lesson, what it covers (its title) and its running time."""
    import nbformat

    rows = ["| lesson | covers | running time |", "|---|---|---|"]
    for master in masters():
        title = _title(nbformat.read(master, as_version=4)).split("—", 1)[-1].strip()
        m = measured(master.stem)
        said = f"about {_rounded(m['seconds'])}" if m else "not measured yet"
        rows.append(f"| `{master.stem}` | {title} | {said} |")
    return "\n".join(rows)


_TABLE = re.compile(r"(<!-- lessons-table -->\n).*?(<!-- /lessons-table -->)", re.S)


def docs_page() -> tuple[Path, str]:
    """docs/lessons.md with its table as the release writes it."""
    path = Path(__file__).resolve().parent.parent / "docs" / "lessons.md"   # the checkout's
    text = path.read_text(encoding="utf-8")
    return path, _TABLE.sub(lambda m: m.group(1) + lessons_table() + "\n" + m.group(2), text)


def release(only: list[str] | None = None) -> list[Path]:
    """Write the student and solutions versions of every master (and the table of
    docs/lessons.md); returns the notebooks written."""
    path, text = docs_page()
    if path.read_text(encoding="utf-8") != text:
        write_text(path, text)
    written = []
    for master in masters(only):
        for target, text in released(master).items():
            target.parent.mkdir(parents=True, exist_ok=True)
            if not target.exists() or target.read_text(encoding="utf-8") != text:
                write_text(target, text)
            written.append(target)
    return written


def code_digest(master: Path) -> str:
    """SHA-256 of a master's code cells: a measurement is stale once it changes."""
    import hashlib

    import nbformat

    nb = nbformat.read(master, as_version=4)
    code = "\n\0".join(c.source for c in nb.cells if c.cell_type == "code")
    return hashlib.sha256(code.encode()).hexdigest()


def measure(only: list[str] | None = None, runs: int | None = None) -> dict[str, float]:
    """Run each master's solutions version at its full size (or ``runs`` per ensemble, said so in
    the lesson): record its running time, the text its cells print (lessons/measured/) and the
    answers its solutions give (gpsaccel/exercises/answers.py)."""
    import time

    import nbformat

    from gpsaccel.exercises import RECORD_VARIABLE

    times = {}
    for master in masters(only):
        nb = solutions_version(nbformat.read(master, as_version=4), master.stem, measured(master.stem))
        with tempfile.TemporaryDirectory(prefix="gpsaccel-measure-") as tmp:
            path = Path(tmp) / master.name
            record = Path(tmp) / "answers.jsonl"
            path.write_text(lab_text(nb), encoding="utf-8")
            os.environ[RECORD_VARIABLE] = str(record)
            try:
                t0 = time.perf_counter()
                done = execute(path, timeout=900, runs=runs)
                seconds = time.perf_counter() - t0
                load = os.getloadavg()[0]
            finally:
                os.environ.pop(RECORD_VARIABLE, None)
            answers = [json.loads(line) for line in record.read_text().splitlines()] \
                if record.exists() else []
        printed = ["".join(_output_text(o) for o in c.get("outputs", []))
                   for c in done.cells if c.cell_type == "code"]
        data = {"seconds": round(seconds, 1), "load": round(load, 1), "runs": runs,
                "code_sha256": code_digest(master), "cell_seconds": _cell_seconds(done),
                "printed": printed}
        target = lessons_dir() / "measured" / f"{master.stem}.json"
        target.parent.mkdir(exist_ok=True)
        write_text(target, json.dumps(data, indent=1, ensure_ascii=False) + "\n")
        _write_answers(master.stem, answers)
        times[master.stem] = seconds
    return times


def _cell_seconds(nb) -> dict[str, float]:
    """{cell id: seconds} from the timing nbclient records in each executed code cell."""
    from datetime import datetime

    out = {}
    for c in nb.cells:
        timing = c.get("metadata", {}).get("execution", {})
        start, end = timing.get("iopub.execute_input"), timing.get("shell.execute_reply")
        if c.cell_type == "code" and start and end:
            d = datetime.fromisoformat(end.rstrip("Z")) - datetime.fromisoformat(start.rstrip("Z"))
            out[c["id"]] = round(d.total_seconds(), 1)
    return out


def _output_text(output) -> str:
    if output.get("output_type") == "stream":
        return output.get("text", "")
    data = output.get("data", {})
    return data.get("text/plain", "") + "\n" if "text/plain" in data and "image/png" not in data else ""


def _write_answers(stem: str, answers: list[dict]) -> None:
    """Replace lesson ``stem``'s entries (keys ``NN.k``) in gpsaccel/exercises/answers.py."""
    from gpsaccel.exercises import answers as module

    prefix = stem.split("-")[0] + "."
    table = {k: v for k, v in module.ANSWERS.items() if not k.startswith(prefix)}
    for a in answers:
        if not a["key"].startswith(prefix):
            raise ValueError(f"{stem}: a check names exercise {a['key']!r}; its keys start {prefix!r}")
        table[a["key"]] = a["value"]
    write_text(Path(module.__file__), answers_text(table))
    module.ANSWERS = table


def answers_text(table: dict) -> str:
    """gpsaccel/exercises/answers.py for ``table``: one entry per key, a long value (a matrix)
    wrapped under the project's line length."""
    import pprint

    lines = ['"""Generated by ``python -m gpsaccel.lessons measure`` from the masters\' solutions: '
             'do not edit."""', "", "ANSWERS: dict = {"]
    for k, v in sorted(table.items()):
        text = pprint.pformat(v, width=100 - len(repr(k)), compact=True)
        lines.append(f"    {k!r}: " + text.replace("\n", "\n" + " " * (len(repr(k)) + 6)) + ",")
    lines.append("}")
    return "\n".join(lines) + "\n"


def pre_save(model, path, **kwargs) -> None:
    """JupyterLab pre-save hook (``make lab`` sets it): a lesson is saved without outputs, execution
    counts or the interpreter's version, i.e. exactly as the release wrote it, so opening and
    running one leaves ``git status`` clean.  Other notebooks are saved untouched."""
    if model.get("type") != "notebook" or not _LESSON_NAME.match(path.lstrip("/")):
        return
    nb = model["content"]
    nb.get("metadata", {}).get("language_info", {}).pop("version", None)
    nb.get("metadata", {}).pop("widgets", None)
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "code":
            cell["outputs"], cell["execution_count"] = [], None
        cell.get("metadata", {}).pop("execution", None)


def main(argv: list[str] | None = None) -> int:
    """``python -m gpsaccel.lessons release|measure|check [NN ...]``."""
    import argparse

    p = argparse.ArgumentParser(prog="python -m gpsaccel.lessons", description=main.__doc__)
    p.add_argument("command", choices=("release", "measure", "check"),
                   help="release: write lessons/ and lessons/solutions/ from lessons/masters/; "
                        "measure: run each master at full size (time, printed text, answers), then "
                        "release; check: exit 1 if a released file differs from its master, or a "
                        "number its text states is neither printed by it nor given")
    p.add_argument("only", nargs="*", metavar="NN", help="only the masters starting with these")
    p.add_argument("--runs", type=int, default=None,
                   help="measure: runs per ensemble (default: each lesson's full size)")
    args = p.parse_args(argv)
    if args.command == "measure":
        for stem, s in measure(args.only, runs=args.runs).items():
            print(f"{stem:<40} {s:6.1f} s")
    if args.command in ("release", "measure"):
        print(f"wrote {len(release(args.only))} notebooks")
        return 0
    stale = [str(t) for m in masters(args.only) for t, text in released(m).items()
             if not t.exists() or t.read_text(encoding="utf-8") != text]
    print("\n".join(stale) or "every released lesson matches its master")
    numbers = [p for m in masters(args.only) for p in number_problems(m)]
    print("\n".join(numbers) or "every number the lessons state is tagged and printed, or given")
    return 1 if stale or numbers else 0


if __name__ == "__main__":
    raise SystemExit(main())
