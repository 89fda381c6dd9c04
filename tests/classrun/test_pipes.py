"""Nothing half-written (issue 38, item 3): a reader that went away (``| head -1``, a closed
pipe) or a SIGPIPE never stops ``gpsaccel grade`` or ``gpsaccel check`` before every file is
written, and the exit status stays the run's own.  Before, ``gpsaccel grade ... | head -1`` said
"error: Broken pipe", exit 2, and wrote no gradebook and no similarity report.  The commands run
as child processes, as an instructor runs them; ``grade()`` from Python writes the same files."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gpsaccel.classrun import grade

from .._hostile import SUBMISSIONS, env_with_package
from ..assignments.conftest import tracker_with_numpy_filter

#: Everything ``gpsaccel grade --roster`` writes.
GRADE_FILES = ("grades.csv", "grades.json", "grading.json", "summary.csv", "summary.png",
               "canvas.csv", "moodle.csv", "gradescope-roster.csv", "gradescope-scores.csv",
               "similarity.csv", "similarity.html")


@pytest.fixture(scope="module")
def klass(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("pipes")
    for who in ("alice", "bob"):
        tracker_with_numpy_filter(root / "class" / who / "tracker.ipynb")
    (root / "roster.csv").write_text("id,name,email\nalice,Alice A,a@u.edu\nbob,Bob B,b@u.edu\n"
                                     "carol,Carol C,c@u.edu\n", encoding="utf-8")
    return root


def _closed_pipe() -> int:
    """The write end of a pipe whose reader is already gone: every write to it fails (EPIPE)."""
    read, write = os.pipe()
    os.close(read)
    return write


def _run(args: list[str], cwd: Path, stdout: int) -> subprocess.Popen:
    try:
        return subprocess.Popen([sys.executable, "-m", "gpsaccel.cli", *args], cwd=cwd,
                                stdout=stdout, stderr=subprocess.PIPE, text=True,
                                env=env_with_package())
    finally:
        os.close(stdout)


def _files(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` but the picture, timings and dates masked."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file() and p.suffix != ".png":
            text = p.read_text(encoding="utf-8")
            text = re.sub(r'"(seconds|started)": [^,}\n]+', r'"\1": T', text)
            out[p.relative_to(folder).as_posix()] = re.sub(r",\d+\.\d(,[a-z]*\r?\n)", r",T\1",
                                                           text)  # grades.csv's seconds
    return out


@pytest.mark.slow
def test_grade_into_a_closed_pipe_and_a_sigpipe_writes_every_file(klass):
    out = klass / "cli"
    proc = _run(["grade", "class", "--assignment", "tracker", "--seed", "3", "--jobs", "2",
                 "--roster", "roster.csv", "--out", str(out)], klass, _closed_pipe())
    try:
        deadline = time.monotonic() + 300  # a hang guard: the event is the run's record
        while not (out / "grading.json").is_file() and proc.poll() is None \
                and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGPIPE)  # mid-run: the notebooks are being graded
        _, err = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "Broken pipe" not in err and "Exception ignored" not in err, err
    assert sorted(p.name for p in out.iterdir()) == sorted((*GRADE_FILES, "feedback"))
    assert "Bob B,,b@u.edu" not in (out / "moodle.csv").read_text()  # bob was graded: a total
    # the Python API writes what the command writes
    python = klass / "python"
    grades = grade(klass / "class", "tracker", out=python, seed=3, jobs=2,
                   roster=klass / "roster.csv")
    assert [(g.student, g.total) for g in grades] == [("alice", 10.0), ("bob", 10.0)]
    assert _files(python) == _files(out)


@pytest.mark.slow
def test_check_into_a_closed_pipe_writes_its_files_and_keeps_its_status(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(SUBMISSIONS / "correct_gps_rate.py", folder / "a.py")
    shutil.copy(SUBMISSIONS / "mutant_m0_order.py", folder / "b.py")
    proc = _run(["check", "class", "-v", "--runs", "2", "--seed", "1", "--workers", "1",
                 "--json", "out.json"], tmp_path, _closed_pipe())
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 1, err  # b.py fails: the check's own status, not 2
    assert "Broken pipe" not in err and "Exception ignored" not in err, err
    assert '"codes": [\n        "m0-order"' in (tmp_path / "out.json").read_text()
    assert len((tmp_path / "out.jsonl").read_text().splitlines()) == 2
