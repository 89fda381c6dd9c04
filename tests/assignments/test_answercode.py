"""A notebook's record for the similarity report (gpsaccel.assignments.answercode): each
question's answer found where the notebook really defines it, and a record that never raises."""

from __future__ import annotations

import json

import pytest

from gpsaccel.assignments import answercode as ac
from gpsaccel.assignments.notebook import transform

Q3 = {"q3": ac.Asked(names=frozenset({"average_nees", "nees_bounds"}))}
Q2 = {"q2": ac.Asked(file="kalman_filter.py", roots=frozenset({"kalman_filter"}))}
AVG = ("def average_nees(x_true, x_hat, P):\n    e = x_true[:, -1] - x_hat[:, -1]\n"
       "    return helper(e, P)\n")
HELPER = "def helper(e, P):\n    return float((e * e).sum())\n"
BOUNDS = "def nees_bounds(N):\n    return (0.5, 1.5)\n"


def record(sources: list[str], asked=Q3) -> dict:
    return ac.record([(i, transform(s)) for i, s in enumerate(sources, 1)],
                     ac.written_files(sources), asked)


def answer(rec: dict, q: str = "q3") -> dict:
    return rec["questions"][q]


def test_the_answer_is_the_definitions_and_their_helpers():
    rec = record(["import numpy as np", HELPER, "junk = 1\nprint(junk)", AVG + BOUNDS])
    code = answer(rec)["code"]
    assert "def helper" in code and "def average_nees" in code and "junk" not in code
    assert answer(rec)["undefined"] == [] and rec["hidden"] == []


@pytest.mark.parametrize("wrap", [
    lambda c: "%%time\n" + c,
    lambda c: "%%capture out\n" + c,
    lambda c: f"exec({c!r})",
])
def test_code_run_from_literal_text_is_read_as_code(wrap):
    plain = record([HELPER + AVG + BOUNDS])
    wrapped = record([wrap(HELPER + AVG + BOUNDS)])
    assert answer(wrapped)["tokens"] == answer(plain)["tokens"]
    assert answer(wrapped)["undefined"] == [] and wrapped["hidden"] == []


def test_a_helper_file_the_notebook_writes_and_imports_is_read():
    sources = ["%%writefile nees.py\nimport numpy as np\n" + HELPER + AVG + BOUNDS,
               "from nees import average_nees, nees_bounds"]
    assert answer(record(sources))["tokens"] == answer(record([HELPER + AVG + BOUNDS]))["tokens"]


def test_a_file_question_keeps_what_the_checker_calls():
    body = "import numpy as np\n\ndef unused_padding():\n    return 1\n\n" \
           "def step(x):\n    return x + 1\n\ndef kalman_filter(z):\n    return step(z), z\n"
    rec = record(["%%writefile kalman_filter.py\n" + body], Q2)
    code = answer(rec, "q2")["code"]
    assert "def kalman_filter" in code and "def step" in code and "unused_padding" not in code
    assert answer(record(["x = 1"], Q2), "q2") == {"code": "", "tokens": ac.pack([]),
                                                   "undefined": []}


def test_a_packed_answer_is_undefined_and_hidden():
    import base64
    import zlib

    packed = base64.b64encode(zlib.compress((AVG + HELPER + BOUNDS).encode())).decode()
    rec = record([f"import zlib, base64\nexec(zlib.decompress(base64.b64decode('{packed}')))"])
    assert answer(rec)["undefined"] == ["average_nees", "nees_bounds"]
    assert rec["hidden"] == ["cell 1: exec of computed text (from zlib.decompress, "
                             "base64.b64decode)"]


def test_a_record_is_json_and_never_raises():
    rec = record([AVG, "def broken(:", BOUNDS])  # a cell Python cannot parse is left out
    assert json.loads(json.dumps(rec)) == rec and answer(rec)["undefined"] == []
    deep = ac.record([(1, "x = " + "-" * 200_000 + "1")], {}, Q3)
    assert set(deep) == {"why"}


def test_an_oversized_cell_cannot_hide_the_other_answers():
    """The bound is on the code parsed, not on the notebook: a huge comment cell is left
    unread and flagged, the answer beside it is still compared."""
    junk = "# " + "x" * ac.MAX_CODE
    rec = record([AVG + HELPER, junk, BOUNDS])
    assert "def average_nees" in answer(rec)["code"] and answer(rec)["undefined"] == []
    assert rec["hidden"] == [f"cell 2 is {len(junk) // 1024} KB of code, past the "
                             f"{ac.MAX_CODE // 1024} KB a notebook may hold to be compared: "
                             "not compared, not scanned"]


