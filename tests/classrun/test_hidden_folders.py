"""``gpsaccel check`` of a class under ``--sandbox basic``: every classmate's file is out of a box's
reach, as under bwrap, and the repository's own world-readable tests/submissions are still checked
when ``auto`` falls back to basic (the refusal tried before stopped them).

The class is laid out world-readable (0755/0644, as an unzipped export) under a folder of ``/tmp``
other users may enter (pytest's ``tmp_path`` is 0700, which would hide it anyway).  Mallory's
filter is Alice's, and at import it tries to read Alice's file by absolute path and by a relative
path from its box: one read and it defines no filter (``no-kalman-filter``).  With the hiding taken
away the same file must fail so, which shows the attack reaches what it aims at.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import tempfile
from pathlib import Path

import pytest

from gpsaccel import sandbox as sb
from gpsaccel.classrun import check_many, running
from gpsaccel.classrun.checking import plan_check

SUBMISSIONS = Path(__file__).resolve().parents[1] / "submissions"

MALLORY = '''
import os
_alice = {alice!r}
_read = []
for _p in (_alice, os.path.relpath(_alice, os.getcwd())):
    try:
        with open(_p, "rb") as _f:
            _read.append(_f.read())
    except OSError:
        pass
if not _read:
'''

pytestmark = pytest.mark.skipif(not sb.basic_is_safe(), reason="basic is safe only as root")


@pytest.fixture
def klass():
    top = Path(tempfile.mkdtemp(prefix="gpsaccel-hidecheck-"))
    try:
        top.chmod(0o755)
        folder = top / "class"
        folder.mkdir(mode=0o755)
        alice = folder / "alice.py"
        shutil.copy(SUBMISSIONS / "correct_joseph.py", alice)
        own = alice.read_text(encoding="utf-8")
        body = "".join("    " + ln + "\n" if ln.strip() else "\n" for ln in own.splitlines())
        (folder / "mallory.py").write_text(
            "from __future__ import annotations\n" * ("from __future__" in own)
            + MALLORY.format(alice=str(alice)) + body.replace(
                "    from __future__ import annotations\n", "    pass\n"), encoding="utf-8")
        for p in folder.iterdir():
            p.chmod(0o644)
        yield folder
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.parametrize("warm", [False, True], ids=["cold", "warm"])
def test_a_classmates_file_is_out_of_a_basic_box_reach(klass, warm):
    results = check_many([klass], n_runs=2, seed=1, sandbox="basic", max_workers=2,
                         warm_boxes=warm)
    by = {r["subject"]: r for r in results}
    assert by["alice.py"]["passed"], by["alice.py"]
    assert by["mallory.py"]["passed"], by["mallory.py"]  # it read nothing, so it kept its filter


def test_without_the_hiding_the_attack_reads_the_classmate(klass, monkeypatch):
    monkeypatch.setattr(running, "hidden_from_boxes", lambda *a, **k: contextlib.nullcontext())
    by = {r["subject"]: r for r in check_many([klass], n_runs=2, seed=1, sandbox="basic",
                                              max_workers=2, warm_boxes=False)}
    assert by["alice.py"]["passed"]
    assert by["mallory.py"]["codes"] == ["no-kalman-filter"], by["mallory.py"]


def test_the_repositorys_own_submissions_are_checked_when_auto_falls_back_to_basic(monkeypatch):
    """tests/submissions is 0755 in a checkout: hidden (Landlock here), not refused, and its
    files are checked with their folder hidden from every box."""
    monkeypatch.setattr(sb, "resolve_backend", lambda backend: "basic")
    plan = plan_check([SUBMISSIONS, SUBMISSIONS / "correct_gps_rate.py"], n_runs=2, seed=1,
                      sandbox="auto")
    assert plan.backend == "basic"
    with running.hidden_from_boxes(plan.backend, *plan.hidden()) as hidden:
        assert hidden == [str(SUBMISSIONS)]  # the folder once (the file's folder is the same)
    results = check_many([SUBMISSIONS / "correct_gps_rate.py", SUBMISSIONS / "mutant_w_value.py"],
                         n_runs=2, seed=1, sandbox="auto", max_workers=2)
    assert [r["passed"] for r in results] == [True, False]
    assert results[1]["codes"], results[1]


def _reads_the_log(folder: Path, log: Path) -> None:
    """Mallory of ``folder`` (checked after Alice) reads ``log`` at import: a read, even of an
    empty log, and her import stops (``import-error``); else she is Alice."""
    alice = (folder / "alice.py").read_text(encoding="utf-8")
    (folder / "mallory.py").write_text(
        f"try:\n    open({str(log)!r}, 'rb').read()\nexcept OSError:\n    pass\nelse:\n"
        f"    raise SystemExit\n\n{alice}", encoding="utf-8")


@pytest.mark.parametrize("hidden", [True, False], ids=["hidden", "open"])
def test_the_check_s_json_and_its_log_are_out_of_a_basic_box_reach(klass, hidden, monkeypatch):
    """``check --json`` writes the class's seed and every classmate's findings as the run goes
    (the ``.jsonl`` log): the files are their owner's alone (writing.PRIVATE) and their folder,
    world-readable beside the class as an instructor makes it, is hidden from the boxes.  With
    both taken away (``open``), the same student reads the log: the attack reaches it."""
    from gpsaccel.classrun import writing
    from gpsaccel.cli import main

    out = klass.parent / "results"
    out.mkdir(mode=0o755)
    _reads_the_log(klass, out / "results.jsonl")
    if not hidden:
        monkeypatch.setattr(running, "hidden_from_boxes", lambda *a, **k: contextlib.nullcontext())
        monkeypatch.setattr(writing, "PRIVATE", 0o644)
    status = main(["check", str(klass), "--runs", "2", "--sandbox", "basic", "--workers", "1",
                   "--boxes", "cold", "--json", str(out / "results.json")])
    results = {r["subject"]: r for r in json.loads((out / "results.json").read_text())["results"]}
    assert results["alice.py"]["passed"], results["alice.py"]
    if hidden:
        assert status == 0 and results["mallory.py"]["passed"], results["mallory.py"]
        for name in ("results.json", "results.jsonl"):
            assert (out / name).stat().st_mode & 0o777 == 0o600, name
    else:
        assert results["mallory.py"]["codes"] == ["import-error"], results["mallory.py"]


def test_a_log_left_readable_by_an_earlier_run_is_the_owners_alone_again(tmp_path):
    from gpsaccel.classrun.writing import appender, write_json

    log, out = tmp_path / "r.jsonl", tmp_path / "r.json"
    for p in (log, out):
        p.write_text("old", encoding="utf-8")
        p.chmod(0o644)
    appender(log)({"subject": "a.py"})
    write_json([], out, seed=1)
    assert log.stat().st_mode & 0o777 == 0o600 and out.stat().st_mode & 0o777 == 0o600
    assert json.loads(log.read_text(encoding="utf-8")) == {"subject": "a.py"}
