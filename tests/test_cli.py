"""The gpsaccel command: the main job and compare, end to end."""

from __future__ import annotations

import re

from gpsaccel.cli import main


def test_run_writes_summary_and_figures(tmp_path, capsys):
    assert main(["run", "--out", str(tmp_path), "--runs", "20"]) == 0
    out = capsys.readouterr().out
    assert "P at t = 30 s" in out
    assert re.search(r"9\.50\d+e-03", out)  # P11 at 30 s, report 000's value
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert "r000-fig01-position-error.png" in pngs and "r000-fig06-bias-estimate.png" in pngs
    assert (tmp_path / "index.html").read_text().count("<img") == len(pngs)


def test_compare_prints_the_table(capsys):
    assert main(["compare", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("information form"))
    dx, dP = (float(v) for v in row.split()[2:4])
    assert dx < 1e-10 and dP < 1e-10


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["figures", "--report", "999", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "report must be one of" in err and "Traceback" not in err
