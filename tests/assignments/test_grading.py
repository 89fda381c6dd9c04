"""The isolated job: time limit, leftover processes killed, scrubbed environment; the untrusted
results.json; the CLI."""

from __future__ import annotations

import json
import os
import sys
import textwrap
import time

import pytest

from gpsaccel.assignments.grading import _cell, _safe_name, parse_results
from gpsaccel.assignments.isolation import MARKER, run_isolated
from gpsaccel.cli import main


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8") as f:
            return f.read().split()[2] != "Z"  # a zombie is dead
    except FileNotFoundError:
        return False


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="needs /proc")
def test_timeout_kills_the_job_and_a_process_that_left_its_session(tmp_path):
    # the child starts a grandchild in a session of its own (as jupyter_client starts a kernel),
    # writes its pid, then loops forever
    script = textwrap.dedent("""
        import subprocess, sys, time
        p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"],
                             start_new_session=True)
        open("grandchild.pid", "w").write(str(p.pid))
        while True:
            time.sleep(0.1)
    """)
    t0 = time.perf_counter()
    result = run_isolated([sys.executable, "-c", script], tmp_path, timeout=3)
    assert result.timed_out and result.returncode is None
    assert time.perf_counter() - t0 < 20
    pid = int((tmp_path / "grandchild.pid").read_text())
    time.sleep(0.2)
    assert not _alive(pid), "the grandchild in its own session survived the job"
    assert result.killed >= 1


def test_environment_is_scrubbed(tmp_path, monkeypatch):
    monkeypatch.setenv("GPSACCEL_TEST_SECRET", "do-not-leak")
    script = "import json, os; print(json.dumps(dict(os.environ)))"
    result = run_isolated([sys.executable, "-c", script], tmp_path, timeout=30)
    assert result.returncode == 0 and not result.timed_out
    env = json.loads(result.output.strip().splitlines()[-1])
    assert "GPSACCEL_TEST_SECRET" not in env
    assert env["HOME"].startswith(str(tmp_path)) and env["TMPDIR"].startswith(str(tmp_path))
    assert env["OMP_NUM_THREADS"] == "1" and MARKER in env


def test_results_json_is_untrusted():
    possible = {"q1": 3.0, "q2": 4.0}
    forged = {"tests": [{"name": "q1", "score": 1e9, "output": "x"},
                        {"name": "q2", "score": float("nan")},
                        {"name": "bonus", "score": 100},
                        "junk", {"name": "q1", "score": -5}]}
    scores, outputs = parse_results(json.dumps(forged), possible)
    assert scores == {"q1": 0.0, "q2": 0.0}  # last q1 entry wins, clipped to [0, 3]
    scores, _ = parse_results(json.dumps({"tests": [{"name": "q1", "score": 7}]}), possible)
    assert scores == {"q1": 3.0, "q2": 0.0}
    assert parse_results("[]", possible)[0] == {"q1": 0.0, "q2": 0.0}
    with pytest.raises(ValueError):
        parse_results("{not json", possible)


def test_names_cannot_escape_or_start_a_formula():
    assert _safe_name("../../etc/passwd.ipynb") == "passwd"
    assert "/" not in _safe_name("a/b c.ipynb")
    assert _cell("=HYPERLINK(1)").startswith("'") and _cell("alice.ipynb") == "alice.ipynb"


def test_cli_assignment_and_grade(tmp_path, capsys):
    pytest.importorskip("otter")
    out = tmp_path / "dist"
    assert main(["assignment", "ship", "--out", str(out), "--no-run-tests"]) == 0
    assert (out / "student" / "ship.ipynb").is_file() and (out / "ship-autograder.zip").is_file()
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "broken.ipynb").write_text("not a notebook", encoding="utf-8")
    assert main(["grade", str(subs), "--assignment", "ship", "--autograder",
                 str(out / "ship-autograder.zip"), "--timeout", "120"]) == 0
    text = (subs / "grades" / "grades.csv").read_text(encoding="utf-8").splitlines()
    assert text[0] == "submission,q1,q2,total,possible,status,seconds"
    assert text[1].startswith("broken.ipynb,0,0,0,10,error,")
    assert main(["grade", str(tmp_path / "nope"), "--assignment", "ship"]) == 2
    assert "submissions must be a folder" in capsys.readouterr().err


def test_generate_does_not_delete_a_folder_it_did_not_write(tmp_path):
    from gpsaccel.assignments import generate

    (tmp_path / "notes.txt").write_text("keep me", encoding="utf-8")
    with pytest.raises(ValueError, match="not an earlier"):
        generate("ship", tmp_path)
    assert (tmp_path / "notes.txt").read_text(encoding="utf-8") == "keep me"


@pytest.mark.parametrize("name", ["calibration", "coop", "ship"])
def test_masters_are_committed_clean_with_public_and_hidden_tests(name):
    import nbformat

    from gpsaccel.assignments import master_notebook, questions

    path = master_notebook(name)
    nb = nbformat.read(str(path), as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert not cell.get("outputs") and cell.get("execution_count") is None
    code = [c.source for c in nb.cells if c.cell_type == "code"]
    for q in questions(path):
        public = [s for s in code if s.startswith(f"def test_{q}_")]
        hidden = [s for s in code if s.startswith(f"# HIDDEN\ndef test_{q}_")]
        assert public and hidden, f"{name} {q}: a public and a hidden test"
