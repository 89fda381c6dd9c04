"""The documentation site: it builds with warnings as errors, and opened in headless Chromium with
no network it shows typeset math (MathJax's output, no raw ``$…$`` or ``\\(``), working internal
links and every lesson.  Skips where Sphinx or Chromium is missing.

``GPSACCEL_DOCS_HTML`` names a site already built by ``make docs`` (CI builds it once, then runs
these tests on it); otherwise the site is built once per content (18 CPU s) into the suite's disk
cache (tests/conftest.py), keyed by every file Sphinx reads: docs/ (not what it writes there),
lessons/, the package and the versions of Sphinx and its extensions.  The links test is the
quick run's one test of the docs (tests/conftest.py KEPT); the browser tests are slow.
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

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "",
                             shutil.which("chromium-browser") or "") if p and os.path.exists(p)),
                None)


#: What Sphinx writes into docs/ itself (conf.py): not part of what the site is built from.
_WRITTEN = ("_build", "_lessons", "api/generated", "benchmarks/index.md")
_SPHINX = ("sphinx", "myst-nb", "myst-parser", "pydata-sphinx-theme", "numpydoc",
           "jupyter-server-mathjax")


def _sources_digest() -> bytes:
    """sha256 over the files Sphinx reads (the package is in every disk-cache key already) and the
    versions of Sphinx and its extensions."""
    import hashlib
    import importlib.metadata as md

    h = hashlib.sha256()
    for name in _SPHINX:
        try:
            h.update(f"{name}={md.version(name)};".encode())
        except md.PackageNotFoundError:
            h.update(f"{name}=none;".encode())
    docs = ROOT / "docs"
    files = [p for p in docs.rglob("*") if p.is_file() and not any(
        p.relative_to(docs).as_posix().startswith(w) for w in _WRITTEN)]
    files += [p for p in (ROOT / "lessons").rglob("*") if p.is_file()]
    for path in sorted(files):
        if "__pycache__" not in path.parts and ".ipynb_checkpoints" not in path.parts:
            h.update(path.relative_to(ROOT).as_posix().encode() + b"\0" + path.read_bytes())
    return h.digest()


@pytest.fixture(scope="module")
def site(disk_cache) -> Path:
    given = os.environ.get("GPSACCEL_DOCS_HTML")
    if given:
        assert (Path(given) / "index.html").is_file(), f"GPSACCEL_DOCS_HTML={given} holds no site"
        return Path(given)
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")

    def build(target: Path) -> None:
        proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html",
                               "-q", str(ROOT / "docs"), str(target)], capture_output=True,
                              text=True, env=dict(os.environ, MPLBACKEND="Agg"), timeout=1800)
        assert proc.returncode == 0, proc.stderr[-3000:]

    return disk_cache.path("docs", disk_cache.key("site", _sources_digest()), build)


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


@pytest.mark.slow
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
