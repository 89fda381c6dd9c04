"""A run that could not write everything (issue 42 item 4): a full disk costs the files it
refused, never the run or the other files; the run names them on the terminal and in
grading.json, exits 2, and ``--from-grades`` writes the class-wide ones from grades.json once
there is room, without grading.  The disk is made full for chosen files at the one place every
file is written (:func:`gpsaccel._atomic.replacing`), and the class is graded by a fake run
(tests/classrun/test_grading.py): no notebook runs here.  (A full tmpfs, tried by hand, is in
the closing note of issue 42.)"""

from __future__ import annotations

import errno
import json
import os

import pytest

from gpsaccel import _atomic
from gpsaccel.assignments.roster import Student
from gpsaccel.classrun import grade, grade_class, rewrite_class, running, writing
from gpsaccel.classrun.writing import Outputs, missing_lines
from gpsaccel.cli import main

from .test_grading import _fake_run

ROSTER = [Student("alice", name="Alice Liddell", email="a@x.org"),
          Student("bob", name="Bob Stone", email="b@x.org")]
GRADEBOOKS = ("canvas.csv", "moodle.csv", "gradescope-roster.csv", "gradescope-scores.csv")
ENOSPC = os.strerror(errno.ENOSPC)


@pytest.fixture
def full(monkeypatch):
    """``full.add(name)``: every later write of a file of that name (or ``feedback/NAME``)
    fails as on a full disk, before a byte of it is written."""
    names: set[str] = set()
    real = _atomic.replacing

    def replacing(path, mode=None):
        p = os.fspath(path)
        if os.path.basename(p) in names or \
                f"feedback/{os.path.basename(p)}" in names and "feedback" in p:
            raise OSError(errno.ENOSPC, ENOSPC, p)
        return real(path, mode)

    monkeypatch.setattr(_atomic, "replacing", replacing)
    return names


def _class(tmp_path, monkeypatch):
    sub = tmp_path / "class"
    for name in ("alice", "bob"):
        (sub / name).mkdir(parents=True)
        (sub / name / "calibration.ipynb").write_text("{}")
    monkeypatch.setattr(running, "run", _fake_run([]))
    return sub


def _files(out) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.suffix != ".png" and p.name != "grading.json"}


def test_a_full_disk_names_what_it_did_not_write_and_from_grades_writes_it(
        tmp_path, monkeypatch, full):
    sub = _class(tmp_path, monkeypatch)
    ref = grade_class(sub, "calibration", out=tmp_path / "ref", seed=1, roster=ROSTER,
                      similarity=False)
    assert ref.missing == {} and json.loads(
        (ref.out / "grading.json").read_text(encoding="utf-8"))["missing"] == {}

    full.update({"summary.png", "moodle.csv", "feedback/bob.txt"})
    graded = grade_class(sub, "calibration", out=tmp_path / "out", seed=1, roster=ROSTER,
                         similarity=False)
    out = graded.out
    # canvas.csv was written before moodle.csv failed; the two after it never were
    want = {f: ENOSPC for f in ("feedback/bob.txt", "summary.png", *GRADEBOOKS[1:])}
    assert graded.missing == want
    assert json.loads((out / "grading.json").read_text(encoding="utf-8"))["missing"] == want
    assert [g.status for g in graded.grades] == ["graded", "graded"]  # nothing lost
    for f in ("grades.csv", "grades.json", "summary.csv", "canvas.csv", "feedback/alice.txt"):
        assert (out / f).is_file()
    for f in want:
        assert not (out / f).exists()
    lines = missing_lines(graded.missing, "AGAIN")
    assert lines[0] == f"NOT WRITTEN ({ENOSPC}): 5 file(s), listed in grading.json's 'missing'"
    assert lines[1] == ("  summary.png, moodle.csv, gradescope-roster.csv, "
                        "gradescope-scores.csv: once there is room, AGAIN")
    assert lines[2].startswith("  the feedback of bob: ") and "--student" in lines[2]

    full.clear()  # room again: the class-wide step alone, from grades.json
    again = rewrite_class(sub, "calibration", out, ROSTER, similarity=False)
    assert again.missing == {"feedback/bob.txt": ENOSPC}  # only a regrade writes feedback
    record = json.loads((out / "grading.json").read_text(encoding="utf-8"))
    assert record["missing"] == again.missing and len(record["rewrites"]) == 1
    mine = _files(out)
    assert mine == {k: v for k, v in _files(ref.out).items() if k != "feedback/bob.txt"}
    assert (out / "summary.png").stat().st_size > 0


