"""A hostile class graded to the end (issue 27, items 4 and 5): every student has a row and a
feedback file of their own, each hostile one its own status, every other student is graded; a
regrade interrupted with Ctrl-C or SIGTERM leaves the old row; a regrade is appended to the class
record.

Kept cheap: three notebooks run in a box (two honest, one forging a shape); the others end
before any box (a folder nested 1500 deep, an unparseable notebook, a cell of magics stopped at a
CPU limit lowered to 1 s, colliding names).  The cell of magics is 1200 lines, which IPython's
transformer (quadratic in them) would take about 30 CPU s to read here: 300 lines took 1.9, so a
host twice as fast would have read them inside the limit and graded the notebook; the limit
keeps its cost at 1 CPU s whatever its size.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from gpsaccel import _untrusted
from gpsaccel.assignments import notebook as nbm
from gpsaccel.classrun import grade

from .conftest import CHI2_SPECIAL, kill_pids, write_variant

ZOE = os.fsdecode(b"Zo\xeby")  # Latin-1, not UTF-8: the run used to crash here and on every rerun
BAD_FILE = os.fsdecode(b"\xff\xfe.ipynb")

# the student replaces the functions that report reads: every read says "shape (10⁶, 10⁶)"
FORGE = """
import numpy as _n
_reads = _gpsaccel_probe.__self__.reads
def _gpsaccel_probe(k, *args):
    st = _n.zeros(9, dtype=_n.int64)
    st[0], st[2], st[3], st[4] = 7, 2, 10**6, 10**6
    return (st, _n.zeros(320, dtype=_n.uint8), *[_n.full(s, _n.nan) for s in _reads[int(k)][2]])
def _gpsaccel_reads(ks, nargs, *args):
    one = [_gpsaccel_probe(k) for k in _n.ravel(ks)]
    return tuple(_n.stack(parts) for parts in zip(*one))
