"""A class as an LMS exports it, graded in the sandbox: grades.csv, feedback, the summary table
and figure, a regrade, stale feedback, Dask; the notebook-to-module step; the CLI (one
notebook's box: test_scoring.py)."""

from __future__ import annotations

import csv
import hashlib
import json
import os
import shutil

import nbformat
import pytest

from gpsaccel import _untrusted, registry
from gpsaccel.assignments import grading
from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments.questions import question_seed, variant_number
from gpsaccel.classrun import default_out, grade, notebooks, walk
from gpsaccel.cli import main
from gpsaccel.sandbox import zygote

from .._hostile import Started
from .conftest import CHI2_SPECIAL, read_grades, tracker_with_numpy_filter, write_variant

PHI = 'dt = 1 / VARIANT["rate_hz"]\nPhi = np.array([[1.0, dt, -dt**2 / 2],'
MEAN = "return float(np.mean([ei @ np.linalg.solve(Pi, ei) for ei, Pi in zip(e, P[:, -1])]))"
SECRET = b"class-test-secret-0123456789abcdef"
STUDENTS = ("Doe, Jane (1001)", "Smith John 1002", "blank 1003", "crash 1004", "hostile 1005")


def _class(sub):
    # the master's solution as it is (scipy.stats); the others' bounds with scipy.special
    write_variant("calibration", sub / STUDENTS[0] / "Calibration.IPYNB")
    write_variant("calibration", sub / STUDENTS[1] / "homework" / "calibration.ipynb",
                  [(PHI, PHI.replace("-dt**2", "+dt**2")),
                   (MEAN, MEAN.replace("np.mean", "np.sum")), CHI2_SPECIAL])
    write_variant("calibration", sub / STUDENTS[2] / "calibration.ipynb",
                  [("    return x_hat, P", "    return None")],
                  last_cell="Phi = Gamma = H = V = W = M0 = average_nees = nees_bounds = ...")
    write_variant("calibration", sub / STUDENTS[3] / "calibration.ipynb",
                  [("def average_nees(", "import os\nos._exit(3)\n\n\ndef average_nees(")])
    write_variant("calibration", sub / STUDENTS[4] / "calibration.ipynb",
                  [("    return x_hat, P",
                    "    import gpsaccel\n    r = gpsaccel.run_multirate(gpsaccel.CalibrationModel(), z)"
                    "\n    return r.x_hat, r.P"), CHI2_SPECIAL],
                  last_cell="import gpsaccel.check as c\nc.assert_submission = lambda *a, **k: None\n"
                            "Phi = Gamma = H = V = W = M0 = ...")
    (sub / "empty 1006").mkdir()
    (sub / "notes.txt").write_text("not a submission", encoding="utf-8")


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("lms")
    sub = root / "Homework 1 submissions"
    _class(sub)
    out = default_out(sub)
    (out / "feedback").mkdir(parents=True)
    (out / "feedback" / "dropped the course.txt").write_text("stale", encoding="utf-8")
    grades = grade(sub, "calibration", jobs=2, timeout=120, seed=2027, secret=SECRET,
                   warm_boxes=False)  # cold: test_warm_boxes_give_the_same_grades compares
    return {"sub": sub, "out": out, "grades": {g.student: g for g in grades},
            "csv": read_grades(out / "grades.csv"), "handed_in": _handed_in(sub)}


