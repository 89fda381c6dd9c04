"""When the box reads a notebook's answers and which reads grade a stopped notebook
(:mod:`gpsaccel.assignments.snapshots`): the answer cells found in the student's text, the plan
of calls, the one group that grades.  No box here (tests/assignments/test_keep.py runs them)."""

from __future__ import annotations

import pytest

from gpsaccel.assignments import notebook as nbm
from gpsaccel.assignments import snapshots as sn

Q1 = ["Phi", "V"]
Q3 = ["average_nees"]


def _last(*cells: str, questions=None) -> dict:
    return sn.last_binding_cells(list(cells), questions or {"q1": Q1, "q3": Q3})


def test_a_cell_that_binds_or_changes_an_answer_is_its_answer_cell():
    assert _last("Phi = 1", "V = 2", "x = 3") == {"q1": 1, "q3": None}
    for change in ("V[0, 0] = 1", "V += 1", "del V", "V.fill(0)", "import numpy as V",
                   "for V in range(2): pass", "def V(): pass", "class V: pass",
                   "if (V := 3): pass", "m.V = 1", "g = {'V': 1}"):
        assert _last("V = 1", change, "x = 1") == {"q1": 1, "q3": None}, change
    # what rebinds names the parser cannot see: every question's
    for dynamic in ("setattr(m, 'x', 1)", "globals()['y'] = 1", "exec(code)",
                    "from helpers import *", "print(vars())", "f.__globals__['z'] = 1"):
        assert _last("V = 1", dynamic, "x = 1") == {"q1": 1, "q3": 1}, dynamic


def test_a_cell_that_only_uses_an_answer_is_not_its_answer_cell():
    # a slow exploratory cell calling the student's functions, a plot, a reimport of numpy
    assert _last("Phi = V = 1", "def average_nees(a):\n    return np.mean(a)",
                 "import numpy as np\nfor k in range(10**9):\n    x = average_nees(Phi @ V)",
                 "print(Phi.shape, average_nees)", "bad syntax (") == {"q1": 0, "q3": 1}


def test_the_globals_a_function_reads_are_part_of_its_answer():
    cells = ["import numpy as np\nK = 2", "def helper(x):\n    return K * x",
             "def average_nees(a, b, P):\n    e = a - b\n    return helper(e)",
             "e = P = a = 0\nimport numpy as np",  # its locals and its imports: not its answer
             "K = 3"]                             # a global it reads, through helper: is
    assert _last(*cells) == {"q1": None, "q3": 4}
    assert _last(*cells[:4]) == {"q1": None, "q3": 2}
    lam = ["f = lambda x: x * c", "average_nees = lambda a: f(a)", "c = 2"]
    assert _last(*lam) == {"q1": None, "q3": 2}


def test_an_otter_check_cell_moves_the_answer_cell_after_what_precedes_it():
    from gpsaccel.assignments.scoring import checked_question

    run = [nbm.Cell(0, "VARIANT = {}"), nbm.Cell(3, "def make():\n    global Phi\n    Phi = 1"),
           nbm.Cell(5, "make()"), nbm.Cell(9, "x = 1")]
    numbered = [*run[1:3], nbm.Cell(6, 'grader.check("q1")'), nbm.Cell(7, 'grader.check("q9")'),
                nbm.Cell(8, "grader.check(q)"), run[3]]
    checks = {c.number: q for c in numbered if (q := checked_question(c.source)) is not None}
    assert checks == {6: "q1", 7: "q9"}
    # the def cell binds Phi (global); the call after it does so only when run: the check cell
    # after it says the answer is complete there
    assert sn.answer_cells(run, checks, {"q1": Q1, "q3": Q3}) == {"q1": 2, "q3": None}
    assert sn.answer_cells(run, {}, {"q1": Q1}) == {"q1": 1}


def test_answer_cells_of_text_the_parser_cannot_take_are_none(monkeypatch):
    run = [nbm.Cell(1, "Phi = 1"), nbm.Cell(2, "x = " + "(" * 200_000 + ")" * 200_000)]
    assert sn.answer_cells(run, {}, {"q1": Q1}) == {"q1": 0}  # the deep cell binds nothing
    monkeypatch.setattr(nbm, "LOAD_CPU", 0.01)
    big = [nbm.Cell(i, f"Phi{i} = {i}\n" * 2000) for i in range(1, 200)]
    assert sn.answer_cells(big, {}, {"q1": ["Phi1"]}) == {"q1": None}  # over the CPU limit


SPANS = {"q1": (0, 2), "q3": (2, 3)}


def test_the_plan_reads_after_each_answer_cell_every_question_answered_by_then():
    p = sn.plan(5, SPANS, {"q1": 1, "q3": 3})
    assert p.calls == ((-1, 0), (-1, 1), (0, 0), (0, 1), (-1, 2), (-1, 3), (1, 0), (1, 1), (1, 2),
                       (-1, 4), (2, 0), (2, 1), (2, 2))
    assert [(g.after, g.questions, g.first) for g in p.groups] == [
        (1, ("q1",), 2), (3, ("q1", "q3"), 6), (4, ("q1", "q3"), 10)]
    assert p.cell_calls == [0, 1, 4, 5, 9]
    assert list(p.read_calls(1, "q3")) == [8]
    # the last cell completes q3: its group is the final one; a question without an answer
    # cell is read in every group
    p = sn.plan(5, SPANS, {"q1": None, "q3": 4})
    assert [(g.after, g.questions) for g in p.groups] == [(4, ("q1", "q3"))]
    p = sn.plan(3, SPANS, {"q1": None, "q3": 0})
    assert [(g.after, g.questions) for g in p.groups] == [(0, ("q1", "q3")), (2, ("q1", "q3"))]


@pytest.mark.parametrize(("received", "group", "stopped", "questions"), [
    (13, 2, None, {"q1": [10, 11], "q3": [12]}),  # everything came back: the final reads
    (11, 2, 11, {"q1": [10, 11], "q3": [12]}),    # in the final group: that group, partly
    (9, 1, 9, {"q1": [6, 7], "q3": [8]}),         # in the last cell: the group before it
    (7, 1, 7, {"q1": [6, 7], "q3": [8]}),         # in q1's read after cell 3
    (5, 0, 5, {"q1": [2, 3]}),                    # in cell 3: q3's cells had not run
    (1, None, 1, {}),                             # before any answer cell had run
])
def test_one_group_grades_every_question(received, group, stopped, questions):
    k = sn.kept(sn.plan(5, SPANS, {"q1": 1, "q3": 3}), received)
    assert (k.group, k.stopped) == (group, stopped)
    assert {q: list(r) for q, r in k.questions.items()} == questions


def test_names_local_to_a_function_class_or_comprehension_bind_nothing():
    # a filter that assigns its own Phi and V (q1's names), a class attribute, a comprehension
    assert _last("Phi = 1", "def kalman_filter(z):\n    Phi = V = 2\n    V.fill(0)\n"
                 "    return Phi", "class M:\n    V = 3", "[V for V in range(3)]") == \
        {"q1": 0, "q3": None}
    # what runs when the cell runs does: decorators, defaults, a declared global
    for binding in ("@V.register(1)\ndef f(): pass", "def f(x=V.fill(0)): pass",
                    "def f():\n    global V\n    V = 2"):
        assert _last("Phi = 1", binding)["q1"] == 1, binding
