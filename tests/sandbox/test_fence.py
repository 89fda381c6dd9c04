"""What a basic box may not read (:mod:`gpsaccel.sandbox.fence`): each fence tried on its own, as root
(as Gradescope's container runs the grader), with files read through libc (no audit event).
The Landlock fence, the one chosen where the kernel has it, is tried by every backend-parametrised
test of test_attacks.py; here the fallbacks, forced by hiding the ones before them."""

from __future__ import annotations

import errno
import os
import shutil
import tempfile

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import fence

from .test_attacks import WAYS, read_in_box

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=30, processes=16)
needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="the fallbacks are root's")

def _read(tmp_path, rel: list[str], hide: list[str]) -> np.ndarray:
    return read_in_box(tmp_path, rel, "basic", hide)


@pytest.fixture
def no_landlock(monkeypatch):
    monkeypatch.setattr(fence, "landlock_abi", lambda: 0)


@pytest.fixture
def secret_folder():
    """A folder of the package holding a "solution" (removed afterwards): what a caller hides."""
    name = f"_fence_test_{os.getpid()}"
    folder = sb.PACKAGE_DIR / name
    folder.mkdir()
    (folder / "solution.py").write_text("ANSWER = 42\n")
    try:
        yield name, folder
    finally:
        shutil.rmtree(folder)


@needs_root
@pytest.mark.skipif(not fence.mounts_allowed(), reason="this machine refuses mount namespaces")
def test_without_landlock_root_binds_an_empty_folder_over_each_hidden_one(tmp_path, no_landlock):
    read = _read(tmp_path, ["check/problem.py", "assignments/masters/calibration/graded.py",
                            "calibration/model.py"], ["check", "assignments"])
    assert read[:2].ravel().tolist() == [-errno.ENOENT] * 2 * WAYS  # empty folders over them
    size = (sb.PACKAGE_DIR / "calibration/model.py").stat().st_size
    assert read[2].tolist() == [size] * (WAYS - 1) + [-errno.EPERM]  # root's file: no hard link


@needs_root
def test_without_landlock_nor_mounts_a_folder_closed_to_others_is_the_fence(
        tmp_path, no_landlock, monkeypatch, secret_folder):
    monkeypatch.setattr(fence, "mounts_allowed", lambda: False)
    name, folder = secret_folder
    folder.chmod(0o750)  # root reads it; the box's own uid is another user
    read = _read(tmp_path, [f"{name}/solution.py", "calibration/model.py"], [name])
    assert set(read[0].tolist()) == {-errno.EACCES} and (read[1, :WAYS - 1] > 0).all()


@needs_root
def test_as_root_a_box_that_cannot_be_fenced_does_not_start(tmp_path, no_landlock, monkeypatch,
                                                            secret_folder):
    monkeypatch.setattr(fence, "mounts_allowed", lambda: False)
    name, folder = secret_folder
    folder.chmod(0o755)
    with pytest.raises(sb.NoFence, match="chmod -R o-rwx"):
        _read(tmp_path, [f"{name}/solution.py"], [name])
    assert not [p for p in os.listdir(tempfile.gettempdir()) if p.startswith(sb.BOX_PREFIX)
                and p.split("-")[2] == str(os.getpid())]  # its box folder is gone


def test_not_as_root_without_landlock_there_is_no_fence(tmp_path, no_landlock):
    """Not as root basic is not safe anyway (the box is the user): no fence, no refusal (a
    student's own check at home, on a Mac)."""
    (tmp_path / "h").mkdir()
    assert fence.choose([str(tmp_path / "h")], root=False, empty=str(tmp_path / "e")) is None


def test_nothing_to_hide_is_no_fence(tmp_path):
    assert fence.choose([str(tmp_path / "missing")], root=True, empty=str(tmp_path / "e")) is None


def test_landlock_grants_no_link_into_a_hidden_folder_nor_above_it(tmp_path):
    a = tmp_path / "a"
    (a / "hidden").mkdir(parents=True)
    (a / "pub").mkdir()
    (a / "file.txt").write_text("x")
    (a / "to_hidden").symlink_to(a / "hidden")
    (a / "to_top").symlink_to(tmp_path)
    (a / "to_pub").symlink_to(a / "pub")
    granted = {}
    for path, is_dir, fd in fence._grants([str(a / "hidden")], []):
        os.close(fd)
        granted[path] = is_dir
    assert granted[str(a / "pub")] and granted[str(a / "to_pub")]
    assert granted[str(a / "file.txt")] is False
    for absent in ("hidden", "to_hidden", "to_top"):
        assert str(a / absent) not in granted
    assert str(a) not in granted and str(tmp_path) not in granted and "/" not in granted


def test_hide_is_checked():
    sub = sb.Submission.__new__(sb.Submission)  # never run: the arguments are refused first
    for hide, allow, match in ((["check"], False, "without allow_gpsaccel"),
                               ("check", True, "a sequence"), (["../x"], True, "relative"),
                               (["/etc"], True, "relative")):
        with pytest.raises(ValueError, match=match):
            sb.run(sub, [], LIMITS, "basic", allow_gpsaccel=allow, hide=hide)