def _handed_in(sub):
    """Each file of the class and its SHA-256: a test that grades the class again and compares
    with the fixture's grades must grade these very notebooks (a test that hands one in again
    works on its own copy)."""
    return {str(p.relative_to(sub)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(sub.rglob("*")) if p.is_file()}


def test_output_is_beside_the_submissions_not_inside(graded):
    assert graded["out"].parent == graded["sub"].parent
    with pytest.raises(ValueError, match="inside the submissions"):
        grade(graded["sub"], "calibration", out=graded["sub"] / "grades")


def test_grades_csv_has_ids_points_possible_and_status(graded):
    rows = graded["csv"]
    assert rows["Points Possible"]["q1"] == "3" and rows["Points Possible"]["total"] == "10"
    want = {STUDENTS[0]: ("10", "graded"), STUDENTS[1]: ("8", "graded"),
            STUDENTS[2]: ("0", "graded"), STUDENTS[3]: ("7", "crashed"),
            STUDENTS[4]: ("6", "graded"), "empty 1006": ("0", "no-notebook")}
    got = {k: (v["total"], v["status"]) for k, v in rows.items() if k != "Points Possible"}
    assert got == want, {k: graded["grades"][k].feedback for k in graded["grades"]}
    assert rows[STUDENTS[0]]["file"] == f"{STUDENTS[0]}/Calibration.IPYNB"


def test_mistakes_lose_exactly_their_questions_with_the_checkers_codes(graded):
    g = graded["grades"][STUDENTS[1]]
    # partial credit: Φ is one of q1's six matrices, average_nees one of q3's two functions
    assert g.scores == {"q1": 2.5, "q2": 4.0, "q3": 1.5}
    assert g.codes["q3"] == ["nees-sum"] and g.codes["q1"] == ["phi-sign"]


def test_a_crash_names_the_students_cell_and_keeps_the_file_question(graded):
    g = graded["grades"][STUDENTS[3]]
    nb = nbformat.read(str(graded["sub"] / STUDENTS[3] / "calibration.ipynb"), as_version=4)
    cell = next(i for i, c in enumerate(nb.cells, 1) if "os._exit(3)" in c.source)
    assert f"stopped in cell {cell}" in g.feedback
    # q1 was answered before the crash and counts (issue 42); q3's cell crashed: not run
    assert g.scores == {"q1": 3.0, "q2": 4.0, "q3": 0.0} and g.codes["q3"] == ["not-run"]


def test_the_hostile_student_gets_nothing_from_the_package(graded):
    # its cell that patches the checker fails at the import (the box may not import it), so its
    # honest q1 and q3 stand; q2's file, which calls the package's filter, runs without gpsaccel
    g = graded["grades"][STUDENTS[4]]
    assert g.scores == {"q1": 3.0, "q2": 0.0, "q3": 3.0} and "uses-checker" in g.codes["q2"]
    assert "ImportError" in g.feedback


def test_feedback_once_each_without_answers_stale_files_removed(graded):
    fb = graded["out"] / "feedback"
    names = sorted(p.name for p in fb.iterdir())
    assert names == sorted(f"{_untrusted.student_id(s)}.txt" for s in (*STUDENTS, "empty 1006"))
    text = (fb / f"{_untrusted.student_id(STUDENTS[1])}.txt").read_text(encoding="utf-8")
    assert "nees-sum" in text and "Your variant: rate_hz = " in text
    lines = [ln for ln in text.splitlines() if ln.startswith("    - ")]
    assert len(lines) == len(set(lines))
    assert "test_q" not in text and "2026" not in text  # no hidden test, no seed
    blank = (fb / "blank 1003.txt").read_text(encoding="utf-8")
    assert "returns-none" in blank or "not-defined" in blank


def test_summary_table_and_figure(graded):
    with open(graded["out"] / "summary.csv", newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    q3 = [r for r in rows if r[:1] == ["q3"]]
    assert ["nees-sum", "1", "08", "The consistency test: NEES and its bounds"] in \
        [r[5:9] for r in q3]
    # two full marks (3 points) and one half (nees_bounds right) among six
    assert float(q3[0][2]) == pytest.approx(7.5 / 6)
    png = (graded["out"] / "summary.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    record = json.loads((graded["out"] / "grading.json").read_text(encoding="utf-8"))
    assert record["seed"] == 2027 and any("notes.txt" in n for n in record["skipped"])


def test_regrade_one_student_with_the_recorded_seed(graded, tmp_path):
    # on a copy of the class and its grades: the module's class stays as it was graded
    root = tmp_path / "lms"
    shutil.copytree(graded["sub"].parent, root)
    sub, out = root / graded["sub"].name, root / graded["out"].name
    write_variant("calibration", sub / STUDENTS[4] / "calibration.ipynb",  # handed in again
                  [CHI2_SPECIAL])
    again = grade(sub, "calibration", student=STUDENTS[4], secret=SECRET, timeout=120)
    rows = read_grades(out / "grades.csv")
    assert [g.total for g in again] == [10.0]
    assert rows[STUDENTS[4]]["total"] == "10" and rows[STUDENTS[1]]["total"] == "8"
    assert len(rows) == 7  # six students and the points-possible row


def test_dask_gives_the_same_grades(graded, tmp_path):
    """One notebook on a one-worker cluster (a worker and a notebook cost 3 CPU s each): the
    partly right one, whose every score and code must come back as the forked run gave them."""
    pytest.importorskip("dask.distributed")
    s = STUDENTS[1]
    nb = next(p for p in (graded["sub"] / s).rglob("*") if p.suffix.lower() == ".ipynb")
    (tmp_path / "one" / s).mkdir(parents=True)
    (tmp_path / "one" / s / "calibration.ipynb").write_bytes(nb.read_bytes())
    grades = grade(tmp_path / "one", "calibration", out=tmp_path / "out", seed=2027,
                   secret=SECRET, dask="dask-local", jobs=1, timeout=120)
    want = graded["grades"][s]
    assert [(g.student, g.status, g.scores, g.codes) for g in grades] == [
        (s, "graded", want.scores, want.codes)]


@pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on Linux")
def test_warm_boxes_give_the_same_grades(graded, tmp_path, monkeypatch):
    """The class again with every box forked from the run's zygotes (its notebooks' and its
    filters'): each student's status, scores, codes and feedback as the cold run gave them (the
    crash, the blank and the hostile notebook included), every box started warm."""
    assert _handed_in(graded["sub"]) == graded["handed_in"]  # the class the cold run graded
    started = Started()
    started.counting(monkeypatch)
    grades = grade(graded["sub"], "calibration", out=tmp_path / "warm", jobs=2, timeout=120,
                   seed=2027, secret=SECRET, warm_boxes=True)
    assert (started.cold, started.warm > 0) == (0, True)
    assert [(g.student, g.status, g.scores, g.codes, g.feedback) for g in grades] == [
        (g.student, g.status, g.scores, g.codes, g.feedback)
        for g in (graded["grades"][x.student] for x in grades)]
    assert len(grades) == len(graded["grades"])
    record = json.loads((tmp_path / "warm" / "grading.json").read_text(encoding="utf-8"))
    assert record["boxes"] == "warm"


def test_warm_boxes_where_they_cannot_start_warm_are_an_error(graded, tmp_path):
    with pytest.raises(ValueError, match=r"warm_boxes \(--boxes warm\): .*this machine's items"):
        grade(graded["sub"], "calibration", out=tmp_path / "o", dask="dask-local",
              warm_boxes=True)
    with pytest.raises(ValueError, match="warm_boxes must be True, False or None"):
        grade(graded["sub"], "calibration", out=tmp_path / "o", warm_boxes="yes")
    assert not (tmp_path / "o").exists()  # refused before anything was written


# ------------------------------------------------------------------------ the parts alone
def test_lms_layout_any_case_spaces_nothing_silent(tmp_path):
    for rel in ("A B/x.IpYnB", "C/one.ipynb", "C/two.ipynb", "D/sub/ship.ipynb",
                "D/sub/other.ipynb", "E.ipynb"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("{}", encoding="utf-8")
    (tmp_path / "F").mkdir()
    (tmp_path / "readme.md").write_text("", encoding="utf-8")
    os.symlink(tmp_path / "E.ipynb", tmp_path / "G.ipynb")
    entries, notes = walk(tmp_path, notebooks("ship"))
    got = {e.student: (e.path.name if e.path else e.problem[0]) for e in entries}
    assert got == {"A B": "x.IpYnB", "C": "ambiguous", "D": "ship.ipynb", "E": "E.ipynb",
                   "F": "no-notebook"}
    assert any("readme.md" in n for n in notes) and any("G.ipynb" in n for n in notes)


def test_variants_and_seeds_are_keyed_and_independent():
    a = variant_number(SECRET, "ship", "alice")
    assert a == variant_number(SECRET, "ship", "alice")
    assert a != variant_number(SECRET, "ship", "bob")
    assert a != variant_number(b"another secret of the instructor", "ship", "alice")
    assert question_seed(1, "ship", "q1", "alice") != question_seed(1, "ship", "q1", "bob")
    assert question_seed(1, "ship", "q1", "alice") != question_seed(2, "ship", "q1", "alice")


def test_ipython_syntax_is_handled_explicitly():
    nb = nbm.Notebook([nbm.Cell(1, "%matplotlib inline\n!pip install foo\nx = 1"),
                       nbm.Cell(2, "%%time\ny = x + 1"),
                       nbm.Cell(3, "%%writefile f.py\ndef f():\n    return 2")])
    src = nbm.module_source(nb, [nbm.Read("y", (), ((),), value=True)])
    compile(src, "notebook.py", "exec")
    assert "get_ipython().run_line_magic('matplotlib', 'inline')" in src
    assert "get_ipython().system('pip install foo')" in src
    assert nb.writefile("f.py")[1] == "def f():\n    return 2"


def test_cli_assignment_with_a_relative_out_and_grade(tmp_path, monkeypatch, capsys):
    # the tracker: its notebook grades in half the CPU of the ship's voyage
    monkeypatch.chdir(tmp_path)
    (tmp_path / "roster.txt").write_text("alice\nbob\n", encoding="utf-8")
    (tmp_path / "secret").write_bytes(SECRET)
    assert main(["assignment", "tracker", "--out", "dist/tracker", "--no-run-tests", "--roster",
                 "roster.txt", "--secret-file", "secret"]) == 0
    student = tmp_path / "dist" / "tracker" / "student" / "tracker.ipynb"
    assert student.is_file()
    mine = (tmp_path / "dist" / "tracker" / "students" / "alice" / "tracker.ipynb").read_text()
    v = grading.student_variant("tracker", "alice", SECRET)
    assert f"VARIANT = {v!r}" in mine and "BEGIN SOLUTION" not in mine
    sub = tmp_path / "class"
    tracker_with_numpy_filter(sub / "alice" / "tracker.ipynb")  # no filterpy in the file's box
    assert main(["grade", str(sub), "--assignment", "tracker", "--seed", "1", "--secret-file",
                 "secret"]) == 0
    assert "alice" in capsys.readouterr().out
    assert read_grades(tmp_path / "class-grades" / "grades.csv")["alice"]["total"] == "10"


@pytest.mark.parametrize("name", registry.assignments())
def test_packaged_student_side_is_the_masters_and_holds_no_solution(name, student_sides):
    from gpsaccel.assignments.generate import student_package_dir

    packaged = nbformat.read(str(student_package_dir() / name / f"{name}.ipynb"), as_version=4)
    fresh = nbformat.read(str(student_sides[name]), as_version=4)  # otter assign, once
    def body(nb):  # otter's own init cell (its blank lines vary) left out
        return [c.source for c in nb.cells if "otter.Notebook(" not in c.source]
    assert body(packaged) == body(fresh), (
        "the master changed: run gpsaccel.assignments.generate.refresh_student_package")
    text = json.dumps(packaged.dict())
    assert "BEGIN SOLUTION" not in text and "HIDDEN" not in text and "_graded" not in text


def test_the_notebook_module_is_data_and_calls_only():
    """What is generated per notebook holds no program: an import of the box-side module, a call
    of its guard with the hidden folders' modules (the list the sandbox fences, so the two
    cannot part) and a call of its start with the cells and reads as literals; a student's
    text that tries to close its string literal stays inside it."""
    import ast

    import numpy as np

    hostile = "x = 1\n'''\n\"\"\")\nimport os; os.system('ls')  # "
    nb = nbm.Notebook([nbm.Cell(2, hostile), nbm.Cell(5, "%time y = 1")])
    src = nbm.module_source(nb, [nbm.Read("f", (np.zeros(3),), ((3,), (2, 2))),
                                 nbm.Read("y", (), ((),), value=True)])
    body = ast.parse(src).body
    assert [type(n).__name__ for n in body] == ["ImportFrom", "Expr", "Assign"]
    assert body[0].module == "gpsaccel.boxside" and [a.name for a in body[0].names] == ["notebook"]
    guard, start = body[1].value, body[2].value
    assert isinstance(guard, ast.Call) and isinstance(start, ast.Call)
    assert ast.unparse(guard.func) == "_gpsaccel_box.guard"
    assert ast.literal_eval(guard.args[0]) == tuple(
        "gpsaccel." + rel.replace("/", ".") for rel in nbm.BOX_HIDES)
    assert ast.unparse(start.func) == "_gpsaccel_box.start"
    assert ast.unparse(start.args[0]) == "globals()"
    assert ast.literal_eval(start.args[1]) == [
        (2, hostile + "\n"), (5, "get_ipython().run_line_magic('time', 'y = 1')\n")]
    assert ast.literal_eval(start.args[2]) == [("f", False, [(3,), (2, 2)]), ("y", True, [()])]
    with pytest.raises(ValueError, match="Python name"):
        nbm.module_source(nb, [nbm.Read("f(); import os", ())])


def _unbound_names(test_source: str) -> set[str]:
    """The names a test function of ``test_source`` reads that it neither takes as a parameter,
    binds itself, nor finds in its file or in builtins."""
    import ast
    import builtins

    tree = ast.parse(test_source)
    module = {t.id for node in tree.body if isinstance(node, ast.Assign) for t in node.targets
              if isinstance(t, ast.Name)}
    module |= {a.asname or a.name.split(".")[0] for node in tree.body
               if isinstance(node, ast.Import | ast.ImportFrom) for a in node.names}
    unbound: set[str] = set()
    for fn in (n for n in tree.body if isinstance(n, ast.FunctionDef)):
        bound = {a.arg for a in fn.args.args + fn.args.kwonlyargs}
        bound |= {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)
                  and isinstance(n.ctx, ast.Store)}
        bound |= {a.asname or a.name.split(".")[0] for n in ast.walk(fn)
                  if isinstance(n, ast.Import | ast.ImportFrom) for a in n.names}
        bound |= {n.name for n in ast.walk(fn) if isinstance(n, ast.FunctionDef) and n is not fn}
        loads = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)
                 and isinstance(n.ctx, ast.Load)}
        unbound |= loads - bound - module - set(dir(builtins))
    return unbound


def test_unbound_names_finds_a_notebook_variable_read_without_a_parameter():
    src = ("import os\nname = 'q'\ndef test_q(f):\n    import math\n    g = f\n"
           "    return h(g, math, os, len)\n")
    assert _unbound_names(src) == {"h"}


@pytest.mark.parametrize("name", registry.assignments())
def test_public_tests_take_every_notebook_variable_they_use_as_a_parameter(name):
    """otter runs a public test (``grader.check``) as a module of its own and hands its test
    function only the notebook variables named as parameters: any other notebook name is a
    NameError for every student, right answer or not (coop's q2 read jacobian_A so), while
    ``otter assign`` runs the same test in the notebook's namespace and passes."""
    from gpsaccel.assignments.generate import student_package_dir

    packaged = nbformat.read(str(student_package_dir() / name / f"{name}.ipynb"), as_version=4)
    tests = packaged.metadata["otter"]["tests"]
    assert tests
    assert {q: _unbound_names(src) for q, src in tests.items()} == {q: set() for q in tests}
