"""What the instructor reads (issue 20): a table a terminal can show and a results.jsonl a parser
can split, whatever the names and the students' text hold; the secret seed of a class's check,
recorded so a verdict can be reproduced; the basic sandbox refused for a class where it is
unsafe."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel._untrusted import printable
from gpsaccel.classrun import appender, check_many, table
from gpsaccel.sandbox import _boxuser, confinement

HOSTILE_NAMES = ["yes\x1b[2K\ryes.py", "line\u2028sep.py", "bidi\u202eyp.txt.py",
                 "nel\x85.py", "tab\tname.py"]


@pytest.mark.parametrize("name", HOSTILE_NAMES)
def test_the_table_shows_no_control_character_of_a_name(name):
    r = {"subject": name, "details": {"path": name}, "passed": False, "seconds": 1.0,
         "codes": ["p-mismatch"]}
    text = table([r])
    assert all(c == "\n" or (c.isprintable() and c not in "\u2028\u2029") for c in text)
    row = text.splitlines()[2]
    assert row.split()[1] == "NO" and "0 of 1 passed" in text


def test_printable_escapes_and_keeps_what_is_text():
    assert printable("a\x1b[31mb") == "a\\x1b[31mb"
    assert printable("x\u2028y\u2029z") == "x\\u2028y\\u2029z"
    assert printable("é ü σ Φ", keep_newlines=True) == "é ü σ Φ"
    assert printable("one\ntwo", keep_newlines=True) == "one\ntwo"
    assert printable("one\ntwo") == "one\\x0atwo"


def test_results_jsonl_is_one_object_per_line_whatever_the_names(tmp_path):
    log = tmp_path / "results.jsonl"
    append = appender(log)
    for name in HOSTILE_NAMES:
        append({"subject": name, "text": f"{name}: FAILED\n  - {name}"})
    text = log.read_text(encoding="utf-8")
    lines = text.splitlines()  # str.splitlines splits on U+2028, U+0085, ... as well
    assert len(lines) == len(HOSTILE_NAMES)
    assert [json.loads(line)["subject"] for line in lines] == HOSTILE_NAMES


def test_a_class_is_checked_on_a_secret_seed_recorded_in_the_json(tmp_path, hostile):
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", folder / "a.py")
    seeds = []
    for k in range(2):
        out = tmp_path / f"r{k}.json"
        proc = subprocess.run([sys.executable, "-m", "gpsaccel.cli", "check", str(folder),
                               "--runs", "2", "--workers", "1", "--json", str(out)],
                              capture_output=True, text=True, env=hostile.env(), timeout=300)
        assert proc.returncode == 0, proc.stderr
        data = json.loads(out.read_text(encoding="utf-8"))
        assert data["settings"]["seed_drawn"] is True
        seed = data["settings"]["seed"]
        assert data["results"][0]["details"]["seed"] == seed
        assert f"(seed {seed}, drawn)" in proc.stdout
        seeds.append(seed)
    # 63 random bits: two equal draws have probability 2^-63
    assert seeds[0] != seeds[1]
    assert all(0 <= s < 2**63 for s in seeds)
    # the API: check_many draws too; a student's own check keeps its fixed default seed
    assert check_many([folder], n_runs=2, executor=None)[0]["details"]["seed"] not in (0, *seeds)
    assert check.submission(folder / "a.py", n_runs=2).details["seed"] == 0
    # a verdict is reproduced by passing the recorded seed
    again = check_many([folder], n_runs=2, executor=None, seed=seeds[0])[0]
    assert again["details"]["seed"] == seeds[0]


def test_basic_is_refused_for_a_class_where_it_is_unsafe(tmp_path, hostile, monkeypatch,
                                                        capsys):
    from gpsaccel.cli import main

    monkeypatch.setattr(_boxuser, "box_uid", lambda: None)  # as a user other than root
    assert not sb.basic_is_safe()
    path = hostile.SUBMISSIONS / "correct_gps_rate.py"
    assert main(["check", str(path), "--sandbox", "basic", "--runs", "2"]) == 2
    err = capsys.readouterr().err
    assert "not safe for grading" in err and "--allow-unsafe-basic" in err
    monkeypatch.setattr(confinement, "bwrap_path", lambda: None)  # auto falls back on basic: refused
    assert main(["check", str(path), "--runs", "2"]) == 2
    assert main(["check", str(path), "--runs", "2", "--allow-unsafe-basic", "--workers",
                 "1"]) == 0
    assert check.submission(path, n_runs=2, sandbox="basic").passed  # a student's own check


def test_a_check_without_a_verdict_reads_again_not_no():
    """A box stopped because the machine was too busy (or lost) says nothing about the student's
    code: the table shows "again" and counts it apart; a real failure beside it still reads NO."""
    busy = {"subject": "busy.py", "details": {"path": "busy.py"}, "passed": False, "seconds": 30.0,
            "codes": ["machine-busy"]}
    wrong = {"subject": "wrong.py", "details": {"path": "wrong.py"}, "passed": False,
             "seconds": 1.0, "codes": ["machine-busy", "p-mismatch"]}
    rows = table([busy, wrong]).splitlines()
    assert rows[2].split()[:2] == ["busy.py", "again"]
    assert rows[3].split()[:2] == ["wrong.py", "NO"]
    assert rows[-1].startswith("0 of 2 passed; 1 without a verdict")


def test_the_report_says_no_verdict_when_every_reason_is_ours():
    from gpsaccel.check.report import render

    assert render("f.py", False, ["machine-busy"], [], []) == "f.py: NO VERDICT (machine-busy)"
    assert render("f.py", False, ["timeout"], [], []).startswith("f.py: FAILED (timeout)")
    assert render("f.py", False, [], [], []) == "f.py: FAILED"
    assert render("f.py", True, [], [], []) == "f.py: PASSED"
