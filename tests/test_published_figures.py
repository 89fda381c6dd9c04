"""The figures the documentation publishes are what the benchmarks measured (issue 43: a page gave
a 118 MB Monte Carlo peak "including ≈100 MB of imports"; measured, 49.5 MiB).

``make bench`` (benchmarks/run.py) writes each script's table, ``docs/benchmarks/NAME.txt``, and
beside it ``NAME.json``: the figures the script published (benchmarks/_figures.py) and the
table's sha256.  Here, without running any benchmark:

* every table of docs/benchmarks/ that ``make bench`` writes is exactly the one written with its
  figures (a table typed or edited by hand, or one without its figures, fails; a side-by-side
  record run by hand says so in its first line, its command with its arguments);
* every figure a page of docs/ quotes with a marker, ``49.5 MiB<!-- bench: montecarlo_memory
  peak_mib/now/30 -->``, is within a factor :data:`TOLERANCE` of the figure measured (a stale
  page fails once ``make bench`` measures something else);
* a page that names a benchmark whose figures are published quotes them with markers.

A noisy machine does not fail this: nothing is timed here, and what the pages quote are CPU
seconds, peaks of memory and ratios, which a busy machine moves by far less than 2x (wall time
it stretches 8-20x; benchmarks/_cpu.py), so a ``make bench`` on a loaded machine keeps them in.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
BENCH = DOCS / "benchmarks"
TOLERANCE = 2.0

#: A quoted number (digits, thousands commas, a decimal point, an exponent), perhaps a unit, then
#: its marker naming the script (the JSON's stem) and the figure's key.
MARKER = re.compile(r"(?P<number>\d[\d,]*(?:\.\d+)?(?:[eE][-+]?\d+)?)[^\d<|]{0,12}?"
                    r"<!-- bench: (?P<script>[\w-]+) (?P<key>\S+) -->")
ANY_MARKER = re.compile(r"<!-- bench:")


def _made_by_bench() -> list[str]:
    """The scripts ``make bench`` runs (benchmarks/run.py's rule): their tables are sealed."""
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location("_bench_run", ROOT / "benchmarks" / "run.py")
    run = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(ROOT / "benchmarks"))  # run.py imports _figures from its folder
    try:
        spec.loader.exec_module(run)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return sorted(p.stem for p in (ROOT / "benchmarks").glob("*.py")
                  if not p.name.startswith("_") and p.name not in (*run.SEPARATE, "run.py"))


def _measured(script: str) -> dict[str, float]:
    path = BENCH / f"{script}.json"
    assert path.is_file(), f"{path.relative_to(ROOT)}: no figures measured (run make bench)"
    return json.loads(path.read_text(encoding="utf-8"))["figures"]


def off(text: str, measured) -> list[str]:
    """The quoted figures of ``text`` that are more than TOLERANCE away from ``measured(script)``
    (or that name no measured figure), one line each."""
    bad = []
    if len(MARKER.findall(text)) != len(ANY_MARKER.findall(text)):
        bad.append("a marker without a number right before it")
    for m in MARKER.finditer(text):
        quoted = float(m["number"].replace(",", ""))
        figures = measured(m["script"])
        if m["key"] not in figures:
            bad.append(f"{m['script']} {m['key']}: not a figure it publishes")
            continue
        value = figures[m["key"]]
        ratio = quoted / value if value else (1.0 if quoted == 0 else float("inf"))
        if not 1 / TOLERANCE <= ratio <= TOLERANCE:
            bad.append(f"{m['script']} {m['key']}: the page says {m['number']}, measured {value:.4g}")
    return bad


PAGES = sorted(DOCS.glob("*.md"))


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_quoted_figure_is_within_2x_of_what_make_bench_measured(page):
    assert not off(page.read_text(encoding="utf-8"), _measured), page.name


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_a_page_naming_a_benchmark_with_published_figures_quotes_them_with_markers(page):
    text = page.read_text(encoding="utf-8")
    quoted = {m["script"] for m in MARKER.finditer(text)}
    for script in _made_by_bench():
        path = BENCH / f"{script}.json"
        if f"benchmarks/{script}.py" in text and path.is_file() and _measured(script):
            assert script in quoted, f"{page.name} names benchmarks/{script}.py but quotes none " \
                                     f"of its figures with a marker"


def test_every_table_make_bench_writes_is_the_one_written_with_its_figures():
    """A table whose header is run.py's (the script's name alone: ``make bench``) has its figures
    beside it, and every set of figures its table, unchanged.  A record run by hand with its
    arguments in its header (``startup.py --before DIR``: a side-by-side with an earlier
    version) is not make bench's, and has no figures file."""
    for script in _made_by_bench():
        txt, record = BENCH / f"{script}.txt", BENCH / f"{script}.json"
        if record.exists():
            assert txt.is_file(), f"{script}: figures without their table (run make bench)"
            sealed = json.loads(record.read_text(encoding="utf-8"))["txt_sha256"]
            assert hashlib.sha256(txt.read_bytes()).hexdigest() == sealed, \
                f"docs/benchmarks/{script}.txt is not the table make bench wrote with its figures"
        elif txt.exists():
            first = txt.read_text(encoding="utf-8").split("\n", 1)[0]
            assert not first.startswith(f"`python benchmarks/{script}.py`,"), \
                f"docs/benchmarks/{script}.txt: make bench's table without its figures"


def test_the_reader_finds_a_stale_figure_and_a_marker_without_a_number():
    """The check itself: the issue's stale page, its fixed figure, a figure the script does not
    publish, and a marker with no number before it."""
    measured = {"montecarlo_memory": {"peak_mib/now/30": 49.4, "x": 0.0}}.__getitem__
    page = "| 30 s | 151 | {} MB<!-- bench: montecarlo_memory peak_mib/now/30 --> |"
    assert off(page.format("49.5"), measured) == []
    assert off(page.format("118"), measured) == [
        "montecarlo_memory peak_mib/now/30: the page says 118, measured 49.4"]
    assert off(page.format("1,234.5"), measured) != []
    assert off("0 s<!-- bench: montecarlo_memory x -->", measured) == []
    assert off("2 s<!-- bench: montecarlo_memory y -->", measured) == [
        "montecarlo_memory y: not a figure it publishes"]
    assert off("about<!-- bench: montecarlo_memory x -->", measured) == [
        "a marker without a number right before it"]
