"""Sphinx configuration of the gpsaccel documentation (``make docs``: warnings are errors).

Pages are MyST markdown (``docs/*.md``; a page another helper adds is picked up by the last
toctree of ``index.md``).  The lessons are rendered by myst-nb from their committed files with the
outputs stored in them, never executed here: the solutions' versions (``lessons/solutions/``) where
they exist, else the student versions, copied into ``docs/_lessons/`` with their solutions
collapsed.  Math is typeset by the MathJax 2.7 of ``jupyter-server-mathjax``, copied into the
site's ``_static/`` (:mod:`gpsaccel._mathjax`): the site works with no network.
"""

from __future__ import annotations

import gc
import json
import logging
import re
import sys
from pathlib import Path

# The build keeps every page's doctree (a heap of small objects, each linked to its parent):
# with the collector's default thresholds it walked that heap in 13 full collections, a fifth of
# the build's CPU.  Collections 14 times rarer for the young and no full one in a build: the same
# pages (the HTML byte for byte), the same peak memory within 4 %.
gc.set_threshold(10_000, 50, 1000)

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))

import gpsaccel  # noqa: E402
from gpsaccel import _mathjax  # noqa: E402

project = "gpsaccel"
author = "The gpsaccel maintainers"
copyright = "2026, The gpsaccel maintainers"
release = version = gpsaccel.__version__

extensions = [
    "myst_nb",  # MyST markdown pages and the notebooks (includes myst-parser)
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
]
exclude_patterns = ["_build", "**/.ipynb_checkpoints", "benchmarks/README.md"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist", "html_image"]
myst_heading_anchors = 3
myst_update_mathjax = False  # its settings are MathJax 3's; ours is MathJax 2 (below)
nb_execution_mode = "off"  # the lessons render with the outputs stored in them
nb_merge_streams = True
nb_code_prompt_show = "Show {type}"  # a solution, or a self-check cell
nb_code_prompt_hide = "Hide {type}"

html_theme = "pydata_sphinx_theme"
html_title = f"gpsaccel {version}"
html_static_path: list[str] = []
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2,
                      "secondary_sidebar_items": ["page-toc"]}
html_sidebars: dict[str, list[str]] = {}

# MathJax 2 from _static/mathjax (copied there when the build ends), not from a CDN
mathjax_path = _mathjax.url()
# Sphinx writes math as \(…\) and \[…\]: no dollar delimiters on the pages
mathjax2_config = {**_mathjax.HUB_CONFIG,
                   "tex2jax": {"inlineMath": [["\\(", "\\)"]], "displayMath": [["\\[", "\\]"]],
                               "processEscapes": True}}

autosummary_generate = True
# each object on the page of the module that defines it (gpsaccel.check re-exports its modules'
# functions under the modules' own names: documented twice otherwise)
autodoc_default_options = {"members": True, "show-inheritance": False, "ignore-module-all": True}
autodoc_typehints = "none"
# no function of gpsaccel has a signature type comment (``# type: (int) -> str``): with them off
# autodoc does not read and parse again the source of each of its 1300 functions and methods
autodoc_use_type_comments = False
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
suppress_warnings = ["mystnb.unknown_mime_type"]


# ---------------------------------------------------------------------------------- the lessons

LESSONS_OUT = DOCS / "_lessons"
#: A solution cell (tagged ``solution``) is collapsed whole, a self-check cell shows its output
CODE_TAGS = {"solution": "hide-cell", "check": "hide-input"}


def _lesson_sources() -> list[Path]:
    """Each lesson once: its solutions' version if there is one, else the student version."""
    student = sorted((ROOT / "lessons").glob("[0-9]*.ipynb"))
    solved = {p.name: p for p in (ROOT / "lessons" / "solutions").glob("*.ipynb")}
    return [solved.get(p.name, p) for p in student]


def _collapse(nb: dict) -> dict:
    """Solutions and self-checks collapsed, as they are in JupyterLab."""
    for cell in nb["cells"]:
        tags = cell.setdefault("metadata", {}).get("tags", [])
        if cell["cell_type"] == "code":
            cell["metadata"]["tags"] = tags + [CODE_TAGS[t] for t in tags if t in CODE_TAGS]
        elif "solution" in tags:
            source = "".join(cell["source"])
            cell["source"] = ('<details class="gpsaccel-solution"><summary>Solution (click to '
                              f'reveal)</summary>\n\n{source}\n\n</details>\n')
    return nb


