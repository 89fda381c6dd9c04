"""The documentation site: it builds with warnings as errors, and opened in headless Chromium with
no network it shows typeset math (MathJax's output, no raw ``$…$`` or ``\\(``), working internal
links and every lesson.  Skips where Sphinx or Chromium is missing.

``GPSACCEL_DOCS_HTML`` names a site already built by ``make docs`` (CI builds it once); otherwise the
test builds one into a temporary folder.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

pytestmark = pytest.mark.slow  # a Sphinx build, a browser

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "",
                             shutil.which("chromium-browser") or "") if p and os.path.exists(p)),
                None)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    given = os.environ.get("GPSACCEL_DOCS_HTML")
    if given:
        assert (Path(given) / "index.html").is_file(), f"GPSACCEL_DOCS_HTML={given} holds no site"
        return Path(given)
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    out = tmp_path_factory.mktemp("site") / "html"
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q",
                           str(ROOT / "docs"), str(out)], capture_output=True, text=True,
                          env=dict(os.environ, MPLBACKEND="Agg"), timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


class _Page(HTMLParser):
    """Links, ids, image count, MathJax output elements and the visible text of a page."""

    SKIP = {"script", "style", "pre", "code", "textarea"}

    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()
        self.images = 0
        self.mathjax = 0
        self.text: list[str] = []
        self._skip = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "a" and a.get("href"):
            self.links.append(a["href"])
        if tag == "img":
            self.images += 1
        if "MathJax" in (a.get("class") or "").split():
            self.mathjax += 1
        if tag in self.SKIP:
            self._skip += 1

    def handle_endtag(self, tag):
        if tag in self.SKIP and self._skip:
            self._skip -= 1

    def handle_data(self, data):
        if not self._skip:
            self.text.append(data)


def _parse(html: str) -> _Page:
    page = _Page()
    page.feed(html)
    return page


def _dom(page: Path, tmp_path: Path) -> str:
    """The page's DOM after its scripts ran, in headless Chromium with no network."""
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'chromium'}", "--virtual-time-budget=30000",
           "--dump-dom", page.as_uri()]
    if shutil.which("unshare") and subprocess.run(["unshare", "-n", "true"]).returncode == 0:
        cmd = ["unshare", "-n", *cmd]  # no network at all: MathJax must come from the site
    else:
        pytest.skip("unshare -n (a network namespace) is not available to cut the network")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)  # a hang guard
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


RAW_MATH = re.compile(r"\\\(|\\\[|(?<![\w$])\$[^\s$][^$\n]{0,200}\$(?![\w$])")


def _lessons() -> list[str]:
    return sorted(p.stem for p in (ROOT / "lessons").glob("[0-9]*.ipynb"))


def test_every_internal_link_resolves_and_every_lesson_is_there(site):
    pages = {p.relative_to(site).as_posix(): p for p in site.rglob("*.html")}
    parsed = {name: _parse(p.read_text(encoding="utf-8")) for name, p in pages.items()}
    broken = []
    for name, page in parsed.items():
        for href in page.links:
            parts = urlsplit(href)
            if parts.scheme or href.startswith(("mailto:", "//")):
                continue
            target = (pages[name].parent / unquote(parts.path)).resolve() if parts.path \
                else pages[name].resolve()
            if not target.exists():
                broken.append(f"{name}: {href}")
            elif parts.fragment and target.suffix == ".html":
                ids = parsed[target.relative_to(site.resolve()).as_posix()].ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{name}: {href} (no such anchor)")
    assert not broken, broken[:20]
    index = parsed["_lessons/index.html"]
    for stem in _lessons():
        assert f"{stem}.html" in index.links, f"the lessons' index does not link {stem}"
        lesson = parsed[f"_lessons/{stem}.html"]
        solved = ROOT / "lessons" / "solutions" / f"{stem}.ipynb"
        if solved.exists() and "image/png" in solved.read_text(encoding="utf-8"):
            assert lesson.images, f"{stem}: the stored figures are not rendered"
    for guide in ("student", "instructor", "comparing-filters", "design", "api/index"):
        assert f"{guide}.html" in " ".join(parsed["index.html"].links), guide


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
def test_math_is_typeset_offline_in_a_browser(site, tmp_path):
    """MathJax comes from the site itself (the network is cut): its output elements are on the
    page and no TeX is left raw in the text."""
    first = _lessons()[0]
    for name in ("comparing-filters.html", f"_lessons/{first}.html"):
        html = (site / name).read_text(encoding="utf-8")
        assert "cdn" not in re.findall(r'<script[^>]*src="([^"]*MathJax[^"]*)"', html)[0].lower()
        page = _parse(_dom(site / name, tmp_path))
        assert page.mathjax > 0, f"{name}: no typeset math (MathJax did not run)"
        text = "".join(page.text)
        raw = RAW_MATH.findall(text)
        assert not raw, f"{name}: TeX left raw: {raw[:5]}"


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed")
def test_a_lessons_html_typesets_its_math_offline(lesson_02_html, tmp_path):
    """``gpsaccel lessons --html``: MathJax is copied next to the pages and loaded from there
    (the CLI's one rendering of lesson 02, conftest's ``lesson_02_html``)."""
    out, returncode, _, err = lesson_02_html
    assert returncode == 0, err
    page = out / "02-error-model.html"
    html = page.read_text(encoding="utf-8")
    (src,) = re.findall(r'<script[^>]*src="([^"]*MathJax\.js[^"]*)"', html)
    assert src.startswith("mathjax/MathJax.js?config=")
    assert (out / "mathjax" / "MathJax.js").is_file()
    dom = _parse(_dom(page, tmp_path))
    assert dom.mathjax > 0, "no typeset math in the lesson's HTML"
    assert not RAW_MATH.findall("".join(dom.text))
