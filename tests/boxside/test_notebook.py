"""The box-side code of a graded notebook (:mod:`gpsaccel.boxside.notebook`), run here in-process (the
box runs the same module): each status a read can give, the cell runner, the stand-ins for the
kernel and otter, and the import guard (in a child interpreter: an audit hook cannot be removed)."""

from __future__ import annotations

import subprocess
import sys
import types

import numpy as np
import pytest

from gpsaccel.boxside import notebook as box

READS = [("f", False, [(3,)]), ("pair", False, [(2,), (2, 2)]), ("v", True, [(2, 2)]),
         ("missing", False, [()]), ("number", False, [()]), ("none", False, [()]),
         ("single", False, [(2,), (2,)]), ("words", True, [(2,)]), ("boom", False, [()]),
         ("ellipsis", True, [()])]


def _text(arr: np.ndarray) -> str:
    return bytes(arr).rstrip(b"\0").decode()


def _code(status: np.ndarray) -> str:
    return box.STATUSES[int(status[0])]


@pytest.fixture
def notebook(monkeypatch):
    monkeypatch.setitem(sys.modules, "otter", None)  # put back whatever was there
    ns: dict = {"__name__": "student_submission"}
    cells = [(1, "import numpy as np\ndef f(a):\n    return a * 2\n"),
             (2, "def pair(a):\n    return a[:2], np.eye(2)\nv = np.ones((2, 2))\n"),
             (4, "number = 3\nnone = lambda *a: None\nsingle = lambda *a: 5\n"),
             (5, "words = ['a', 'b']\ndef boom(*a):\n    raise KeyError('secret-free text')\n"),
             (7, "ellipsis = ...\nget_ipython().run_line_magic('matplotlib', 'inline')\n"),
             (9, "x = 1\n\n1 / 0\n"),
             (10, "raise SystemExit(3)\n")]
    cell, probe, _ = box.start(ns, cells, READS)
    return ns, cell, probe


def test_cells_run_in_order_and_a_failing_one_is_reported_not_raised(notebook):
    ns, cell, _ = notebook
    out = [cell(np.array(i)) for i in range(7)]
    assert [_code(s) for s, _ in out] == ["ok"] * 5 + ["exception"] * 2
    assert _text(out[4][1]) == "%matplotlib"  # skipped lines, listed for the feedback
    assert _text(out[5][1]) == "cell 9, line 3: ZeroDivisionError: division by zero"
    assert _text(out[6][1]) == "cell 10, line 1: SystemExit: 3"
    assert ns["x"] == 1 and isinstance(sys.modules["otter"], types.ModuleType)


def test_every_status_of_a_read(notebook):
    _, cell, probe = notebook
    for i in range(5):
        cell(i)
    got = {name: probe(np.array(k), np.arange(3.0)) for k, (name, _, _) in enumerate(READS)}
    f = got["f"]
    assert _code(f[0]) == "ok" and f[2].tolist() == [0.0, 2.0, 4.0]
    assert _code(got["pair"][0]) == "ok" and got["pair"][3].tolist() == np.eye(2).tolist()
    assert _code(got["v"][0]) == "ok" and got["v"][2].tolist() == [[1.0, 1.0], [1.0, 1.0]]
    status = {name: _code(out[0]) for name, out in got.items()}
    assert status == {"f": "ok", "pair": "ok", "v": "ok", "missing": "not-defined",
                      "number": "not-callable", "none": "returns-none", "single": "return-value",
                      "words": "not-a-matrix", "boom": "exception", "ellipsis": "not-defined"}
    assert _text(got["number"][1]) == "int" and _text(got["single"][1]) == "int"
    assert "KeyError" in _text(got["boom"][1])
    for name, out in got.items():  # a failed read gives NaN arrays of the declared shapes
        shapes = next(r[2] for r in READS if r[0] == name)
        assert [o.shape for o in out[2:]] == [tuple(s) for s in shapes]