def _write(path: Path, text: str) -> None:
    """Write only what changed, so that an incremental build re-reads only that."""
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def _write_lessons() -> None:
    """docs/_lessons/: the lessons to render and their index page."""
    LESSONS_OUT.mkdir(exist_ok=True)
    names = []
    for src in _lesson_sources():
        nb = _collapse(json.loads(src.read_text(encoding="utf-8")))
        _write(LESSONS_OUT / src.name, json.dumps(nb, indent=1))
        names.append(src.stem)
    for stale in set(LESSONS_OUT.glob("*.ipynb")) - {LESSONS_OUT / f"{n}.ipynb" for n in names}:
        stale.unlink()
    toc = "\n".join(names)
    _write(LESSONS_OUT / "index.md", f"""# The lessons

The course's Jupyter lessons, in reading order, rendered with the outputs and figures stored in
them; every solution is collapsed after its exercise (click to reveal). To run and change them:
`gpsaccel lessons --copy my-lessons`, then `gpsaccel lab my-lessons` (see [](../student.md)).

```{{toctree}}
:maxdepth: 1

{toc}
```
""")


_write_lessons()


# ------------------------------------------------------------------------------ the benchmarks

def _write_benchmarks() -> None:
    """docs/benchmarks/index.md: the tables ``make bench`` wrote next to it, each as printed."""
    folder = DOCS / "benchmarks"
    folder.mkdir(exist_ok=True)
    tables = sorted(folder.glob("*.txt"))
    parts = ["# Benchmarks\n",
             "Speed measured side by side, in one run per script, by `make bench` (which runs every "
             "script of `benchmarks/` and writes each one's output here; nothing on this page is "
             "typed by hand). The numbers are from the machine and the load named in each header.\n"]
    if not tables:
        parts.append("No table yet: run `make bench`, then `make docs`.\n")
    for table in tables:
        text = table.read_text(encoding="utf-8")
        header, _, body = text.partition("\n")
        parts.append(f"## {table.stem}\n\n{header}\n\n```text\n{body.rstrip()}\n```\n")
    _write(folder / "index.md", "\n".join(parts))


_write_benchmarks()


# ----------------------------------------------------------------------------- the API's pages

sys.path.insert(0, str(DOCS / "_ext"))
from stale_pages import remove_stale_pages  # noqa: E402

# a page autosummary wrote for a module since renamed or removed fails the build under -W; only
# those go, so every other page keeps its time stamp (docs/_ext/stale_pages.py)
remove_stale_pages(DOCS / "api" / "generated")


# ------------------------------------------------------------------------------- the docstrings

#: The docstrings are numpydoc with two habits of their own, made valid reStructuredText here
#: before numpydoc parses them (the source stays as it is):
#:
#: - absolute values written |x| (course notation), which reST reads as a substitution: escaped,
#:   outside ``literals`` (and ``*args``-style stars likewise);
#: - "name : what it is" lines (with indented continuation lines) outside a numpydoc section,
#:   for a result's fields: made a definition list; other indented lines after a paragraph get the
#:   blank line reST wants around a block quote; a section title numpydoc does not know
#:   ("Attributes (n = …)") becomes a bold paragraph.
_LITERAL = re.compile(r"(``.*?``)")
_FIELD = re.compile(r"^(\S[^:]{0,60}?) : (.+)$")
_SECTIONS = {"Parameters", "Returns", "Yields", "Receives", "Raises", "Warns", "Warnings",
             "Other Parameters", "Attributes", "Methods", "See Also", "Notes", "References",
             "Examples"}


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


_STARS = re.compile(r"(?<=[(\s,])(\*\*?)(?=[A-Za-z_]\w*[,)])")  # f(*args, **kwargs)


def _escape_bars(line: str) -> str:
    return "".join(p if p.startswith("``") else
                   _STARS.sub(lambda m: "\\*" * len(m.group(1)), p.replace("|", r"\|"))
                   for p in _LITERAL.split(line))


def _clean_docstring(app, what, name, obj, options, lines) -> None:
    out: list[str] = []
    literal_at = None  # indentation of the line that opened a literal block (::)
    in_section = False
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if literal_at is not None and line.strip() and _indent(line) <= literal_at:
            literal_at = None
        if literal_at is not None or in_section:
            out.append(_escape_bars(line) if literal_at is None else line)
            i += 1
            continue
        if line.strip() and set(nxt.strip()) == {"-"} and not line.startswith(" "):
            if line.strip() in _SECTIONS:
                in_section = True  # numpydoc's own from here on
                out.append(line)
                continue_at = i + 1
                out.append("-" * len(line.strip()))
                i = continue_at + 1
                continue
            out += ["", f"**{_escape_bars(line.strip())}**", ""]  # a title numpydoc ignores
            i += 2
            continue
        previous = out[-1] if out else ""
        field = _FIELD.match(line)
        if field and _indent(line) == 0:
            if previous.strip() and not _FIELD_TERM.get("open"):
                out.append("")
            out += [_escape_bars(field.group(1)), "    " + _escape_bars(field.group(2))]
            _FIELD_TERM["open"] = True
            i += 1
            continue
        if _FIELD_TERM.get("open") and line.strip() and _indent(line) == 0:
            out.append("")  # the definition list ends
            _FIELD_TERM["open"] = False
        elif _FIELD_TERM.get("open") and not line.strip():
            _FIELD_TERM["open"] = False
        elif (line.strip() and previous.strip() and _indent(line) != _indent(previous)
              and not previous.rstrip().endswith("::") and not _FIELD_TERM.get("open")):
            out.append("")  # a block quote starts or ends: reST wants a blank line
        if line.rstrip().endswith("::"):
            literal_at = _indent(line)
        out.append(_escape_bars(line))
        i += 1
    _FIELD_TERM["open"] = False
    lines[:] = out


