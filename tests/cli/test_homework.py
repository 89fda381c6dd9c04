"""gpsaccel grade's flags against what a student's box can reach (cli/homework.py)."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

from gpsaccel.classrun.running import open_to_others
from gpsaccel.cli import main


@pytest.fixture
def open_folder():
    """A folder other users may enter, under /tmp (pytest's own is 0700: nothing in it is open)."""
    d = Path(tempfile.mkdtemp(prefix="gpsaccel-secret-"))
    d.chmod(0o755)
    yield d
    shutil.rmtree(d)


def test_open_to_others_needs_the_file_readable_and_every_folder_above_enterable(open_folder):
    if not os.access("/tmp", os.X_OK) or not Path("/tmp").stat().st_mode & 0o001:
        pytest.skip("/tmp is not open to other users here")
    f = open_folder / "secret.txt"
    f.write_text("x" * 32)
    f.chmod(0o644)
    assert open_to_others(f)
    f.chmod(0o640)
    assert not open_to_others(f)
    f.chmod(0o644)
    open_folder.chmod(0o700)
    assert not open_to_others(f)


def test_grade_refuses_a_secret_a_basic_box_could_read(open_folder, monkeypatch, capsys):
    """A redteam notebook graded with --sandbox basic read a 0644 --secret-file and raised it: its
    feedback carried the secret.  The run now stops before any box, naming the flag and the
    chmod; a 0600 secret is taken."""
    if not Path("/tmp").stat().st_mode & 0o001:
        pytest.skip("/tmp is not open to other users here")
    from gpsaccel.classrun import running

    monkeypatch.setattr(running, "backend_of", lambda sandbox, *a: "basic")
    f = open_folder / "secret.txt"
    f.write_text("x" * 32)
    f.chmod(0o644)
    sub = open_folder / "subs"
    sub.mkdir()
    code = main(["grade", str(sub), "--assignment", "calibration", "--secret-file", str(f),
                 "--sandbox", "basic", "--out", str(open_folder / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert "--secret-file" in err and "chmod 600" in err
    assert not (open_folder / "out").exists()
    f.chmod(0o600)
    code = main(["grade", str(sub), "--assignment", "calibration", "--secret-file", str(f),
                 "--sandbox", "basic", "--out", str(open_folder / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "--secret-file" not in err  # past the check: the empty class's error
