"""The lessons: one master each (lessons/masters/), released as a student version (lessons/) without
any solution and a solutions version (lessons/solutions/); both are exactly what the release step
writes, so they cannot drift from the master.  The masters run (as their solutions version, at a
small ensemble) with ✓ under every self-check; the student versions run with no answer printed
(read from that same run: their code is its lesson cells, then unanswered cells).  Each is
executed once per content (conftest's ``executed_lesson``: a changed lesson or package
executes again)."""

from __future__ import annotations

import ast
import json
import re

import nbformat
import pytest

from gpsaccel import lessons as L
from gpsaccel.exercises.answers import ANSWERS
from gpsaccel.lessons import numbers

MASTERS = L.masters()
IDS = [p.stem for p in MASTERS]
SMALL_RUNS = 20
#: How the solutions versions run here: a small ensemble, and figures drawn (a label that cannot
#: be drawn raises) but not cropped, one draw less per figure: nobody looks at these pictures.
SMALL = {"runs": SMALL_RUNS, "crop_figures": False}
_CHECK_CALL = re.compile(r'self_check\("([^"]+)",\s*(answer_\w+)')


def _nb(path):
    return nbformat.read(path, as_version=4)


def _tagged(nb, tag):
    return [c for c in nb.cells if tag in c.metadata.get("tags", [])]


def test_masters_exist():
    assert len(MASTERS) >= 12


_WORDS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
          "eleven", "twelve", "thirteen", "fourteen", "fifteen", "sixteen", "seventeen", "eighteen",
          "nineteen", "twenty")
#: "sixteen Jupyter lessons", "the seventeen lessons", "Seventeen Jupyter notebooks", "16 lessons"
#: but not a share of them ("1 of the 4 notebooks declare a variant": the grader's words)
_COUNT = re.compile(rf"(?<!\d of the )\b({'|'.join(_WORDS)}|\d+)\s+(?:jupyter\s+)?"
                    r"(?:lessons|notebooks)\b", re.I)


def _stated_counts(text):
    return [int(w) if w.isdigit() else _WORDS.index(w.lower()) for w in _COUNT.findall(text)]


def test_the_count_reader_reads_words_and_digits():
    assert _stated_counts("teaches them in Sixteen\nJupyter lessons; the 12 lessons; two notebooks") \
        == [16, 12, 2]
    assert _stated_counts("says `1 of the 4 notebooks`: a copy of the eighteen lessons") == [18]


def test_every_page_counts_the_lessons_as_there_are_masters():
    """The README and every docs page that says how many lessons there are says the number of
    masters (a lesson added without updating a page fails here); the README, docs/index.md,
    docs/lessons.md and docs/student.md must say it."""
    root = L.lessons_dir().resolve().parent
    pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    must = {"README.md", "index.md", "lessons.md", "student.md"}
    for page in pages:
        counts = _stated_counts(page.read_text(encoding="utf-8"))
        assert all(c == len(MASTERS) for c in counts), (page.name, counts, len(MASTERS))
        assert counts or page.name not in must, f"{page.name} no longer says how many lessons"


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_released_versions_are_exactly_what_the_release_step_writes(master):
    for target, text in L.released(master).items():
        assert target.exists(), f"{target} missing: run `python -m gpsaccel.lessons release`"
        assert target.read_text(encoding="utf-8") == text, \
            f"{target} differs from its master: run `python -m gpsaccel.lessons release`"


def test_the_docs_table_is_what_the_release_writes():
    path, text = L.docs_page()
    assert path.read_text(encoding="utf-8") == text, "docs/lessons.md: run the release step"
    for master in MASTERS:
        assert f"`{master.stem}`" in text


def test_the_checkers_table_of_where_each_code_is_taught_is_what_the_release_writes():
    from gpsaccel._taught import TAUGHT

    path, text = L.checker_page()
    assert path.read_text(encoding="utf-8") == text, "docs/checker.md: run the release step"
    for code, section in TAUGHT.items():
        if not code[:1].isdigit():
            assert f"| `{code}` | [lesson {section.number}, {section.heading}](_lessons/" \
                   f"{section.notebook}#{section.anchor})" in text, code