def test_reads_at_once_are_the_reads_one_by_one_stacked(monkeypatch):
    monkeypatch.setitem(sys.modules, "otter", None)
    reads = [("f", False, [(3,), ()])] * 3 + [("g", False, [(2,)])]
    cell, probe, batch = box.start({}, [(1, "import numpy as np\n"
                                            "def f(a, b):\n    return a * b, float(b)\n"
                                            "def g():\n    raise ValueError('no')\n")], reads)
    cell(0)
    args = [(np.arange(3.0), np.array(2.0)), (np.ones(3), np.array(-1.0)), (np.zeros(2),)]
    status, message, x, y = batch(np.arange(3), np.array([2, 2, 1]), *[a for r in args for a in r])
    one = [probe(np.array(k), *a) for k, a in enumerate(args)]
    assert status.shape == (3, box.STATUS_LENGTH) and message.shape == (3, box.MESSAGE_BYTES)
    for j, (s, m, xj, yj) in enumerate(one):
        assert (status[j] == s).all() and (message[j] == m).all()
        np.testing.assert_array_equal(x[j], xj)
        np.testing.assert_array_equal(y[j], yj)
    assert [_code(s) for s in status] == ["ok", "ok", "exception"]  # f(zeros(2)): one argument
    status, message, out = batch(np.array([3, 3]), np.array([0, 0]))  # g raises, twice
    assert [_code(s) for s in status] == ["exception"] * 2 and out.shape == (2, 2)
    assert "ValueError: no" in _text(message[1])
    # reads that cannot be stacked (different shapes): each says so, the batch never raises
    status, message, x, y = batch(np.array([0, 3]), np.array([2, 0]), np.ones(3), np.ones(()))
    assert [_code(s) for s in status] == ["exception"] * 2 and x.shape == (2, 3)


def test_a_read_of_the_wrong_shape_reports_the_shape(notebook):
    ns, _, probe = notebook
    ns["f"] = lambda a: np.zeros((4, 5, 1))
    status, message, out = probe(np.array(0), np.zeros(3))
    assert _code(status) == "shape" and status[1] == 0 and status[2] == 3
    assert status[3:6].tolist() == [4, 5, 1] and np.isnan(out).all()


def test_the_argument_is_a_copy(notebook):
    ns, _, probe = notebook
    arg = np.arange(3.0)

    def scribble(a):
        a[:] = -1
        return a

    ns["f"] = scribble
    probe(np.array(0), arg)
    assert arg.tolist() == [0.0, 1.0, 2.0]


def test_the_shell_runs_time_and_writefile_and_lists_the_rest(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    shell = box.Shell(ns)
    assert shell.run_line_magic("time", "1 + 1") == 2
    shell.run_line_magic("time", "z = 5")
    shell.run_cell_magic("capture", "", "w = z * 2")
    shell.run_cell_magic("writefile", "f.py", "A = 1\n")
    shell.run_cell_magic("writefile", "-a f.py", "B = 2\n")
    shell.run_cell_magic("writefile", "--append f.py", "C = 3\n")  # IPython's long option
    shell.run_cell_magic("bash", "", "rm -rf /")
    assert shell.system("pip install x") == 0 and shell.getoutput("ls") == []
    shell.run_cell()
    assert shell.anything_else(1, 2) is None
    assert (ns["z"], ns["w"]) == (5, 10) and (tmp_path / "f.py").read_text() == "A = 1\nB = 2\nC = 3\n"
    assert shell.skipped == ["%%bash", "!pip", "!ls", "run_cell"]


def test_otter_stand_in_does_nothing(monkeypatch):
    monkeypatch.setitem(sys.modules, "otter", None)
    box.install_otter()
    import otter

    grader = otter.Notebook("hw.ipynb", tests_dir="x")
    assert grader.check("q1") is None and grader.export() is None


def test_text_is_cut_and_padded():
    assert box.text("é" * 400).shape == (box.MESSAGE_BYTES,)
    assert bytes(box.text("ok")).rstrip(b"\0") == b"ok"


def test_the_guard_refuses_the_hidden_modules_and_nothing_else():
    code = ("from gpsaccel.boxside import notebook as b\n"
            "b.guard(('csv', 'email.mime'))\n"
            "for name in ('csv', 'email.mime.text', 'email.utils', 'csvkit_not_csv'):\n"
            "    try:\n"
            "        __import__(name)\n"
            "        print(name, 'imported')\n"
            "    except ImportError as exc:\n"
            "        print(name, type(exc).__name__, exc)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout.splitlines()
    assert out == ["csv ImportError csv is not available while a notebook is graded",
                   "email.mime.text ImportError email.mime.text is not available while a "
                   "notebook is graded",
                   "email.utils imported",
                   "csvkit_not_csv ModuleNotFoundError No module named 'csvkit_not_csv'"]
