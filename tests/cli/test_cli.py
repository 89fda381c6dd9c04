"""The gpsaccel command: the main job and compare, end to end."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from gpsaccel.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_run_writes_summary_and_figures(tmp_path, capsys):
    assert main(["run", "--out", str(tmp_path), "--runs", "20"]) == 0
    out = capsys.readouterr().out
    assert "P at t = 30 s" in out
    assert re.search(r"9\.50\d+e-03", out)  # P11 at 30 s, report 000's value
    pngs = sorted(p.name for p in tmp_path.glob("*.png"))
    assert "r000-fig01-position-error.png" in pngs and "r000-fig06-bias-estimate.png" in pngs
    assert (tmp_path / "index.html").read_text().count("<img") == len(pngs)


def test_compare_prints_the_table(capsys):
    assert main(["compare", "--seed", "1", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    for form in ("standard", "joseph", "information", "filterpy-information", "square-root"):
        row = next(line for line in out.splitlines() if line.startswith(form + " "))
        dx, dP = (float(v) for v in row.split()[1:3])
        assert dx < 1e-10 and dP < 1e-10


def test_compare_a_form_with_a_student_file(capsys):
    path = Path(__file__).parent.parent / "submissions" / "correct_joseph.py"
    assert main(["compare", "joseph", str(path), "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("correct_joseph.py"))
    assert float(row.split()[1]) < 1e-10
    assert "square-root" not in out


def test_compare_sweep_writes_one_figure(tmp_path, capsys, monkeypatch):
    from gpsaccel.calibration import compare as compare_module

    monkeypatch.setitem(compare_module.DEFAULT_FACTORS, "prior", np.array([1.0, 1e12]))
    monkeypatch.setitem(compare_module.DEFAULT_FACTORS, "gps", np.array([1.0, 1e-12]))
    assert main(["compare", "standard", "square-root", "--sweep", "prior", "--sweep", "gps",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "conditioning sweep 'prior'" in out and "conditioning sweep 'gps'" in out
    assert (tmp_path / "compare-sweep-prior-gps.png").stat().st_size > 10_000


def test_compare_bad_arguments_exit_2(capsys):
    assert main(["compare", "ud"]) == 2
    assert "neither a filter form" in capsys.readouterr().err
    path = Path(__file__).parent.parent / "submissions" / "correct_joseph.py"
    assert main(["compare", str(path), "--sweep", "gps"]) == 2
    assert "built-in forms only" in capsys.readouterr().err


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert main(["figures", "--report", "999", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "report must be one of" in err and "Traceback" not in err


def test_montecarlo_draws_figures_only_with_out(tmp_path, monkeypatch):
    """The verdicts are the command's answer; its four figures cost more CPU than a 10,000-run
    ensemble, so they are drawn when --out names a folder (and matplotlib is not even imported
    without it: a fresh process, as the command runs)."""
    monkeypatch.chdir(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    code = ("import sys; from gpsaccel.cli import main; code = main(sys.argv[1:]); "
            "print(sorted(m for m in ('matplotlib', 'gpsaccel.plots') if m in sys.modules)); "
            "sys.exit(code)")
    res = subprocess.run([sys.executable, "-c", code, "montecarlo", "--runs", "20",
                          "--no-progress"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.strip().splitlines()
    assert lines[-1] == "[]"
    assert "no figures drawn: --out DIR writes them" in lines[-2]
    assert list(tmp_path.iterdir()) == []