"""


def _rows(out: Path) -> dict[str, dict[str, str]]:
    with open(out / "grades.csv", newline="", encoding="utf-8") as f:
        return {r["id"]: r for r in csv.DictReader(f) if r["student"] != "Points Possible"}


def _class(sub: Path, nested_folders) -> None:
    write_variant("calibration", sub / "alice" / "calibration.ipynb", [CHI2_SPECIAL])
    write_variant("calibration", sub / ZOE / "calibration.ipynb", [CHI2_SPECIAL])
    write_variant("calibration", sub / "mallory" / "calibration.ipynb", last_cell=FORGE)
    write_variant("calibration", sub / "deep" / "calibration.ipynb")
    nested_folders.make(sub / "deep", 1500)  # rglob died here: RecursionError, nobody graded
    (sub / BAD_FILE).write_text("[" * 100_000)  # json recursed: grader-error, not unreadable
    (sub / "Doe, Jane").mkdir()
    (sub / "Doe, Jane" / "calibration.ipynb").write_text(json.dumps({"cells": [
        {"cell_type": "code", "source": "%time x = 1\n" * 1200, "metadata": {}, "outputs": []}]}))
    (sub / "Doe_ Jane").mkdir()
    (sub / "Doe_ Jane" / "calibration.ipynb").write_text("{not json")
    write_variant("calibration", sub / "bob" / "calibration.ipynb")
    (sub / "bob.ipynb").write_bytes((sub / "bob" / "calibration.ipynb").read_bytes())


@pytest.fixture(scope="module")
def hostile(tmp_path_factory, nested_folders):
    root = tmp_path_factory.mktemp("hostile")
    sub = root / "class"
    _class(sub, nested_folders)
    out = root / "out"
    mp = pytest.MonkeyPatch()
    mp.setattr(nbm, "LOAD_CPU", 1)  # inherited by the forked children
    try:
        grades = grade(sub, "calibration", out=out, seed=7, jobs=2, timeout=60)
    except BaseException:
        nested_folders.remove(sub / "deep")
        raise
    finally:
        mp.undo()
    yield {"sub": sub, "out": out, "grades": grades}
    nested_folders.remove(sub / "deep")


WANT = {  # id: (status, total)
    "alice": ("graded", "10"),
    _untrusted.student_id(ZOE): ("graded", "10"),
    "deep": ("file-limit", "0"),
    _untrusted.student_id(BAD_FILE[:-6]): ("unreadable", "0"),
    _untrusted.student_id("Doe, Jane"): ("unreadable", "0"),
    "Doe_ Jane": ("unreadable", "0"),
}


def test_every_student_has_a_row_of_their_own(hostile):
    rows = _rows(hostile["out"])
    got = {k: (r["status"], r["total"]) for k, r in rows.items()}
    for sid, want in WANT.items():
        assert got.pop(sid) == want, (sid, rows.get(sid))
    mallory = got.pop("mallory")
    assert mallory[0] == "graded" and float(mallory[1]) <= 4  # its reads all forged: q2 only
    # bob's folder and bob.ipynb: both reported, neither graded, two rows, two files
    assert sorted(got.values()) == [("id-collision", "")] * 2 and len(got) == 2
    assert sorted(r["student"] for k, r in rows.items() if k in got) == ["bob", "bob"]
    assert rows[_untrusted.student_id(ZOE)]["student"] == "Zo\\xeby"


def test_feedback_one_file_each_printable_and_its_own(hostile):
    fb = hostile["out"] / "feedback"
    files = {p.name: p.read_text(encoding="utf-8") for p in fb.iterdir()}
    assert sorted(files) == sorted(f"{k}.txt" for k in _rows(hostile["out"]))
    assert len(files) == 9
    assert "not valid JSON" in files["Doe_ Jane.txt"]
    assert "CPU seconds" in files[f"{_untrusted.student_id('Doe, Jane')}.txt"]
    assert "levels deep" in files["deep.txt"]
    for text in files.values():
        assert text == _untrusted.clean(text, newlines=True)
    assert any("id-collision" in n for n in json.loads(
        (hostile["out"] / "grading.json").read_text(encoding="utf-8"))["skipped"])


def _cmdline(p: psutil.Process) -> list[str]:
    try:
        return p.cmdline()
    except psutil.Error:  # gone, or a zombie
        return []


#: A hang guard, not an expected duration (tests/_hostile.py's HANG): the regrade reaches its box
#: within seconds when the code works; a loaded machine may take minutes.
HANG = 600.0


def _wait(predicate, proc: subprocess.Popen) -> None:
    """Until ``predicate()``; fails if ``proc`` ends first or the hang guard passes."""
    deadline = time.monotonic() + HANG
    while not predicate():
        assert proc.poll() is None, f"the grader ended first: {proc.communicate()}"
        assert time.monotonic() < deadline, "the event never came"
        time.sleep(0.05)


def _stop_a_regrade(hostile, first_cell: str, running, sig: int):
    """Alice hands in again (``first_cell`` first), her regrade starts; once it is recorded and
    ``running(kids)`` holds for the grader's descendants, ``sig``; the grader's exit status, its
    stderr, and its descendants alive when it had exited.  Her old row stays meanwhile."""
    sub, out = hostile["sub"], hostile["out"]
    before = _rows(out)["alice"]
    write_variant("calibration", sub / "alice" / "calibration.ipynb", first_cell=first_cell)
    record = out / "grading.json"
    regrades = len(json.loads(record.read_text(encoding="utf-8")).get("regrades") or [])
    proc = subprocess.Popen([sys.executable, "-m", "gpsaccel", "grade", str(sub), "--assignment",
                             "calibration", "--out", str(out), "--student", "alice",
                             "--timeout", "60"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    seen: set[int] = set()
    try:
        me = psutil.Process(proc.pid)

        def started() -> bool:  # the regrade is recorded, then its notebook's box runs
            if len(json.loads(record.read_text(encoding="utf-8")).get("regrades") or []) \
                    == regrades:
                return False
            kids = me.children(recursive=True)
            seen.update(p.pid for p in kids)
            return running(kids, me)

        _wait(started, proc)
        assert _rows(out)["alice"] == before  # the old row stays while the regrade runs
        os.kill(proc.pid, sig)
        _, stderr = proc.communicate(timeout=HANG)
        left = [p for p in seen if _alive(p)]
    finally:
        kill_pids([proc.pid, *seen])
    assert _rows(out)["alice"] == before
    info = json.loads(record.read_text(encoding="utf-8"))
    assert info["student"] is None and info["seed"] == 7  # the class record is kept
    assert info["regrades"][-1]["student"] == ["alice"] and info["regrades"][-1]["interrupted"]
    return proc.returncode, stderr, left


def test_ctrl_c_during_a_regrade_keeps_the_old_row(hostile):
    def in_the_box(kids, me) -> bool:
        return any(_cmdline(p) not in ([], me.cmdline()) for p in kids)  # exec'd: the box

    code, stderr, _ = _stop_a_regrade(hostile, "while True:\n    pass", in_the_box,
                                      signal.SIGINT)
    assert code == 130, stderr


def test_sigterm_during_a_regrade_is_ctrl_c(hostile):
    """SIGTERM (``timeout``, ``docker stop``) as Ctrl-C: the box is killed before the grader exits
    (nothing of the run alive when it has exited, counted then), the grader says what it kept,
    the old row stays and the regrade is recorded as interrupted; exit status 143."""
    def sleeping(kids, me) -> bool:  # the box's own child runs
        return any(_cmdline(p)[:1] == ["sleep"] for p in kids)

    code, stderr, left = _stop_a_regrade(
        hostile, "import subprocess\nsubprocess.Popen(['sleep', '120'])\nwhile True:\n    pass",
        sleeping, signal.SIGTERM)
    assert code == 143 and not left, (stderr, left)
    assert b"interrupted by SIGTERM: 0 of 1 finished and kept, 1 stopped" in stderr


def _alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def test_a_regrade_replaces_its_row_and_is_appended_to_the_record(hostile):
    sub, out = hostile["sub"], hostile["out"]
    write_variant("calibration", sub / "mallory" / "calibration.ipynb",  # the honest one now
                  [CHI2_SPECIAL])
    again = grade(sub, "calibration", out=out, student="mallory", timeout=60)
    assert [(g.status, g.total) for g in again] == [("graded", 10.0)]
    rows = _rows(out)
    assert rows["mallory"]["total"] == "10" and len(rows) == 9
    assert rows["deep"]["status"] == "file-limit" and rows["alice"]["total"] == "10"
    info = json.loads((out / "grading.json").read_text(encoding="utf-8"))
    assert info["student"] is None and [r["student"] for r in info["regrades"]] == \
        [["alice"], ["alice"], ["mallory"]]  # two interrupted (Ctrl-C, SIGTERM), then this one
    assert info["regrades"][-1]["seed"] == 7 and not info["regrades"][-1]["interrupted"]


def test_a_grade_stopped_in_a_box_leaves_no_temporary_folder(tmp_path):
    """Ctrl-C while a notebook runs in its box: the notebook's process is killed inside its
    scratch folder, which then stayed in /tmp (``gpsaccel-nb-*/submission``) after every such
    run; named as a box folder, the pool's sweep removes it.  The run's TMPDIR is a folder of
    this test, so only its own leftovers are counted."""
    sub, tmp = tmp_path / "sub", tmp_path / "tmp"
    tmp.mkdir()
    write_variant("calibration", sub / "alice" / "calibration.ipynb",
                  first_cell="while True:\n    pass")
    proc = subprocess.Popen([sys.executable, "-m", "gpsaccel", "grade", str(sub), "--assignment",
                             "calibration", "--out", str(tmp_path / "out"), "--timeout", "60",
                             "--no-similarity"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=dict(os.environ, TMPDIR=str(tmp)))
    seen: set[int] = set()
    try:
        me = psutil.Process(proc.pid)

        def in_its_folder() -> bool:  # the notebook's scratch folder exists: its box starts
            seen.update(p.pid for p in me.children(recursive=True))
            return any("-nb-" in p.name for p in tmp.iterdir())

        _wait(in_its_folder, proc)
        assert all(p.name.startswith(("gpsaccel-box-", "gpsaccel-uids", "gpsaccel-zygote-"))
                   for p in tmp.iterdir())  # a warm run's zygotes live there too
        os.kill(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        kill_pids([proc.pid, *seen])
    assert proc.returncode != 0, (stdout, stderr)
    assert sorted(p.name for p in tmp.iterdir()) in ([], ["gpsaccel-uids"])
