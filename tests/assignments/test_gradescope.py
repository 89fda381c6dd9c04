"""The wheel the Gradescope zip carries is rebuilt from the installed package
(:func:`gpsaccel.assignments.gradescope.package_wheel`); the end-to-end autograder is in
tests/test_kit.py and tests/test_packaging.py."""

from __future__ import annotations

import zipfile
from importlib import metadata
from pathlib import Path

from gpsaccel.assignments.gradescope import package_wheel


def test_the_rebuilt_wheel_carries_its_license_and_a_record_of_every_file(tmp_path):
    """From the installed package or a checkout (where ``gpsaccel.egg-info`` names the license
    without a copy): the MIT text goes with every copy."""
    wheel = package_wheel(tmp_path)
    dist = metadata.distribution("gpsaccel")
    licenses = dist.metadata.get_all("License-File")
    assert licenses, "the installed metadata names no License-File"
    info = f"gpsaccel-{dist.version}.dist-info"
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        assert {f"{info}/licenses/{name}" for name in licenses} <= names
        assert "MIT" in z.read(f"{info}/licenses/LICENSE").decode()
        recorded = {line.split(",")[0] for line in z.read(f"{info}/RECORD").decode().splitlines()}
    assert recorded == names
    assert "gpsaccel/__init__.py" in names and not any("_lessons/masters" in n for n in names)


# ------------------------------------------------- who a submission is (issue 39 item 4)
def test_a_roster_gradescope_cannot_name_gets_no_zip_and_one_it_can_maps_each_account(
        tmp_path):
    """A plain roster of names gave a zip whose config mapped names to names: Gradescope names
    a submitter by email and SID, so every submission scored 0.  Now such a roster gets no zip
    (an error naming the students); a plain roster of emails, and Gradescope's own roster, map
    each account to its student."""
    import json

    import pytest

    from gpsaccel.assignments.gradescope import _student_id, build
    from gpsaccel.assignments.roster import Student, read

    with pytest.raises(ValueError, match=r"neither for 2 student\(s\) \('Jane Doe', 'bob'\)"):
        build("ship", tmp_path, [Student("Jane Doe"), Student("bob"), Student("a@u.edu")])
    assert not list(tmp_path.iterdir())

    def ids_of(roster) -> dict:
        with zipfile.ZipFile(build("ship", tmp_path, roster)) as z:
            return json.loads(z.read("config.json"))["ids"]

    (tmp_path / "plain.txt").write_text("Ann@U.edu\nben@u.edu\n")
    ids = ids_of(read(tmp_path / "plain.txt").students)
    meta = {"users": [{"email": "ann@u.edu", "sid": None, "name": "Ann"}]}
    assert _student_id(meta, ids) == ("Ann@U.edu", "")  # the hand-out's id: its variant
    (tmp_path / "gs.csv").write_text("First Name,Last Name,SID,Email,Role\n"
                                     "Ann,Lee,1001,ann@u.edu,Student\n"
                                     "Ben,Ray,1002,ben@u.edu,Student\n")
    ids = ids_of(read(tmp_path / "gs.csv").students)
    by_sid = {"users": [{"email": "ben.other@gmail.com", "sid": "1002", "name": "Ben"}]}
    assert _student_id(by_sid, ids) == ("ben@u.edu", "")
    stranger = {"users": [{"email": "eve@u.edu", "sid": "9", "name": "Ann Lee"}]}
    assert _student_id(stranger, ids)[0] == ""  # never matched by a name anyone can take


def test_run_autograder_puts_nothing_before_the_installed_package(tmp_path):
    """run_autograder runs ``python -I``: a gpsaccel/ in the working folder (the submission's
    side of the container) or on PYTHONPATH is not what runs."""
    import os
    import shlex
    import subprocess
    import sys

    from gpsaccel.assignments.gradescope import RUN_AUTOGRADER

    line = next(ln for ln in RUN_AUTOGRADER.splitlines() if ln.startswith("exec "))
    cmd = shlex.split(line)[1:]
    assert cmd[0] == "/autograder/venv/bin/python"
    cmd = [sys.executable, *cmd[1:-1], "--no-such-option"]  # main() exits at once on this
    fake = tmp_path / "gpsaccel"
    (fake / "assignments").mkdir(parents=True)
    marker = tmp_path / "ran"
    (fake / "__init__.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    (fake / "assignments" / "__init__.py").write_text("")
    (fake / "assignments" / "gradescope.py").write_text("")
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, timeout=120)
    assert not marker.exists()


def test_setup_fences_the_folders_no_box_may_read(tmp_path):
    """setup.sh runs :func:`fence` as root: the installed package's checks, answers, masters
    and solutions readable by their owner alone, so a basic box (another user) cannot read
    them where nothing else fences them; the rest of the package stays readable."""
    import shutil
    import stat

    import gpsaccel
    from gpsaccel.assignments.gradescope import SETUP_SH, fence
    from gpsaccel.check.problem import BOX_HIDES

    assert "python -I -m gpsaccel.assignments.gradescope --fence" in SETUP_SH
    pkg = tmp_path / "gpsaccel"
    src = Path(gpsaccel.__file__).parent
    for rel in ("kalman", "assignments/masters", "_lessons/masters", "check"):
        if (src / rel).is_dir():
            shutil.copytree(src / rel, pkg / rel, ignore=shutil.ignore_patterns("__pycache__"))
    for p in pkg.rglob("*"):
        p.chmod(p.stat().st_mode | 0o055)
    done = fence(pkg)
    assert {d.relative_to(pkg).as_posix() for d in done} == {
        rel for rel in BOX_HIDES if (pkg / rel).is_dir()} >= {"check", "assignments"}
    for p in pkg.rglob("*"):
        hidden = any(p.relative_to(pkg).as_posix().startswith(rel) for rel in BOX_HIDES)
        assert (stat.S_IMODE(p.stat().st_mode) & 0o077 == 0) == hidden, p


def test_the_module_refuses_an_option_and_a_root_without_the_zip_in_words(tmp_path, capsys):
    """`python -m gpsaccel.assignments.gradescope --help` (an instructor trying the zip) was a
    FileNotFoundError traceback for '--help/source/config.json'."""
    from gpsaccel.assignments.gradescope import main

    assert main(["--help"]) == 2
    assert "unexpected argument(s): --help" in capsys.readouterr().err
    assert main([str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path} has no source/config.json" in err and "gradescope.zip" in err
    assert not (tmp_path / "results").exists()
