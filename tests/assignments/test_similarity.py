"""The similarity report against the class it reports on (issue 39 items 1-2, issue 42 item 6).

Engine tests run on records made the grader's way (answercode.record of a notebook's cells);
the class at the end is graded from notebooks, in the sandbox, to the written report.
"""

from __future__ import annotations

import csv
import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from gpsaccel.assignments import similarity

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import _similarity_classes as sc  # noqa: E402
import _similarity_copies as copies  # noqa: E402


def _bench():
    spec = importlib.util.spec_from_file_location("bench_similarity",
                                                  ROOT / "benchmarks" / "similarity.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def hw():
    return _bench().Homework()


def honest_class(n: int, seed: int) -> sc.Class:
    return sc.honest(n, np.random.default_rng(seed))


def test_a_ring_of_six_is_one_group_of_six(hw):
    rng = np.random.default_rng(3)
    c = honest_class(20, 3)
    ring = sc.plant(c, "q2", "all three", 6, rng)
    rep = hw.report(c)
    groups = [g for g in rep.groups if g.question == "q2"]
    assert [(g.size, set(g.students)) for g in groups] == [(6, set(ring))], rep.groups
    assert rep.compared == 26 and not rep.not_compared


def test_a_padded_copy_is_found_inside_its_source(hw):
    rng = np.random.default_rng(4)
    c = honest_class(10, 4)
    pair = sc.plant(c, "q2", "padded", 2, rng)
    source, copy = (c.answers[s]["q2"] for s in pair)
    assert copy.count("\n") > source.count("\n") + 80  # about 90 dead statements
    rep = hw.report(c)
    assert [set(g.students) for g in rep.groups] == [set(pair)]


def test_nothing_is_common_because_many_share_it(hw):
    """Twenty students handing in one answer among twenty honest ones: one group of twenty
    (the old rule dropped what more than a quarter of the class shared)."""
    rng = np.random.default_rng(5)
    c = honest_class(20, 5)
    ring = sc.plant(c, "q2", "renamed", 20, rng)
    rep = hw.report(c)
    assert [(g.size, set(g.students)) for g in rep.groups] == [(20, set(ring))]


def test_short_answers_are_never_flagged(hw):
    """Everyone hands in the published q1 and q3 verbatim: both are under the line (too short
    to tell a copy from the one way of writing it): no group, no published match."""
    c = honest_class(12, 6)
    q1, q3 = _bench()._master_answer("q1"), _bench()._master_answer("q3")
    for a in c.answers.values():
        a["q1"], a["q3"] = q1, q3
    rep = hw.report(c)
    assert not [g for g in rep.groups if g.question in ("q1", "q3")]
    assert not [m for m in rep.published if m.question in ("q1", "q3")]
    assert rep.short["q1"] == rep.short["q3"] == 12


def test_the_published_solution_is_named(hw):
    rng = np.random.default_rng(7)
    c = honest_class(10, 7)
    pasted = sc.plant(c, "q2", "all three", 1, rng, source=_bench()._master_answer("q2"))
    rep = hw.report(c)
    assert [(m.student, m.question, m.source) for m in rep.published] == \
        [(pasted[0], "q2", "the published solution of calibration q2")]
    lines = similarity.summary_lines(rep)
    assert "1 answer(s) matching the published solution" in lines[0]
    assert any("matches the published solution of calibration q2" in ln for ln in lines)


def test_a_notebook_that_cannot_be_compared_is_named_and_costs_nothing(hw):
    c = honest_class(6, 8)
    records = {s: hw.record(a) for s, a in c.answers.items()}
    records["bomb"] = {"why": "its notebook could not be read within the grader's limits"}
    records["damaged"] = {"questions": {"q2": {"tokens": 12}}}
    records["old"] = {}
    rep = similarity.report(records, "t", hw.boilerplate, hw.refs)
    assert rep.compared == 6
    assert set(rep.not_compared) == {"bomb", "damaged", "old"}
    assert "regrade" in rep.not_compared["old"]


def test_hidden_code_is_flagged_and_an_undefined_answer_that_scored(hw):
    import base64
    import zlib

    c = honest_class(4, 9)
    packed = base64.b64encode(zlib.compress(c.answers["student000"]["q3"].encode())).decode()
    c.answers["student000"]["q3"] = (f"import zlib, base64\n"
                                     f"exec(zlib.decompress(base64.b64decode('{packed}')))")
    records = {s: hw.record(a) for s, a in c.answers.items()}
    scores = {s: {"q1": 3.0, "q2": 4.0, "q3": 3.0} for s in records}
    rep = similarity.report(records, "t", hw.boilerplate, hw.refs, scores=scores)
    assert list(rep.hidden) == ["student000"]
    found = rep.hidden["student000"]
    assert any("exec of computed text (from zlib.decompress, base64.b64decode)" in f
               for f in found)
    assert any(f.startswith("q3: average_nees, nees_bounds scored 3") for f in found)
    # without points the undefined names alone are not a finding
    rep0 = similarity.report(records, "t", hw.boilerplate, hw.refs)
    assert not any(f.startswith("q3:") for f in rep0.hidden["student000"])


def test_the_report_files_hold_student_text_as_data(hw, tmp_path):
    c = honest_class(4, 10)
    rng = np.random.default_rng(10)
    evil = ['<script>alert(1)</script>', '=HYPERLINK("http://x")', "two\nlines\u202e"]
    for name in evil:
        c.answers[name] = dict(c.answers["student000"])
    c.answers[evil[0]]["q2"] = c.answers["student000"]["q2"].replace(
        "import numpy as np", "import numpy as np\n_ = '</pre><script>x()</script>'", 1)
    sc.plant(c, "q1", "renamed", 1, rng)
    rep = hw.report(c)
    similarity.write_report(rep, tmp_path)
    page = (tmp_path / "similarity.html").read_text(encoding="utf-8")
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    with open(tmp_path / "similarity.csv", newline="", encoding="utf-8") as f:
        cells = [x for row in csv.reader(f) for x in row]
    assert not any(x[:1] in "=+-@" and x for x in cells), cells
    assert any(evil[0] in x for x in cells)
    assert not any("\n" in x or "\u202e" in x for x in cells)
    assert "two\\x0alines\\u202e" in "".join(similarity.summary_lines(rep))


def _hub(codes: list[str], rng: np.random.Generator) -> dict[str, str]:
    """A student whose kalman_filter calls every filter in ``codes`` (red team, hub.py): each
    classmate's answer it holds passes the share, in the direction of the smaller answer."""
    import textwrap

    parts = ["import numpy as np", ""]
    for i, code in enumerate(codes):
        parts.append(f"def _make_{i}():\n" + textwrap.indent(code, "    ")
                     + "    return kalman_filter\n")
    calls = ", ".join(f"_make_{i}()(z)" for i in range(len(codes)))
    parts.append(f"def kalman_filter(z):\n    outs = [{calls}]\n    return outs[0]\n")
    answers = {q: g(rng) for q, g in sc.GENERATORS.items()}
    answers["q2"] = "\n".join(parts)
    return answers


def test_a_hub_of_generated_filters_joins_nobody_and_is_named(hw, tmp_path):
    """40 honest-style filters from the hub's own seed hold three honest classmates' answers
    (hub.py: before, the three were one group of four with the hub)."""
    c = honest_class(50, 3)
    rng = np.random.default_rng(99)
    c.answers["mallory"] = _hub([sc.q2(rng) for _ in range(40)], rng)
    rep = hw.report(c)
    assert not [g for g in rep.groups if g.question == "q2"], rep.groups
    (hub,) = rep.hubs
    assert (hub.question, hub.student, hub.parts) == ("q2", "mallory", 3)
    assert len(hub.matches) == 3 and "mallory" not in hub.matches
    assert not _bench().flagged(rep, "q2")  # the benchmark's false flags: none
    lines = similarity.summary_lines(rep)
    assert lines[0].endswith("0 not compared, 1 hub(s) (grades unchanged)"), lines[0]
    assert "  q2: hub: mallory matches 3 classmates in 3 groups that do not match one " \
        "another (look at it; no group is joined through it)" in lines
    similarity.write_report(rep, tmp_path)
    with open(tmp_path / "similarity.csv", newline="", encoding="utf-8") as f:
        rows = [r for r in csv.DictReader(f) if r["kind"] == "hub"]
    assert [(r["question"], r["students"]) for r in rows] == [("q2", "mallory")]
    assert rows[0]["detail"].endswith("; ".join(hub.matches))
    page = (tmp_path / "similarity.html").read_text(encoding="utf-8")
    assert "q2: mallory matches 3 classmates" in page
    assert ["q2", "", "", "", "", "integrity: a hub (matches classmates that do not match one "
            "another)", "1"] in similarity.summary_rows(rep)


def test_a_hub_of_classmates_code_leaves_a_real_ring_its_own_group(hw):
    """The hub holds ten classmates' real answers and a ring's: the class is not one group;
    the ring of four is found without the hub, and the hub names all it matches."""
    rng = np.random.default_rng(14)
    c = honest_class(10, 14)
    ring = sc.plant(c, "q2", "mixed", 4, rng)
    held = [a["q2"] for a in c.answers.values()]
    c.answers["mallory"] = _hub(held, rng)
    rep = hw.report(c)
    assert [set(g.students) for g in rep.groups if g.question == "q2"] == [set(ring)]
    (hub,) = rep.hubs
    assert hub.student == "mallory" and hub.parts == 11
    assert set(hub.matches) == set(c.answers) - {"mallory"}


def test_the_hub_rule_at_its_line():
    """Exact fingerprint sets: holding two answers that do not match each other makes a hub
    (HUB_PARTS = 2), and the pair those two make if they do match is still a group."""
    a, b = frozenset(range(200)), frozenset(range(1000, 1200))
    hub = a | b
    groups, hubs = similarity._groups("q2", ["a", "b", "hub"], [a, b, hub])
    assert groups == [] and hubs == [similarity.Hub("q2", "hub", ("a", "b"), 2)]
    copy = frozenset(range(5, 205))  # a's copy: 195 of 200 shared
    groups, hubs = similarity._groups("q2", ["a", "b", "copy", "hub"], [a, b, copy, hub])
    assert [(g.students, g.pairs) for g in groups] == [(("a", "copy"), (("a", "copy", 0.975),))]
    assert hubs == [similarity.Hub("q2", "hub", ("a", "b", "copy"), 2)]
    # one answer held in one other: a pair, as a real copy is (no hub)
    groups, hubs = similarity._groups("q2", ["a", "hub"], [a, hub])
    assert [g.students for g in groups] == [("a", "hub")] and hubs == []


def test_a_source_copied_twice_is_no_hub(hw):
    """An answer copied by two classmates whose copies match each other: one group of three,
    no hub (what the rule must not break)."""
    rng = np.random.default_rng(15)
    c = honest_class(10, 15)
    ring = sc.plant(c, "q2", "all three", 3, rng)
    rep = hw.report(c)
    assert [set(g.students) for g in rep.groups] == [set(ring)] and not rep.hubs


# ------------------------------------------------------------------------ published figures
@pytest.mark.slow
def test_the_table_in_the_docs_is_what_the_benchmark_measures(hw):
    bench = _bench()
    doc = bench.DOC.read_text(encoding="utf-8")
    published = doc.split(bench.BEGIN, 1)[1].split(bench.END, 1)[0].strip()
    assert published == bench.table(hw).strip()


def test_the_docs_state_the_thresholds_in_force():
    doc = " ".join((ROOT / "docs" / "grading.md").read_text(encoding="utf-8").split())
    from gpsaccel.assignments import fingerprint

    assert f"{similarity.MIN_PRINTS} fingerprints" in doc
    assert f"{similarity.SHARE:.0%} of the smaller answer" in doc
    assert f"{fingerprint.K} consecutive tokens" in doc


# ------------------------------------------------------------------------ a class, graded
def _notebook(path: Path, cells: list[str]) -> None:
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(s) for s in cells]
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, str(path))


