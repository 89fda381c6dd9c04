"""The suite's on-disk cache (tests/conftest.py ``disk_cache``): a result is made once per key, and
the key moves when the cached thing's bytes or any file of the package change, so a cached lesson
or ``otter assign`` can never stand in for one the current code would produce."""

from __future__ import annotations

import multiprocessing
import time
from pathlib import Path


def _package(root: Path) -> Path:
    (root / "pkg" / "sub").mkdir(parents=True)
    (root / "pkg" / "__init__.py").write_text("x = 1\n")
    (root / "pkg" / "sub" / "data.json").write_text("{}")
    return root / "pkg"


def test_an_entry_is_made_once_per_key_and_again_for_a_new_key(disk_cache, tmp_path):
    cache = type(disk_cache)(tmp_path / "cache", package=_package(tmp_path))
    made = []

    def make(target):
        made.append(target)
        target.write_text(f"made {len(made)}")

    key = cache.key("lesson", b"notebook bytes", "20")
    assert cache.path("k", key, make).read_text() == "made 1"
    assert cache.path("k", key, make).read_text() == "made 1" and len(made) == 1
    other = cache.key("lesson", b"notebook bytes, edited", "20")
    assert other != key and cache.key("lesson", b"notebook bytes", "10") != key
    assert cache.path("k", other, make).read_text() == "made 2"


def test_a_failed_make_leaves_nothing(disk_cache, tmp_path):
    cache = type(disk_cache)(tmp_path / "cache", package=_package(tmp_path))

    def fails(target):
        target.write_text("half")
        raise RuntimeError("cell raised")

    key = cache.key("x")
    try:
        cache.path("k", key, fails)
    except RuntimeError:
        pass
    assert not (tmp_path / "cache" / "k" / key).exists()
    assert [p.name for p in (tmp_path / "cache" / "k").iterdir()] == [f"{key}.lock"]


def test_any_package_file_moves_every_key_but_bytecode_does_not(disk_cache, tmp_path):
    pkg = _package(tmp_path)
    before = type(disk_cache)(tmp_path / "c", package=pkg).key("lesson", b"nb")
    (pkg / "__pycache__").mkdir()
    (pkg / "__pycache__" / "x.cpython-311.pyc").write_bytes(b"\0")
    assert type(disk_cache)(tmp_path / "c", package=pkg).key("lesson", b"nb") == before
    (pkg / "sub" / "data.json").write_text('{"a": 1}')
    assert type(disk_cache)(tmp_path / "c", package=pkg).key("lesson", b"nb") != before


def _slow_make(log: Path):
    def make(target):
        with open(log, "a") as f:
            f.write("made\n")
        time.sleep(0.5)  # the other process asks meanwhile (no timing is asserted)
        target.write_text("entry")
    return make


def test_two_processes_asking_for_one_key_make_it_once(disk_cache, tmp_path):
    cache = type(disk_cache)(tmp_path / "cache", package=_package(tmp_path))
    key, log = cache.key("shared"), tmp_path / "log"
    ctx = multiprocessing.get_context("fork")
    procs = [ctx.Process(target=cache.path, args=("k", key, _slow_make(log))) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
    assert [p.exitcode for p in procs] == [0, 0]
    assert log.read_text() == "made\n"
    assert (tmp_path / "cache" / "k" / key).read_text() == "entry"


def test_the_default_cache_hashes_the_installed_gpsaccel(disk_cache):
    import gpsaccel

    assert disk_cache.package == Path(gpsaccel.__file__).resolve().parent
