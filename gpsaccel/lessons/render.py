"""The lessons as HTML pages (``gpsaccel lessons --html``): executed, figures embedded, math
typeset offline, and an index that links each report's figure to the lesson walking through it."""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

from gpsaccel._atomic import write_text
from gpsaccel.lessons import lessons_dir
from gpsaccel.lessons.kernel import execute


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

    return HTMLExporter(extra_template_basedirs=[str(Path(__file__).parent.parent / "templates")],
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
    report's figure module: :func:`gpsaccel.registry.report_figures`, which the figures package
    declares when imported)."""
    import gpsaccel.figures  # noqa: F401 - declares the report modules to the registry
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