def test_no_released_file_without_a_master():
    stems = {p.stem for p in MASTERS}
    for folder in (L.lessons_dir(), L.lessons_dir() / "solutions"):
        orphans = {p.stem for p in folder.glob("*.ipynb")} - stems
        assert not orphans, f"{folder}: {orphans} have no master"


def _solution_lines(nb):
    """The lines of the solution cells that say something (not a blank, a bracket, an import)."""
    for c in _tagged(nb, L.SOLUTION):
        for line in c.source.splitlines():
            s = line.strip()
            if len(s) >= 25 and not s.startswith(("import ", "from ", "#")):
                yield s


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_student_version_carries_no_solution_text(master):
    nb = _nb(master)
    student = _nb(L.lessons_dir() / master.name)
    text = "\n".join(c.source for c in student.cells)
    shared = [s for s in _solution_lines(nb) if s in text
              and not any(s in c.source for c in nb.cells if L.SOLUTION not in c.metadata.get("tags", []))]
    assert not shared, f"{master.name}: solution text in the student version: {shared[:3]}"
    assert not _tagged(student, L.SOLUTION)
    for c in student.cells:
        assert not c.get("outputs"), f"{master.name}: stored output in the student version"
        assert not c.metadata.get("jupyter", {}).get("source_hidden"), "nothing is collapsed"


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_no_visible_text_announces_a_solution(master):
    """A heading like "*Exercise 2, solution:* K₃₂" outside a solution cell states the answer."""
    for c in _nb(master).cells:
        if c.cell_type == "markdown" and L.SOLUTION not in c.metadata.get("tags", []):
            assert not re.search(r"(?i)exercise \d+, solution|\*\*solution", c.source), \
                f"{master.name}: visible cell announces a solution: {c.source[:80]!r}"


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_each_exercise_ends_with_its_answer_cell_and_self_check(master):
    student = _nb(L.lessons_dir() / master.name).cells
    prefix = master.stem.split("-")[0] + "."
    for i, c in enumerate(student):
        if L.CHECK in c.metadata.get("tags", []):
            key, name = _CHECK_CALL.search(c.source).groups()
            assert key.startswith(prefix), f"{master.name}: self-check key {key!r}"
            assert key in ANSWERS, f"{key}: no recorded answer (python -m gpsaccel.lessons measure)"
            before = student[i - 1]
            assert L.ANSWER in before.metadata.get("tags", []) and \
                before.source.startswith(f"{name} = None"), f"{key}: no answer cell right above"
    solutions = _nb(L.lessons_dir() / "solutions" / master.name)
    assert not _tagged(solutions, L.ANSWER)


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_solutions_never_need_a_name_only_a_solution_defines_later(master):
    """Static: a non-solution cell after a solution must not read a name only solutions assign
    (the student version, without them, would raise NameError)."""
    nb = _nb(master)
    defined_by = {"solution": set(), "other": set()}
    for c in nb.cells:
        if c.cell_type != "code":
            continue
        src = "\n".join(l for l in c.source.splitlines() if not l.startswith(("%", "!")))
        tree = ast.parse(src)
        kind = "solution" if L.SOLUTION in c.metadata.get("tags", []) else "other"
        stored = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        stored |= {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.ClassDef)}
        stored |= {(a.asname or a.name).split(".")[0] for n in ast.walk(tree)
                   if isinstance(n, ast.Import | ast.ImportFrom) for a in n.names}
        if kind == "other":
            loaded = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
            only = (loaded & defined_by["solution"]) - defined_by["other"] - stored
            assert not only, f"{master.name}: {sorted(only)} come only from a solution cell"
        defined_by[kind] |= stored


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_lab_form(master):
    """Saved as JupyterLab writes it: nbformat 4.5, ipykernel's kernelspec and language_info (no
    interpreter version), indent 1, trailing newline; so opening one changes nothing."""
    for path in L.released(master):
        text = path.read_text(encoding="utf-8")
        nb = json.loads(text)
        assert (nb["nbformat"], nb["nbformat_minor"]) == (4, L.NBFORMAT_MINOR)
        assert nb["metadata"]["kernelspec"] == L.LAB_METADATA["kernelspec"]
        assert nb["metadata"]["language_info"] == L.LAB_METADATA["language_info"]
        assert text == json.dumps(nb, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_running_time_is_measured_on_the_current_code(master):
    m = L.measured(master.stem)
    assert m is not None, f"{master.name}: never measured (python -m gpsaccel.lessons measure)"
    assert m["code_sha256"] == L.code_digest(master), \
        f"{master.name}: its code changed since its running time was measured: measure it again"
    first = _nb(L.lessons_dir() / master.name).cells[0].source
    assert L.running_time_line(m) in first


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_numbers_the_text_states_are_printed_by_the_code_or_given(master):
    """Every ``[[number]]`` of a master's text is, digit for digit, in what its cells printed
    when it was measured at full size on the current code; every other decimal it states is a
    given constant (``L.GIVEN``), so no untagged result can creep in."""
    problems = L.number_problems(master)
    assert not problems, "\n".join(problems)


def test_the_number_check_reads_decimals_and_skips_code_tags_and_given_constants():
    text = ("σ = 0.687 m, [[0.621]], `run(0.3)`, Δt = 0.005 s, 1.25·10⁻⁵, 4·10⁻⁵ and 2.6e-12, "
            "section 3.6.1, 40 steps, 10⁻¹², 1e-6 σ, 0.0016/1.0016, about 3.58.\n```\nx = 0.9\n```")
    assert L.untagged_numbers(text) == ["0.687", "4·10⁻⁵", "2.6e-12", "3.58"]
    assert L.PRINTED.findall("[[3.58 @04]], [[0.687]], [[−0.0034, −0.0005], [−0.0005, 0.0]]") == \
        [("3.58", "04"), ("0.687", "")]
    printed = "rank 4.5 of 14; σ = 0.55, 0.5; z = [0.04 3.58 2.48]"
    assert [numbers._prints(printed, n) for n in ("4", "0.5", "3.58", "0.55", "5", "2.4")] == \
        [False, True, True, True, False, False]


def test_the_number_check_finds_a_wrong_quote_an_untagged_result_and_a_bad_reference(tmp_path):
    """A copy of lesson 03 (same code, so its measurement holds) whose text quotes right and
    wrong numbers: only the wrong ones are reported."""
    master = L.masters(["03"])[0]
    nb = _nb(master)
    nb.cells = [c for c in nb.cells if c.cell_type == "code"] + [nbformat.v4.new_markdown_cell(
        "[[0.687]] and [[0.688]]; untagged 0.5123; [[3.58 @04]]; [[9.99 @04]]; [[1.0 @99]]")]
    fake = tmp_path / master.name
    nbformat.write(nb, fake)
    found = L.number_problems(fake)
    assert len(found) == 4, found
    assert "'0.5123'" in found[0] and "quotes 0.688" in found[1], found
    assert "quotes 9.99" in found[2] and "@99" in found[3], found


def test_pre_save_hook_saves_a_lesson_as_released():
    nb = {"cells": [{"cell_type": "code", "execution_count": 3, "outputs": [{"output_type": "stream"}],
                     "metadata": {"execution": {"x": 1}}, "source": "1"}],
          "metadata": {"language_info": {"name": "python", "version": "3.12.1"}, "widgets": {}}}
    model = {"type": "notebook", "content": json.loads(json.dumps(nb))}
    L.pre_save(model, "03-multirate-filter.ipynb")
    cell = model["content"]["cells"][0]
    assert cell["outputs"] == [] and cell["execution_count"] is None and cell["metadata"] == {}
    assert model["content"]["metadata"] == {"language_info": {"name": "python"}}
    mine = {"type": "notebook", "content": json.loads(json.dumps(nb))}
    L.pre_save(mine, "my-scratch.ipynb")
    assert mine["content"] == nb                      # a student's own notebook is left alone


def _outputs(cell) -> str:
    outputs = cell.get("outputs", [])
    return "".join(o.get("text", "") + o.get("data", {}).get("text/plain", "") for o in outputs)


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_solutions_version_runs_with_a_tick_under_every_self_check(master, executed_lesson):
    nb = executed_lesson(L.lessons_dir() / "solutions" / master.name, **SMALL)
    for c in _tagged(nb, L.CHECK):
        out = _outputs(c)
        assert out.startswith("✓") and "\n" == out[-1] and out.count("\n") == 1, \
            f"{master.name}: the self-check says {out!r} to the solution"


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_a_lesson_leaves_nothing_in_the_temporary_folder(master, executed_lesson):
    """Run All, then the kernel stopped as JupyterLab stops it: nothing the lesson made (a
    student's files it checks, the checker's boxes) is left in its TMPDIR (a private folder
    :func:`gpsaccel.lessons.execute` looks at; mkdtemp() was left behind on every run)."""
    nb = executed_lesson(L.lessons_dir() / "solutions" / master.name, **SMALL)
    assert nb.metadata["gpsaccel"]["left_in_tmp"] == [], master.name


def test_the_temporary_folder_check_sees_what_a_lesson_leaves(tmp_path):
    """A kernel's mkdtemp() is seen, its TemporaryDirectory removed at shutdown."""
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(
        "import tempfile\nkept = tempfile.TemporaryDirectory(prefix='kept-')\n"
        "left = tempfile.mkdtemp(prefix='left-')")]
    path = tmp_path / "t.ipynb"
    nbformat.write(nb, str(path))
    [left] = L.execute(path).metadata["gpsaccel"]["left_in_tmp"]
    assert left.startswith("left-")


