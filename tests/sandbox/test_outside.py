"""Folders outside the package hidden from every box (:mod:`gpsaccel.sandbox.outside`): a class's
own, world-readable as an unzipped LMS export is, read by a box in every way test_attacks.py
tries on the package's hidden folders (libc open and openat, /proc/self/root, /proc/self/cwd and
``..`` from the box, a symbolic and a hard link made in /tmp), under both backends, with boxes
started cold and warm (the zygotes started inside the block, as a class run starts them); and
the same box without the block, which must read them (so the reads reach what they aim at)."""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import fence, warmbox, zygote

from .test_attacks import _RAW_READ, LIMITS, REFUSED, WAYS

_NO_BWRAP = pytest.mark.skipif(sb.bwrap_path() is None, reason="bubblewrap does not work here")
_NO_WARM = pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on Linux")
needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="basic isolates a student only as root")


@pytest.fixture
def klass():
    """A class folder other users may enter, under /tmp (pytest's tmp_path is 0700), holding a
    classmate's notebook 0644 and a sub-folder of grades."""
    top = Path(tempfile.mkdtemp(prefix="gpsaccel-outside-"))
    try:
        top.chmod(0o755)
        (top / "Classmate").mkdir(mode=0o755)
        (top / "Classmate" / "hw.ipynb").write_text("def update(): return 42\n" * 20)
        (top / "grades.csv").write_text("student,total\nClassmate,10\n")
        for p in (top / "Classmate" / "hw.ipynb", top / "grades.csv"):
            p.chmod(0o644)
        yield top
    finally:
        shutil.rmtree(top, ignore_errors=True)


def _read(tmp_path: Path, folder: Path, backend: str) -> np.ndarray:
    rel = ["Classmate/hw.ipynb", "grades.csv"]
    f = tmp_path / "s.py"
    f.write_text(f"REL = {rel!r}\n" + _RAW_READ.replace("import gpsaccel\n", "").replace(
        "os.path.dirname(gpsaccel.__file__)", repr(str(folder))))
    box = sb.run(sb.load_submission(f, "f"), [sb.Call("f", (np.zeros(1),), (
        sb.Output("read", (len(rel) * WAYS,)),))], LIMITS, backend)
    assert box.failure is None, (box.detail, box.problem, box.output)
    return box.results[0]["read"].reshape(len(rel), WAYS)


@needs_root
@pytest.mark.parametrize("box,warm", [
    pytest.param("basic", False, id="basic"),
    pytest.param("basic", True, id="basic-warm", marks=_NO_WARM),
    pytest.param("bwrap", False, id="bwrap", marks=_NO_BWRAP),
    pytest.param("bwrap", True, id="bwrap-warm", marks=[_NO_BWRAP, _NO_WARM])])
def test_a_hidden_class_folder_is_read_by_no_box(tmp_path, klass, box, warm):
    served = warmbox.SERVED[0]
    with sb.hiding({"submissions": klass}) as hidden:
        assert hidden == [os.path.realpath(klass)]
        with sb.warm_boxes(sb.Warm(("numpy",))) if warm else contextlib.nullcontext():
            read = _read(tmp_path, klass, box)
    assert set(read.ravel().tolist()) <= REFUSED, read
    assert (warmbox.SERVED[0] > served) == warm  # the warm case's box did start warm


@needs_root
def test_without_hiding_a_basic_box_reads_the_class(tmp_path, klass):
    read = _read(tmp_path, klass, "basic")
    sizes = [(klass / r).stat().st_size for r in ("Classmate/hw.ipynb", "grades.csv")]
    assert read[:, 0].tolist() == sizes  # libc open: the world-readable files are read


def test_a_folder_holding_what_every_box_reads_is_refused_naming_the_argument():
    with pytest.raises(ValueError, match=r"^submissions: .* holds .*every box must read"):
        with sb.hiding({"submissions": sys.prefix}):
            pass
    with sb.hiding({"secret_file": sys.prefix}, optional=("secret_file",)) as hidden:
        assert hidden == []


@needs_root
def test_the_permissions_fence_closes_the_graders_own_folders_and_refuses_anothers(monkeypatch):
    monkeypatch.setattr(fence, "supported", lambda: "permissions")
    top = Path(tempfile.mkdtemp(prefix="gpsaccel-hideperm-"))
    try:
        mine, theirs = top / "mine", top / "theirs"
        for d in (mine, theirs):
            d.mkdir()
            d.chmod(0o755)
        with sb.hiding({"out": mine}):
            assert mine.stat().st_mode & 0o777 == 0o700
        os.chown(theirs, 65534, 65534)
        with pytest.raises(ValueError, match=r"^compare_with: .*theirs.*not yours.*chmod go-rwx"):
            with sb.hiding({"compare_with": theirs}):
                pass
        assert theirs.stat().st_mode & 0o777 == 0o755
    finally:
        shutil.rmtree(top, ignore_errors=True)


def test_the_block_ends_with_the_folders_it_hid_and_nests(klass):
    from gpsaccel.sandbox.confinement import class_dirs

    with sb.hiding({"a": klass}):
        with sb.hiding({"b": klass / "Classmate"}):
            assert class_dirs() == [os.path.realpath(klass), os.path.realpath(klass / "Classmate")]
        assert class_dirs() == [os.path.realpath(klass)]
    assert class_dirs() == []
