"""Every figure each course report lists is walked through in a lesson; the HTML pages show them.

A lesson walks through a figure in a markdown cell that names it ("Report 004, figures 9–11")
directly before the code cell that draws it.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import pytest

from gpsaccel.lessons import lessons_dir, report_figures
from gpsaccel.lessons.render import _mentions

LESSONS = sorted(lessons_dir().glob("*.ipynb"))


def _walked_through() -> dict[tuple[str, str], list[str]]:
    shown: dict[tuple[str, str], list[str]] = {}
    for path in LESSONS:
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        for cell, nxt in zip(cells, cells[1:] + [None], strict=True):
            if cell["cell_type"] == "markdown" and nxt is not None and nxt["cell_type"] == "code":
                for key in _mentions("".join(cell["source"])):
                    shown.setdefault(key, []).append(path.stem)
    return shown


def test_mentions_parse_ranges_lists_and_letters():
    assert _mentions("**Report 004, figures 1–3 and 9**; report 000, figure 3b; Report 002, "
                     "figures 8/9, 10, 11") == [
        ("004", "1"), ("004", "2"), ("004", "3"), ("004", "9"), ("000", "3b"), ("002", "8"),
        ("002", "9"), ("002", "10"), ("002", "11")]


@pytest.mark.parametrize("report", list(report_figures()))
def test_every_listed_figure_is_walked_through_in_a_lesson(report):
    shown = _walked_through()
    missing = [n for n in report_figures()[report] if (report, n) not in shown]
    assert not missing, f"report {report}: figures {missing} are in no lesson"


def test_solutions_are_collapsed_in_the_solutions_version_only():
    """The solutions version (the rendered site's source) shows each solution collapsed; the
    student version has none, and nothing collapsed (JupyterLab would show a first line anyway)."""
    n = 0
    for path in LESSONS:
        for folder, hidden in ((path.parent / "solutions", True), (path.parent, False)):
            for cell in json.loads((folder / path.name).read_text(encoding="utf-8"))["cells"]:
                tags = cell["metadata"].get("tags", [])
                collapsed = bool(cell["metadata"].get("jupyter", {}).get("source_hidden"))
                assert collapsed == (hidden and "solution" in tags), f"{folder.name}/{path.name}"
                n += hidden and "solution" in tags
    assert n > 0


def test_cell_ids_are_unique_and_stable(tmp_path):
    for path in LESSONS:
        ids = [c["id"] for c in json.loads(path.read_text(encoding="utf-8"))["cells"]]
        assert len(ids) == len(set(ids)) and all(ids), path.name


def _browser() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if shutil.which(name):
            return shutil.which(name)
    return None


def test_rendered_lesson_and_index_in_a_headless_browser(lesson_02_html):
    """Lesson 02 and the index as ``gpsaccel lessons --html`` renders them (conftest's
    ``lesson_02_html``: the solutions version at 10 runs), loaded in headless Chromium: read
    back the DOM."""
    browser = _browser()
    if browser is None:
        pytest.skip("no Chromium/Chrome installed (apt-get install chromium)")
    tmp_path, returncode, _, err = lesson_02_html
    assert returncode == 0, err
    solution = "Solution to exercise 02.1 (open once you have tried)"
    for page, must in [("02-error-model.html", ["Deriving", "<img", solution]),
                       ("index.html", ["02-error-model.html", "Report 004"])]:
        dom = subprocess.run(
            [browser, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom",
             (tmp_path / page).as_uri()], capture_output=True, text=True, timeout=120).stdout
        for text in must:
            assert text in dom, f"{page}: {text!r} not in the page the browser built"
