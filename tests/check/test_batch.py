"""A class check nothing can take down (gpsaccel.classrun, ``gpsaccel check DIR``): hostile files in a
class of correct ones, a parent killer, a daemon after the JSON, Ctrl-C; under every backend.

The command runs as a child process (``python -m gpsaccel.cli``), as an instructor runs it, so a
submission that kills its parent hits a real command line.  Every hostile process is found by PID
(tests/_hostile.py) and must be dead when the command returns.
"""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time

import pytest

from gpsaccel import sandbox as sb
from gpsaccel.classrun import PYTHON, check_many, log_path, walk, write_json
from gpsaccel.sandbox import _boxuser

from .._hostile import MARKER


def _class(tmp_path, hostile, hostile_files):
    """A class folder: three honest files, the given hostile ones, a classmate copier."""
    folder = tmp_path / "class"
    folder.mkdir()
    for name in ("correct_gps_rate.py", "correct_covariance.py", "mutant_m0_order.py"):
        shutil.copy(hostile.SUBMISSIONS / name, folder / name)
    for name in hostile_files:
        shutil.copy(hostile.DIR / name, folder / name)
    for name in ("classmate_alice.py", "copier.py"):
        shutil.copy(hostile.DIR / "classmates" / name, folder / name)
    return folder


def _cli(args, hostile, **kw):
    return subprocess.Popen([sys.executable, "-m", "gpsaccel.cli", "check", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=hostile.env(), **kw)


def test_the_walk_takes_top_level_entries_and_notes_the_rest(tmp_path):
    (tmp_path / "a.py").write_text("def kalman_filter(z):\n    pass\n")
    (tmp_path / "b.py").write_text("def kf(z):\n    pass\n")  # misnamed: stays, to be reported
    (tmp_path / "__init__.py").write_text("")
    (tmp_path / "notes.txt").write_text("")
    (tmp_path / ".hidden").mkdir()
    (tmp_path / "carol").mkdir()
    (tmp_path / "carol" / "main.py").write_text("from helpers import f as kalman_filter\n")
    (tmp_path / "carol" / "helpers.py").write_text("def f(z):\n    pass\n")
    entries, notes = walk([tmp_path], PYTHON)
    assert [e.path.name for e in entries] == ["a.py", "b.py", "carol"]  # helpers.py is carol's
    assert any("__init__" in n for n in notes) and any("notes.txt" in n for n in notes)
    assert any(n.endswith(".hidden: skipped (hidden)") for n in notes)  # nothing silent


@pytest.mark.parametrize("workers", [1, 2])
def test_a_class_with_hostile_files_keeps_every_honest_verdict(tmp_path, backend, workers,
                                                               hostile, watch):
    folder = _class(tmp_path, hostile, ["parent_killer.py", "daemon.py"])
    out = tmp_path / "results.json"
    proc = _cli([folder, "--runs", "2", "--workers", workers, "--sandbox", backend,
                 "--timeout", "20", "--json", out], hostile)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 1, stderr  # some fail, none crashed the command
    assert f"sandbox: {backend}" in stderr
    time.sleep(0.5)  # a surviving daemon would have rewritten the JSON by now
    data = json.loads(out.read_text(encoding="utf-8"))
    by_name = {r["subject"]: r for r in data["results"]}
    assert len(by_name) == 7 and data["settings"]["sandbox"] == backend
    assert by_name["correct_gps_rate.py"]["passed"] and by_name["correct_covariance.py"]["passed"]
    assert by_name["classmate_alice.py"]["passed"]
    assert by_name["mutant_m0_order.py"]["codes"] == ["m0-order"]
    assert by_name["copier.py"]["codes"] == ["import-error"]
    assert not by_name["daemon.py"]["passed"]
    # basic as root: the killer runs as a uid of its own and cannot signal its parent; as
    # another user it can, the check's process dies: checker-error for that file only.  bwrap:
    # its parent is the PID namespace's init, which ignores the signal.
    assert by_name["parent_killer.py"]["codes"] == (
        ["checker-error"] if backend == "basic" and not sb.basic_is_safe() else ["exception"])
    lines = log_path(out).read_text(encoding="utf-8").splitlines()
    assert sorted(json.loads(line)["subject"] for line in lines) == sorted(by_name)
    assert "3 of 7 passed" in stdout
    assert watch.seen, "the hostile processes were never seen"
    assert not hostile.alive(watch.seen), f"alive after the command: {hostile.alive(watch.seen)}"


@pytest.mark.parametrize("workers", [1, 2])
def test_ctrl_c_kills_every_student_process_and_writes_what_is_done(tmp_path, backend, workers,
                                                                    hostile, watch):
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", folder / "a_correct.py")
    (folder / "b_spins.py").write_text(
        "import ctypes\n\nctypes.CDLL(None).prctl(15, b'" + MARKER + "', 0, 0, 0)\n\n\n"
        "def kalman_filter(z):\n    while True:\n        pass\n")
    shutil.copy(folder / "b_spins.py", folder / "c_spins.py")
    out = tmp_path / "results.json"
    proc = _cli([folder, "--runs", "2", "--workers", workers, "--sandbox", backend,
                 "--timeout", str(10 * hostile.HANG), "--json", out], hostile)
    try:
        _interrupt(proc, out, watch, hostile)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_a_class_check_as_ctrl_c_does(tmp_path, backend, sig, hostile,
                                                              watch):
    """``timeout``, ``systemctl stop``, ``docker stop`` and a closed terminal stop the check as
    Ctrl-C does: what finished is written, every box is killed before the checker exits (counted
    when it has exited, no clock), and the status is the shell's 128 + the signal."""
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", folder / "a_correct.py")
    for name in ("b_spins.py", "c_spins.py"):
        (folder / name).write_text(
            "import ctypes\n\nctypes.CDLL(None).prctl(15, b'" + MARKER + "', 0, 0, 0)\n\n\n"
            "def kalman_filter(z):\n    while True:\n        pass\n")
    out = tmp_path / "results.json"
    proc = _cli([folder, "--runs", "2", "--workers", 2, "--sandbox", backend,
                 "--timeout", str(10 * hostile.HANG), "--json", out], hostile)
    try:
        _interrupt(proc, out, watch, hostile, sig)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _interrupt(proc, out, watch, hostile, sig=signal.SIGINT):
    deadline = time.monotonic() + hostile.HANG  # a hang guard; the event is started()
    log = log_path(out)

    def started() -> bool:  # the correct file is done, a spinning one runs
        return bool(watch.seen) and log.exists() and log.read_text(encoding="utf-8").strip() != ""

    while not started() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    assert started(), "the check did not get going"
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=hostile.HANG)
    assert proc.returncode == 128 + sig, (stdout, stderr)
    assert not hostile.alive(watch.seen), f"alive when the check exited: {hostile.alive(watch.seen)}"
    assert "interrupted" in stderr
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["settings"]["interrupted"] is True
    assert [r["subject"] for r in data["results"]] == ["a_correct.py"]
    left = hostile.wait_gone(watch.seen)
    assert not left, f"alive after Ctrl-C: {left}"