def test_a_file_refused_then_written_by_a_later_flush_is_not_missing(tmp_path, monkeypatch,
                                                                     full):
    """grades.csv is rewritten after every notebook: refused once, written at the end."""
    sub = _class(tmp_path, monkeypatch)
    real = _fake_run([])

    def fills_then_frees(task, entries, jobs, executor, on_result, warm_boxes=False):
        full.add("grades.csv")
        real(task, entries[:1], jobs, executor, on_result)
        full.discard("grades.csv")
        return real(task, entries, jobs, executor, on_result)

    monkeypatch.setattr(running, "run", fills_then_frees)
    graded = grade_class(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    assert graded.missing == {}


def test_outputs_names_exactly_the_files_a_writer_did_not_replace(tmp_path):
    (tmp_path / "b.txt").write_text("old")
    outputs = Outputs(tmp_path, {"c.txt": "earlier"})

    def writes_a_then_fails():
        _atomic.write_text(tmp_path / "a.txt", "new")
        raise OSError(errno.EDQUOT, os.strerror(errno.EDQUOT))

    assert outputs.write(["a.txt", "b.txt"], writes_a_then_fails) is None
    assert outputs.missing == {"b.txt": os.strerror(errno.EDQUOT), "c.txt": "earlier"}
    assert outputs.write(["b.txt", "c.txt"], _atomic.write_text, tmp_path / "b.txt",
                         "x") == tmp_path / "b.txt"  # the writer's value
    assert outputs.missing == {"c.txt": "earlier"}  # a writer that did not touch c keeps it
    outputs.pending(["d.txt"])
    assert outputs.missing["d.txt"] == writing.PENDING
    with pytest.raises(ValueError):  # only the file system's refusals are recorded
        outputs.write(["d.txt"], int, "x")


def test_grade_raises_naming_what_it_could_not_write(tmp_path, monkeypatch, full):
    sub = _class(tmp_path, monkeypatch)
    full.add("summary.csv")
    with pytest.raises(OSError, match=f"summary.csv \\({ENOSPC}\\)"):
        grade(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    assert (tmp_path / "out" / "grades.csv").is_file()


def test_the_command_exits_2_and_prints_the_rerun_that_writes_the_rest(
        tmp_path, monkeypatch, full, capsys):
    sub = _class(tmp_path, monkeypatch)
    out = tmp_path / "out"
    full.add("summary.png")
    assert main(["grade", str(sub), "--assignment", "calibration", "--out", str(out),
                 "--seed", "1", "--no-similarity"]) == 2
    err = capsys.readouterr().err.splitlines()
    again = (f"gpsaccel grade {sub} --assignment calibration --out {out} --no-similarity "
             f"--from-grades")
    assert err == [f"NOT WRITTEN ({ENOSPC}): 1 file(s), listed in grading.json's 'missing'",
                   f"  summary.png: once there is room, {again}"]
    full.clear()
    assert main(again.split()[1:]) == 0
    assert (out / "summary.png").is_file()
    assert json.loads((out / "grading.json").read_text(encoding="utf-8"))["missing"] == {}


@pytest.mark.parametrize("flag", [["--seed", "3"], ["--student", "alice"], ["--jobs", "1"],
                                  ["--timeout", "5"], ["--sandbox", "basic"]])
def test_from_grades_refuses_a_flag_it_cannot_honour(tmp_path, capsys, flag):
    sub = tmp_path / "class"
    sub.mkdir()
    assert main(["grade", str(sub), "--assignment", "calibration", "--from-grades",
                 *flag]) == 2
    assert f"leave out {flag[0]}" in capsys.readouterr().err


def test_from_grades_needs_a_run_of_this_homework(tmp_path, monkeypatch):
    sub = _class(tmp_path, monkeypatch)
    with pytest.raises(ValueError, match="no grading.json"):
        rewrite_class(sub, "calibration", tmp_path / "nothing")
    grade_class(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    with pytest.raises(ValueError, match="holds the grades of 'calibration', not 'tracker'"):
        rewrite_class(sub, "tracker", tmp_path / "out")
    (tmp_path / "out" / "grades.json").unlink()
    with pytest.raises(ValueError, match="no grades.json of the last run"):
        rewrite_class(sub, "calibration", tmp_path / "out")


def test_from_grades_refuses_a_grades_json_the_last_run_could_not_replace(
        tmp_path, monkeypatch, full):
    """grades.json left from an earlier run (this run's was refused) would put stale grades in
    the gradebooks: the rerun refuses it."""
    sub = _class(tmp_path, monkeypatch)
    grade_class(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    full.add("grades.json")
    graded = grade_class(sub, "calibration", out=tmp_path / "out", seed=2, similarity=False)
    assert graded.missing == {"grades.json": ENOSPC}
    full.clear()
    with pytest.raises(ValueError, match="no grades.json of the last run"):
        rewrite_class(sub, "calibration", tmp_path / "out")


def test_a_refused_similarity_report_is_named_and_from_grades_writes_it(tmp_path, monkeypatch,
                                                                         full):
    """The report's files and its counts at the end of summary.csv go through the run's
    outputs: a refused write names them (the grades and the other files stand), and the
    class-wide step alone writes them once there is room."""
    sub = _class(tmp_path, monkeypatch)
    full.add("similarity.html")
    graded = grade_class(sub, "calibration", out=tmp_path / "out", seed=1)
    out = graded.out
    # similarity.csv was written before the page failed; the counts after it never were
    assert graded.missing == {"similarity.html": ENOSPC, "summary.csv": ENOSPC}
    assert (out / "similarity.csv").is_file() and not (out / "similarity.html").exists()
    assert "integrity report" not in (out / "summary.csv").read_text(encoding="utf-8")
    assert [g.status for g in graded.grades] == ["graded", "graded"]
    full.clear()
    again = rewrite_class(sub, "calibration", out)
    assert again.missing == {} and (out / "similarity.html").is_file()
    summary = (out / "summary.csv").read_text(encoding="utf-8")
    assert summary.count("integrity report,similarity.html") == 1
    assert any(ln.startswith("similarity: 0 notebooks compared") for ln in again.classwide)


def test_grading_json_holds_the_seed_and_is_the_owners_alone(tmp_path, monkeypatch):
    """grading.json records the class's seed (drawn secret unless given): readable by its owner
    only, as check --json's file is, on the first write, the record's end and a rewrite."""
    sub = _class(tmp_path, monkeypatch)
    graded = grade_class(sub, "calibration", out=tmp_path / "out", roster=ROSTER,
                         similarity=False)
    record = graded.out / "grading.json"
    assert json.loads(record.read_text(encoding="utf-8"))["seed"] is not None
    assert record.stat().st_mode & 0o777 == 0o600
    record.chmod(0o644)
    rewrite_class(sub, "calibration", graded.out, ROSTER, similarity=False)
    assert record.stat().st_mode & 0o777 == 0o600