def test_an_oversized_answer_is_an_integrity_signal():
    big = "def average_nees(x_true, x_hat, P):\n    return 0.0\n" + "# pad\n" * ac.MAX_CODE
    rec = record([big, BOUNDS])
    assert answer(rec)["undefined"] == ["average_nees"]
    assert rec["hidden"] == [f"q3: cell 1 is {len(big) // 1024} KB of code, past the "
                             f"{ac.MAX_CODE // 1024} KB a notebook may hold to be compared: "
                             "not compared, not scanned (it mentions the question's answer)"]
    file_q = record(["%%writefile kalman_filter.py\ndef kalman_filter():\n    pass\n"
                     + "# pad\n" * ac.MAX_CODE], Q2)
    assert [f.split(":")[0] for f in file_q["hidden"]] == ["q2", "q2"]  # cell, file
    assert answer(file_q, "q2")["code"] == ""


def test_tokens_are_packed_and_checked():
    assert ac.unpack(ac.pack([1, 2**32 - 1])) == [1, 2**32 - 1]
    for bad in (3, "not base64!", "AAA"):
        with pytest.raises(ValueError):
            ac.unpack(bad)


def test_a_file_whose_function_no_shown_code_defines_is_undefined():
    """The report's backstop for hidden code the scan does not name (a graded name that scored
    although no shown code defines it) held for the questions that read the box only: a
    ``kalman_filter.py`` defining its function by any unlisted way scored 4 / 4 unflagged."""
    hidden = "import numpy as np\nglobals().update(make())\n"
    assert answer(record(["%%writefile kalman_filter.py\n" + hidden], Q2), "q2")[
        "undefined"] == ["kalman_filter"]
    imported = "from filterpy_like import kalman_filter\n"
    assert answer(record(["%%writefile kalman_filter.py\n" + imported], Q2), "q2")[
        "undefined"] == ["kalman_filter"]
    honest = "import numpy as np\n\ndef kalman_filter(z):\n    return z, z\n"
    helper = ["%%writefile kf_core.py\n" + honest,
              "%%writefile kalman_filter.py\nfrom kf_core import kalman_filter\n"]
    for sources in (["%%writefile kalman_filter.py\n" + honest], helper):
        assert answer(record(sources, Q2), "q2")["undefined"] == []


def test_the_master_file_names_are_what_the_checker_calls():
    assert ac.master_file_names("calibration", "kalman_filter.py") == {"kalman_filter"}
    assert ac.master_file_names("calibration", "other.py") == frozenset()


def test_a_graded_function_imported_from_elsewhere_is_undefined():
    """Imported from a module the notebook does not write (one it wrote from decoded text, say):
    no shown code defines it; from a module a %%writefile cell writes, it is read in place."""
    rec = record(["from m import average_nees\n" + BOUNDS])
    assert answer(rec)["undefined"] == ["average_nees"]
    rec = record(["%%writefile m.py\n" + HELPER + AVG, "from m import average_nees\n" + BOUNDS])
    assert answer(rec)["undefined"] == []


def test_a_record_past_its_limits_is_the_notebooks_reason(monkeypatch):
    """Made in a child under limits (sandbox.in_child): a notebook whose code takes longer
    than the child's CPU is "not compared" with that reason, and the caller goes on."""
    from gpsaccel.assignments.notebook import Cell, Notebook

    body = "\n".join(f"        x[{i}] = {i}" for i in range(190))
    slow = "def average_nees(x):\n" + "\n".join(f"    if x > {j}:\n{body}"
                                                  for j in range(130)) + "\n    return x\n"
    monkeypatch.setattr(ac, "RECORD_CPU", 1)
    rec = ac.from_notebook(Notebook([Cell(1, slow, slow)]), Q3)
    assert rec == {"why": "comparing its code took more than 1 CPU seconds"}
    fine = ac.from_notebook(Notebook([Cell(1, AVG + BOUNDS, AVG + BOUNDS)]), Q3)
    assert fine == record([AVG + BOUNDS])