_FIELD_TERM: dict[str, bool] = {}


#: With the cleaning above every docstring builds clean, so their problems are errors under -W
#: like the pages' own.  STRICT_DOCSTRINGS = False collects them in _build/docstring-warnings.txt
#: instead (counted at the end), for a merge that brings new ones until their owner fixes them.
STRICT_DOCSTRINGS = True
_docstring_problems: list[str] = []


class _DocstringFilter(logging.Filter):
    def filter(self, record) -> bool:
        location = getattr(record, "location", None)
        if hasattr(location, "source"):  # a docutils node
            location = f"{location.source}:{location.line}"
        location = str(location or "")
        if record.levelno >= logging.WARNING and "docstring of" in location:
            _docstring_problems.append(f"{location}: {record.getMessage()}")
            return False
        return True


def _report_docstrings(app, exception) -> None:
    out = Path(app.outdir).parent / "docstring-warnings.txt"
    out.unlink(missing_ok=True)
    if _docstring_problems:
        out.write_text("\n".join(_docstring_problems) + "\n", encoding="utf-8")
        print(f"docs: {len(_docstring_problems)} docstring formatting problems, listed in {out}")


def _copy_mathjax(app, exception) -> None:
    if exception is None and app.builder.format == "html":
        _mathjax.copy_to(Path(app.outdir) / "_static")


def _numpydoc_template_once() -> None:
    """numpydoc 1.11 compiles its one Jinja template again for every docstring and signature
    (2800 compilations, a quarter of the build's CPU): compiled once per loader here instead, from
    the same file with the same loader, so the pages are byte for byte the same."""
    from numpydoc import docscrape_sphinx, numpydoc

    made = numpydoc.get_doc_object
    templates: dict[bool, object] = {}

    def get_doc_object(obj, what=None, doc=None, config=None, builder=None):
        config, key = ({} if config is None else config), builder is not None
        if key not in templates:
            templates[key] = made(obj, what, doc, dict(config), builder).template
        config["template"] = templates[key]
        return docscrape_sphinx.get_doc_object_orig(
            obj, what=what, doc=doc, config=config, class_doc=docscrape_sphinx.SphinxClassDoc,
            func_doc=docscrape_sphinx.SphinxFunctionDoc, obj_doc=docscrape_sphinx.SphinxObjDoc)

    numpydoc.get_doc_object = get_doc_object


def _definitions_when_asked() -> None:
    """Sphinx's ModuleAnalyzer tokenizes every documented module a second time to find where each
    class and function is defined (a tenth of the build's CPU), which only ``literalinclude
    :pyobject:`` and sphinx.ext.viewcode ask for (``find_tags``), neither used here: that pass
    runs when ``find_tags`` is called instead, with the same code, so nothing changes on a page."""
    from sphinx.pycode import ModuleAnalyzer, parser

    if getattr(parser.Parser.parse_definition, "_deferred", False):
        return
    find = parser.Parser.parse_definition

    def parse_definition(self) -> None:
        self.definitions = {}  # find_tags below, when asked

    def find_tags(self):
        self.analyze()
        if not self.tags:
            found = parser.Parser(self.code)
            find(found)
            self.tags = found.definitions
        return self.tags

    parse_definition._deferred = True  # type: ignore[attr-defined]
    parser.Parser.parse_definition = parse_definition  # type: ignore[method-assign]
    ModuleAnalyzer.find_tags = find_tags  # type: ignore[method-assign]


def _stems_once() -> None:
    """The search index stems each word of each page with the pure-Python Snowball stemmer,
    memoised per page only (35 000 calls, a tenth of the build's CPU): memoised per build here;
    the stemmer is a function of the word, so the index is the same."""
    from sphinx.search.en import SearchEnglish

    if getattr(SearchEnglish.stem, "_memo", None) is not None:
        return
    stem, memo = SearchEnglish.stem, {}

    def stem_once(self, word: str) -> str:
        if word not in memo:
            memo[word] = stem(self, word)
        return memo[word]

    stem_once._memo = memo  # type: ignore[attr-defined]
    SearchEnglish.stem = stem_once  # type: ignore[method-assign]


def setup(app):
    _numpydoc_template_once()
    _definitions_when_asked()
    _stems_once()
    app.connect("autodoc-process-docstring", _clean_docstring, priority=400)  # before numpydoc
    if not STRICT_DOCSTRINGS:
        for handler in logging.getLogger("sphinx").handlers:
            handler.filters.insert(0, _DocstringFilter())  # before -W counts it
        app.connect("build-finished", _report_docstrings)
    app.connect("build-finished", _copy_mathjax)