_UNANSWERED = re.compile(r"answer_\w+ = None(\s*#[^\n]*)?")


@pytest.mark.parametrize("master", MASTERS, ids=IDS)
def test_student_version_runs_and_shows_no_answer(master, executed_lesson, monkeypatch):
    """The student version runs, prints no stray repr, and every self-check says "not answered".

    Without a second kernel: its code is the solutions version's lesson cells (every code cell up
    to the last untagged one, none of them a solution), unchanged and in order, then only
    ``answer_k = None`` cells and self-checks.  So it runs those lesson cells exactly as the
    solutions run above does (same ensemble; no lesson cell reads a file relative to its folder,
    the one thing that differs), and its outputs there are that run's; the answer and check
    cells are then run here, in one namespace, as the kernel would run them after."""
    import contextlib
    import io

    from gpsaccel.exercises import RECORD_VARIABLE

    def tags(c):
        return set(c.metadata.get("tags", []))

    student = [c for c in _nb(L.lessons_dir() / master.name).cells if c.cell_type == "code"]
    solved = [c for c in _nb(L.lessons_dir() / "solutions" / master.name).cells
              if c.cell_type == "code"]
    lesson = solved[:max(i for i, c in enumerate(solved) if not tags(c)) + 1]
    assert not any(tags(c) for c in lesson), f"{master.name}: a tagged cell among the lesson's"
    assert [(c.source, tags(c)) for c in student[:len(lesson)]] == \
        [(c.source, tags(c)) for c in lesson], f"{master.name}: the lesson cells differ"
    rest = student[len(lesson):]
    assert all(tags(c) in ({L.ANSWER}, {L.CHECK}) for c in rest), master.name
    assert all(_UNANSWERED.fullmatch(c.source.strip()) for c in rest if L.ANSWER in tags(c)), \
        [c.source for c in rest if L.ANSWER in tags(c)]

    ran = [c for c in executed_lesson(L.lessons_dir() / "solutions" / master.name,
                                      **SMALL).cells if c.cell_type == "code"]
    assert [c.source for c in ran[:len(lesson)]] == [c.source for c in lesson]
    outputs = [_outputs(c) for c in ran[:len(lesson)]]
    monkeypatch.delenv(RECORD_VARIABLE, raising=False)
    namespace: dict = {}
    for c in rest:
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            exec(compile(c.source, f"<{master.stem}: {c.source[:30]!r}>", "exec"), namespace)
        outputs.append(printed.getvalue())
        if L.CHECK in tags(c):
            out = outputs[-1]
            lines = out.rstrip("\n").split("\n")       # one verdict, wrapped (exercises.WIDTH)
            assert out.startswith("… ") and "not answered yet" in " ".join(out.split()) and \
                all(s.startswith("  ") for s in lines[1:]), out
    for out in outputs:
        assert "<function" not in out, f"{master.name}: a stray repr {out[:80]!r}"
