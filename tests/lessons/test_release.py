"""What the release and the HTML rendering put in front of a student, checked without executing a
lesson: no remote script in a rendered page, an index a pip user can follow, solutions whose
collapsed placeholder gives nothing away, a slow cell's note in words."""

from __future__ import annotations

import nbformat
import pytest

from gpsaccel import lessons as L
from gpsaccel.lessons import render


def _notebook():
    nb = nbformat.v4.new_notebook()
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {"state": {}}}
    code = nbformat.v4.new_code_cell("print(1)", id="c1")
    code.outputs = [nbformat.v4.new_output("stream", text="1\n")]
    nb.cells = [nbformat.v4.new_markdown_cell("# Lesson 99 — x\n\n$a^2$", id="c0"), code]
    return nb


def test_a_rendered_lesson_loads_no_remote_script(tmp_path):
    """The stock lab template loads require.js, the widgets' manager and mermaid from CDNs (the
    check finds them: it can fail); the lessons' template loads nothing from another host."""
    nbconvert = pytest.importorskip("nbconvert")
    stock, _ = nbconvert.HTMLExporter(template_name="lab").from_notebook_node(_notebook())
    assert len(L.remote_scripts(stock)) >= 2, "the check no longer sees the stock template's CDN scripts"
    page, _ = L.html_exporter("mathjax/MathJax.js?config=TeX-AMS_CHTML").from_notebook_node(
        _notebook(), resources={"gpsaccel_mathjax_config": ""})
    assert L.remote_scripts(page) == []
    assert "require.js" not in page and "html-manager" not in page and "mermaid" not in page.lower()
    assert 'src="mathjax/MathJax.js' in page


@pytest.mark.parametrize("html", [
    '<script src="https://cdn.example/x.js"></script>', "<script type='module'>import m from "
    "'https://cdn.example/m.mjs'</script>", '<script src=//cdn.example/x.js></script>',
    '<link rel="stylesheet" href="http://x.example/a.css">'])
def test_the_remote_check_reads_every_way_a_page_loads_from_elsewhere(html):
    assert L.remote_scripts(html)
    assert not L.remote_scripts('<script src="mathjax/MathJax.js?config=x"></script>')


def test_the_index_tells_a_pip_user_what_to_run(tmp_path, monkeypatch):
    monkeypatch.setattr(render, "report_figures", lambda: {})
    text = L.write_index(tmp_path).read_text(encoding="utf-8")
    assert "gpsaccel lessons --copy" in text and "gpsaccel lab" in text
    assert "make lessons-html" not in text


def test_a_collapsed_solution_shows_a_neutral_first_line():
    """JupyterLab's placeholder for a collapsed code cell shows its first line: in the solutions
    version that line is the same for every solution, never the solution's first step; a
    markdown solution (rendered even when its source is hidden) is a closed <details>."""
    nb = nbformat.v4.new_notebook()
    sol = nbformat.v4.new_code_cell("x = secret_method()", id="s1")
    sol.metadata["tags"] = [L.SOLUTION]
    text = nbformat.v4.new_markdown_cell("Because of the method.", id="s2")
    text.metadata["tags"] = [L.SOLUTION]
    nb.cells = [sol, text]
    out = L.solutions_version(nb, "99-x").cells
    label = "Solution (open once you have tried)"       # no exercise said which: no number
    assert [c.source.splitlines()[0] for c in out] == [f"# {label}", f"<details><summary>{label}</summary>"]
    assert [c.metadata["gpsaccel"]["solution"] for c in out] == [label, label]  # the HTML's summary
    assert out[0].source.endswith("x = secret_method()")
    assert out[1].source.endswith("Because of the method.\n\n</details>")   # shown only when opened
    assert all(c.metadata["jupyter"]["source_hidden"] for c in out)


def test_each_collapsed_solution_names_its_exercise():
    """Three blocks after exercise 1 read alike ("Solution (click to reveal)", "Solution (open once
    you have tried)" twice) though the third solved exercise 2: each names its exercise, from the
    self-check before it, a cell opening "*Exercise 2" or an id ``solution-3``, in one wording."""
    def cell(kind, source, tags=(), id=None):
        c = (nbformat.v4.new_code_cell if kind == "code" else nbformat.v4.new_markdown_cell)(source)
        c.metadata["tags"], c.id = list(tags), id or c.id
        return c

    nb = nbformat.v4.new_notebook()
    nb.cells = [cell("code", "answer_1 = None", [L.ANSWER]),
                cell("code", 'self_check("09b.1", answer_1)', [L.CHECK]),
                cell("code", "answer_1 = 2.0", [L.SOLUTION]),
                cell("markdown", "Because.", [L.SOLUTION]),
                cell("markdown", "*Exercise 2, solution:*", [L.SOLUTION], id="ex09b5"),
                cell("code", "plot()", [L.SOLUTION], id="ex09s5"),   # an id's digit says nothing
                cell("markdown", "**Solution 3.** Algebra.", [L.SOLUTION]),
                cell("code", "more()", [L.SOLUTION], id="solution-4")]
    out = [c for c in L.solutions_version(nb, "09b-ship").cells if L.SOLUTION in c.metadata["tags"]]
    labels = [c.metadata["gpsaccel"]["solution"] for c in out]
    assert labels == [L.solution_label(k) for k in
                      ("09b.1", "09b.1", "09b.2", "09b.2", "09b.3", "09b.4")]
    assert labels[0] == "Solution to exercise 09b.1 (open once you have tried)"
    assert out[0].source.splitlines()[0] == "# " + labels[0]
    assert out[2].source.splitlines()[0] == f"<details><summary>{labels[2]}</summary>"