@pytest.mark.slow
def test_a_hostile_class_graded_to_its_report(tmp_path, monkeypatch):
    """Graded from notebooks in the sandbox: the ring is one group, the padded copy is found,
    the magic bomb is "not compared" and the report is written, the pasted published solution
    is named, the packed answer is hidden code and keeps its grade."""
    import base64
    import zlib

    from gpsaccel.assignments import notebook as nbm
    from gpsaccel.classrun import grade_class

    from .conftest import solved

    monkeypatch.setattr(nbm, "LOAD_CPU", 1)  # the bomb stops at 1 CPU s, not 5
    rng = np.random.default_rng(12)
    c = honest_class(2, 12)
    ring = sc.plant(c, "q2", "mixed", 3, rng)
    pair = sc.plant(c, "q2", "padded", 2, rng)
    sub = tmp_path / "class"
    for student, answers in c.answers.items():
        _notebook(sub / student / "calibration.ipynb", sc.cells(answers))
    solution = solved("calibration")
    import nbformat

    (sub / "mallory").mkdir()
    nbformat.write(solution, str(sub / "mallory" / "calibration.ipynb"))
    honest = {q: g(rng) for q, g in sc.GENERATORS.items()}  # student000's q3, packed
    packed = base64.b64encode(zlib.compress(c.answers["student000"]["q3"].encode())).decode()
    honest["q3"] = f"import zlib, base64\nexec(zlib.decompress(base64.b64decode('{packed}')))"
    _notebook(sub / "packer" / "calibration.ipynb", sc.cells(honest))
    bomb = "\n".join(["%env A=1"] * 600)
    (sub / "bomb").mkdir()
    (sub / "bomb" / "calibration.ipynb").write_text(json.dumps({"cells": [
        {"cell_type": "code", "source": bomb, "metadata": {}, "outputs": []}] * 2}))
    out = tmp_path / "out"
    graded = grade_class(sub, "calibration", out=out, seed=1, jobs=2)  # the report with it
    grades = {g.student: g for g in graded.grades}
    assert grades["bomb"].status == "unreadable"
    assert grades["packer"].scores["q3"] == grades["student000"].scores["q3"] == 3.0
    lines = [ln for ln in graded.classwide if ln.startswith("similarity:")]
    assert (out / "similarity.html").is_file() and (out / "similarity.csv").is_file()
    with open(out / "similarity.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    kinds = {(r["kind"], r["question"], r["students"]) for r in rows}
    assert ("group", "q2", "; ".join(sorted(ring))) in kinds, rows
    assert ("group", "q2", "; ".join(sorted(pair))) in kinds, rows
    assert ("published solution", "q2", "mallory") in kinds
    assert ("not compared", "", "bomb") in kinds
    (why,) = [r["detail"] for r in rows if r["students"] == "bomb"]
    assert why == "its notebook could not be read within the grader's limits (status unreadable)"
    assert any(r["kind"] == "hidden code" and r["students"] == "packer" for r in rows)
    assert not any(r["kind"] == "hidden code" and r["students"] != "packer" for r in rows)
    assert "2 group(s) of copies, 1 answer(s) matching the published solution, 1 with hidden " \
        "code, 1 not compared" in lines[0], lines
    with open(out / "summary.csv", newline="", encoding="utf-8") as f:
        summary = [r for r in csv.reader(f) if r]
    assert summary[summary.index(["integrity report", "similarity.html", "", "", "", "", ""]):][1:] \
        == [["q2", "", "", "", "", "integrity: in a group of copies", "5"],
            ["q2", "", "", "", "", "integrity: matches the published solution", "1"],
            ["integrity", "", "", "", "", "hidden code", "1"],
            ["integrity", "", "", "", "", "not compared", "1"]], summary
    # the records travel with the grades: nothing was parsed again for the report
    data = json.loads((out / "grades.json").read_text(encoding="utf-8"))
    assert all(d["similarity"] for d in data if d["student"] != "bomb")


def _grade(student: str, sid: str, record: dict, status: str = "graded"):
    from gpsaccel.assignments.scoring import Grade

    return Grade(student, f"{sid}/calibration.ipynb", {"q1": 3.0, "q2": 4.0, "q3": 3.0},
                 {"q1": 3.0, "q2": 4.0, "q3": 3.0}, status, id=sid, similarity=record)


def test_the_class_report_from_grades_names_everyone_once(hw, tmp_path):
    """Two students whose names show alike (NFC and NFD folders) are two rows, each with its
    id; a run that did not finish is named as such; last year's export is compared with."""
    rng = np.random.default_rng(13)
    c = honest_class(4, 13)
    copy = dict(c.answers["student001"])
    copy["q2"] = copies.renamed(c.answers["student000"]["q2"], rng)
    grades = [_grade(s, s, hw.record(a)) for s, a in c.answers.items()]
    grades += [_grade("Zoë", "Zoe-1", hw.record(copy)), _grade("Zoë", "Zoe-2", {}),
               _grade("late", "late", {}, status="not-graded")]
    last_year = tmp_path / "2025"
    old = {q: g(rng) for q, g in sc.GENERATORS.items()}
    _notebook(last_year / "ann" / "calibration.ipynb", sc.cells(old))
    c.answers["student002"]["q2"] = copies.padded(old["q2"], rng)
    grades[2] = _grade("student002", "student002", hw.record(c.answers["student002"]))
    (last_year / "bob").mkdir()  # no notebook in it: said, never skipped silently
    rep = similarity.class_report(grades, "calibration",
                                  [("ann", last_year / "ann" / "calibration.ipynb"),
                                   ("bob", None)])
    assert [set(g.students) for g in rep.groups] == [{"student000", "Zoë [Zoe-1]"}]
    assert rep.not_compared == {
        "Zoë [Zoe-2]": "no record of its code (graded before this report existed: regrade it)",
        "late": "its grading did not finish (status not-graded): rerun it"}
    assert [(m.student, m.source) for m in rep.earlier] == [("student002",
                                                             "earlier submission ann")]
    assert rep.earlier_read == ["ann"] and rep.earlier_left == {"bob": "no notebook in it"}
    # the class run walks the folder of earlier submissions as it walks a class
    from gpsaccel.classrun.classwide import similar

    out = tmp_path / "out"
    out.mkdir()
    lines = similar(out, "calibration", grades, last_year)
    assert any(ln.startswith("  q2: student002 matches earlier submission ann") for ln in lines), \
        "\n".join(lines)
    assert "  earlier submissions: 1 compared with, 1 left out" in lines
    with open(out / "similarity.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert ("earlier submission left out", "bob") in {(r["kind"], r["students"]) for r in rows}


def test_compare_with_is_refused_where_it_cannot_be_honoured(tmp_path, capsys):
    """A folder that is not there, or no report to make the comparison in: exit 2, one line
    naming the flag, nothing graded."""
    from gpsaccel.classrun import grade_class
    from gpsaccel.cli import main

    sub = tmp_path / "class"
    _notebook(sub / "ann" / "calibration.ipynb", ["x = 1"])
    args = ["grade", str(sub), "--assignment", "calibration", "--out", str(tmp_path / "out")]
    assert main([*args, "--compare-with", str(tmp_path / "nowhere")]) == 2
    assert "--compare-with: " in capsys.readouterr().err
    assert main([*args, "--compare-with", str(sub), "--no-similarity"]) == 2
    assert "--compare-with: the comparison is the similarity report's" in capsys.readouterr().err
    with pytest.raises(ValueError, match="compare_with: .* and the similarity report asked for"):
        grade_class(sub, "calibration", out=tmp_path / "out", compare_with=sub, similarity=False)
    assert not (tmp_path / "out").exists()