def test_check_many_reports_a_dead_check_and_goes_on(tmp_path, hostile, watch, monkeypatch):
    """The unsafe basic box (the checker's own user, forced): the killer kills its check's
    process; the batch records it and goes on."""
    monkeypatch.setattr(_boxuser, "box_uid", lambda: None)  # as a user other than root
    seen = []
    paths = [hostile.DIR / "parent_killer.py", hostile.SUBMISSIONS / "correct_gps_rate.py"]
    with pytest.raises(ValueError, match="--allow-unsafe-basic"):
        check_many(paths, n_runs=2, sandbox="basic", max_workers=1)
    results = check_many(paths, n_runs=2, sandbox="basic", max_workers=1, on_result=seen.append,
                         allow_unsafe_basic=True)
    assert [r["codes"] for r in results] == [["checker-error"], []]
    assert "died (signal SIGKILL)" in results[0]["findings"][0]["message"]
    assert [r["subject"] for r in seen] == ["parent_killer.py", "correct_gps_rate.py"]
    assert not hostile.alive(watch.seen)


def test_check_many_in_process_keeps_order(hostile):
    paths = [hostile.SUBMISSIONS / "broken_no_function.py",
             hostile.SUBMISSIONS / "correct_gps_rate.py"]
    results = check_many(paths, n_runs=2, executor=None)
    assert [r["subject"] for r in results] == ["broken_no_function.py", "correct_gps_rate.py"]
    assert [r["passed"] for r in results] == [False, True]


def test_json_is_written_atomically(tmp_path):
    path = tmp_path / "out" / "results.json"
    write_json([{"subject": "a"}], path, runs=3)
    assert json.loads(path.read_text())["settings"] == {"runs": 3}
    assert [p.name for p in path.parent.iterdir()] == ["results.json"]  # no temporary left


def test_cli_names_a_bad_limit_and_a_missing_bwrap(tmp_path, hostile, monkeypatch, capsys):
    from gpsaccel import sandbox as sb
    from gpsaccel.cli import main
    from gpsaccel.sandbox import confinement

    path = hostile.SUBMISSIONS / "correct_gps_rate.py"
    assert main(["check", str(path), "--memory", "100"]) == 2  # the flag's own validator
    assert "argument --memory: must be a number >= 256" in capsys.readouterr().err
    monkeypatch.setattr(confinement, "bwrap_path", lambda: None)
    assert main(["check", str(path), "--sandbox", "bwrap"]) == 2
    assert "apt-get install bubblewrap" in capsys.readouterr().err
    assert sb.resolve_backend("auto") == "basic"
    out = tmp_path / "r.json"
    assert main(["check", str(path), "--runs", "2", "--json", str(out)]) == 0
    assert "sandbox: basic (bubblewrap not available" in capsys.readouterr().err
    assert json.loads(out.read_text())["settings"]["sandbox"] == "basic"