def test_an_exercise_listed_only_at_the_top_gets_its_prompt_above_its_solution():
    """Lesson 03's exercises 2-4 are asked only in its "## Exercises" list: the solutions version
    repeats each item above the first solution of that exercise; an exercise with a prompt cell
    of its own (exercise 2 here) is left as it is."""
    nb = nbformat.v4.new_notebook()
    listing = nbformat.v4.new_markdown_cell("## Exercises\n\n1. First [[0.687]] question,\n   "
                                            "continued.\n2. Second question.\n\nAfter the list.")
    own = nbformat.v4.new_markdown_cell("*Exercise 2:* the second, asked here.")
    sols = [nbformat.v4.new_markdown_cell(s) for s in ("*Exercise 1, solution:*", "*Exercise 2, solution:*")]
    for c in sols:
        c.metadata["tags"] = [L.SOLUTION]
    nb.cells = [listing, sols[0], own, sols[1]]
    assert L.exercise_prompts(nb) == {1: "First [[0.687]] question,\ncontinued.", 2: "Second question."}
    out = L.solutions_version(nb, "03-x").cells
    assert [c.source.splitlines()[0] for c in out[1:]] == [
        "*Exercise 1:* First 0.687 question,", f"<details><summary>{L.solution_label('03.1')}</summary>",
        "*Exercise 2:* the second, asked here.", f"<details><summary>{L.solution_label('03.2')}</summary>"]
    assert "jupyter" not in out[1].metadata                       # the prompt is not collapsed


def test_the_solutions_version_says_it_holds_the_solutions():
    """Every master's "How the exercises work" cell sends the student to `solutions/`; the
    solutions version (lessons/solutions/, `gpsaccel lessons --copy`'s and the site's) said the
    same while holding them.  It says what it is; the student version keeps the master's words."""
    from gpsaccel.lessons.release import SOLUTIONS_ELSEWHERE, SOLUTIONS_HERE, masters

    said = 0
    for master in masters():
        nb = nbformat.read(master, as_version=4)
        student = "\n".join(c.source for c in L.student_version(nb, master.stem).cells)
        solutions = "\n".join(c.source for c in L.solutions_version(nb, master.stem).cells)
        assert "not in this notebook" not in solutions, master.stem
        if SOLUTIONS_ELSEWHERE in student:
            said += 1
            assert SOLUTIONS_HERE in solutions, master.stem
    assert said >= 17                       # every lesson with exercises has the sentence


def test_a_master_denying_its_solutions_in_other_words_stops_the_release():
    """A reworded sentence would pass into the solutions version unreplaced: an error naming the
    lesson instead."""
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell("The answers are not in this notebook: see below.")]
    with pytest.raises(ValueError, match="^99-x: .*not in this notebook"):
        L.solutions_version(nb, "99-x")
    assert "not in this notebook" in L.student_version(nb, "99-x").cells[0].source


def test_a_slow_cell_says_so_in_words():
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("work()", id="c1")]
    (cell,) = L.student_version(nb, "99-x", {"seconds": 30, "cell_seconds": {"c1": 12.0}}).cells
    first = cell.source.splitlines()[0]
    assert first.startswith("# Slow cell: about 10 s (measured)")
    assert "⏱" not in cell.source


def test_the_answers_module_holds_a_matrix_within_the_line_length():
    table = {"10.2": [[0.5, -0.0, 0.014] * 4] * 6, "01.2": 7.779839051954151, "12.1": 25}
    text = L.answers_text(table)
    namespace: dict = {}
    exec(text, namespace)
    assert namespace["ANSWERS"] == table
    assert max(len(line) for line in text.splitlines()) <= 110


def test_measure_refuses_a_busy_machine_and_writes_nothing(monkeypatch, capsys):
    """The time `measure` writes into a lesson's header is what a student is told to expect: on a
    busy machine it refuses (exit 2, naming the load and the flag) before running anything."""
    import os

    from gpsaccel.lessons import __main__ as cli

    ran = []
    monkeypatch.setattr(cli, "measure", lambda *a, **k: ran.append(a) or {})
    monkeypatch.setattr(cli, "release", lambda *a, **k: ran.append(a) or [])
    monkeypatch.setattr(os, "getloadavg", lambda: (7.5, 7.0, 6.0))
    for argv in (["measure", "00"], ["measure", "00", "--max-load", "3"]):
        with pytest.raises(SystemExit) as stop:
            cli.main(argv)
        assert stop.value.code == 2
        err = capsys.readouterr().err
        assert "busy" in err and "7.5" in err and "--max-load" in err
    with pytest.raises(SystemExit):
        cli.main(["measure", "00", "--max-load", "0"])
    assert "--max-load must be > 0" in capsys.readouterr().err
    assert ran == []
    assert cli.main(["measure", "00", "--max-load", "8"]) == 0   # accepted: it runs
    assert len(ran) == 2
