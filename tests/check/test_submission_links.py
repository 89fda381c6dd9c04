"""What a submission is, against links and odd folders (issue 20): symbolic links at the top of a
class folder or inside a student's folder, hard links, a folder nested 1,100 deep or holding
thousands of entries: each is a finding for that submission, never a copy followed, never a
crash of the batch."""

from __future__ import annotations

import os
import shutil

import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel.classrun import PYTHON, check_many, walk


@pytest.fixture
def klass(tmp_path, hostile):
    """A class folder with alice (correct), and an instructor's folder beside it."""
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", folder / "alice.py")
    solutions = tmp_path / "instructor"
    solutions.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_covariance.py", solutions / "solution.py")
    (solutions / "solution.py").chmod(0o600)
    return folder, solutions


def test_top_level_links_of_a_class_folder_are_refused(klass):
    folder, solutions = klass
    (folder / "mallory.py").symlink_to(folder / "alice.py")  # a copy of alice's
    (folder / "trudy").symlink_to(solutions)  # the instructor's folder
    (folder / "dangling.py").symlink_to(folder / "nowhere.py")
    entries, _ = walk([folder], PYTHON)
    assert sorted(e.path.name for e in entries) == ["alice.py", "dangling.py", "mallory.py", "trudy"]
    results = check_many([folder], n_runs=2, executor=None, seed=1)
    by_name = {r["subject"]: r for r in results}
    assert by_name["alice.py"]["passed"]
    for name in ("mallory.py", "trudy", "dangling.py"):
        assert by_name[name]["codes"] == ["link-refused"], by_name[name]
        assert "link" in by_name[name]["findings"][0]["message"]


def test_links_inside_a_students_folder_are_refused(tmp_path, klass):
    folder, solutions = klass
    bob = folder / "bob"
    bob.mkdir()
    shutil.copy(folder / "alice.py", bob / "filter.py")
    (bob / "helpers.py").symlink_to(solutions / "solution.py")
    report = check.submission(bob, n_runs=2)
    assert report.codes == ["link-refused"], report
    with pytest.raises(sb.SubmissionError, match="helpers.py is a symbolic link"):
        sb.load_submission(bob, "kalman_filter")


def test_a_hard_link_is_refused_whoever_owns_it(klass):
    """A hard link to the instructor's 0600 solution would reach the box readable; ownership
    tells nothing (a class unpacked by the instructor is all the instructor's), and an archive
    or a repository never holds a hard link: any file with two names is refused."""
    folder, solutions = klass
    os.link(solutions / "solution.py", folder / "eve.py")
    report = check.submission(folder / "eve.py", n_runs=2)
    assert report.codes == ["link-refused"], report
    carol = folder / "carol"
    carol.mkdir()
    shutil.copy(folder / "alice.py", carol / "main.py")
    os.link(solutions / "solution.py", carol / "data.py")
    with pytest.raises(sb.SubmissionError, match="hard link") as e:
        sb.load_submission(carol, "kalman_filter")
    assert e.value.code == "link-refused"


def test_a_folder_too_deep_or_too_full_is_a_finding_not_a_crash(tmp_path, hostile):
    deep = tmp_path / "class" / "dave"
    deep.mkdir(parents=True)
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", deep / "filter.py")
    levels = [deep]
    for _ in range(1100):  # os.walk recursed once per level: RecursionError at ~1000
        levels.append(levels[-1] / "a")
        levels[-1].mkdir()
    wide = tmp_path / "class" / "frank"
    wide.mkdir()
    shutil.copy(hostile.SUBMISSIONS / "correct_gps_rate.py", wide / "filter.py")
    for i in range(sb.MAX_ENTRIES + 1):
        (wide / f".h{i}").mkdir()  # hidden, so never copied, but still walked
    results = check_many([tmp_path / "class"], n_runs=2, executor=None, seed=1)
    by_name = {r["subject"]: r for r in results}
    assert by_name["dave"]["codes"] == ["file-limit"], by_name["dave"]
    assert "nested more than" in by_name["dave"]["findings"][0]["message"]
    assert by_name["frank"]["codes"] == ["file-limit"], by_name["frank"]
    for d in reversed(levels[1:]):  # shutil.rmtree recurses too: removed level by level
        d.rmdir()
