"""``gpsaccel grade --roster <Canvas's gradebook export> --canvas-column``: canvas.csv's grade
column named as the roster's assignment column, so Canvas's import fills that assignment instead
of creating one; a column the roster lacks is refused naming the flag and the columns it has;
without the flag, a roster with one assignment column gets the line naming it."""

from __future__ import annotations

import csv

from gpsaccel.classrun import running
from gpsaccel.cli import main

from ..classrun.test_grading import _fake_run

ROSTER = ("Student,ID,SIS User ID,SIS Login ID,Section,Homework 1 (5501),Current Score\n"
          "    Points Possible,,,,,10.00,(read only)\n"
          '"Nguyen, An",84500,S1001,anguyen,A,,\n'
          '"Doe, Jane",84501,S1002,jdoe,A,,\n')


def _class(tmp_path, monkeypatch):
    sub = tmp_path / "class"
    for cid in ("84500", "84501"):
        (sub / cid).mkdir(parents=True)
        (sub / cid / "calibration.ipynb").write_text("{}")
    (tmp_path / "roster.csv").write_text(ROSTER)
    monkeypatch.setattr(running, "run", _fake_run([]))
    return sub


def _grade(tmp_path, *flags: str) -> int:
    return main(["grade", str(tmp_path / "class"), "--assignment", "calibration", "--out",
                 str(tmp_path / "out"), "--no-similarity", "--roster",
                 str(tmp_path / "roster.csv"), *flags])


def _header(tmp_path) -> list[str]:
    with open(tmp_path / "out" / "canvas.csv", newline="", encoding="utf-8") as f:
        return next(csv.reader(f))


def test_canvas_column_names_the_grade_column_as_the_rosters_assignment(
        tmp_path, monkeypatch, capsys):
    _class(tmp_path, monkeypatch)
    assert _grade(tmp_path, "--seed", "1") == 0
    out = capsys.readouterr().out
    assert _header(tmp_path)[-1] == "Calibrating an accelerometer with GPS (report 000)"
    assert "--canvas-column 'Homework 1 (5501)'" in out  # the one column to pass, quoted
    assert _grade(tmp_path, "--regrade", "--canvas-column", "Homework 1 (5501)") == 0
    assert "--canvas-column" not in capsys.readouterr().out
    assert _header(tmp_path) == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section",
                                 "Homework 1 (5501)"]
    # --from-grades writes it under the same name
    (tmp_path / "out" / "canvas.csv").unlink()
    assert _grade(tmp_path, "--from-grades", "--canvas-column", "Homework 1 (5501)") == 0
    assert _header(tmp_path)[-1] == "Homework 1 (5501)"


def test_a_column_the_roster_lacks_is_refused_naming_the_columns_it_has(
        tmp_path, monkeypatch, capsys):
    _class(tmp_path, monkeypatch)
    assert _grade(tmp_path, "--canvas-column", "Current Score") == 2
    err = capsys.readouterr().err
    assert "--canvas-column: 'Current Score' is not a column" in err
    assert "'Homework 1 (5501)'" in err
    assert not (tmp_path / "out").exists()
    (tmp_path / "ids.txt").write_text("84500\n84501\n")
    assert main(["grade", str(tmp_path / "class"), "--assignment", "calibration",
                 "--roster", str(tmp_path / "ids.txt"), "--canvas-column", "HW (1)"]) == 2
    assert "no assignment column (read as one id a line" in capsys.readouterr().err
    assert main(["grade", str(tmp_path / "class"), "--assignment", "calibration",
                 "--canvas-column", "HW (1)"]) == 2
    assert "give --roster" in capsys.readouterr().err
