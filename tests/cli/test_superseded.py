"""``gpsaccel grade`` on a Canvas export with resubmissions: each superseded attempt (Canvas's
``-1`` suffix names the later one) gets a line on the terminal, its file name made printable
(:func:`gpsaccel._untrusted.shown`), besides grading.json's ``skipped``; the kept attempt is
graded and no superseded one is."""

from __future__ import annotations

import json

from gpsaccel.classrun import running
from gpsaccel.cli import main

from ..classrun.test_grading import _fake_run
from .test_canvas_column import ROSTER


def test_each_superseded_attempt_gets_a_printable_line(tmp_path, monkeypatch, capsys):
    sub = tmp_path / "export"
    sub.mkdir()
    early = "nguyenan_84500_678900_calibration.ipynb"
    odd = "doe\x1b[2Jjane_84501_678901_calibration.ipynb"  # an escape a terminal would obey
    for name in (early, "nguyenan_84500_678950_calibration-1.ipynb",
                 "nguyenan_84500_678960_calibration-2.ipynb", odd,
                 "doejane_84501_678902_calibration-1.ipynb"):
        (sub / name).write_text("{}")
    (tmp_path / "roster.csv").write_text(ROSTER)
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    assert main(["grade", str(sub), "--assignment", "calibration", "--out",
                 str(tmp_path / "out"), "--seed", "1", "--no-similarity", "--roster",
                 str(tmp_path / "roster.csv")]) == 0
    assert sorted(seen) == [("84500", False, 2), ("84501", False, 1)]
    out = capsys.readouterr().out
    lines = [ln for ln in out.splitlines() if ": superseded by" in ln]
    assert sorted(lines) == [
        "not graded: doe\\x1b[2Jjane_84501_678901_calibration.ipynb: superseded by a later "
        "attempt of 84501 (grading.json's skipped)",
        f"not graded: {early}: superseded by a later attempt of 84500 (grading.json's skipped)",
        "not graded: nguyenan_84500_678950_calibration-1.ipynb: superseded by a later attempt "
        "of 84500 (grading.json's skipped)"]
    assert "\x1b" not in out
    skipped = json.loads((tmp_path / "out" / "grading.json").read_text())["skipped"]
    assert len(skipped) == 3 and all("superseded" in s for s in skipped)
