"""A class handed per-student variants is never graded without the secret (issue 43's closing
note): the hand-out's own notebooks (:func:`gpsaccel.assignments.generate.personalize`) graded
with no secret are refused before any box starts, through ``gpsaccel grade`` and the Python
API, naming ``--secret-file`` and how many notebooks declare a variant; ``--no-variants`` grades
them on the public numbers all the same.  The notebooks are the students': one who deletes or
forges the marker changes nothing of the class (the run is faked: no notebook runs)."""

from __future__ import annotations

import json

import nbformat
import pytest

from gpsaccel.assignments.generate import personalize, student_package_dir
from gpsaccel.assignments.grading import declares_variant
from gpsaccel.classrun import grade, grade_class, running
from gpsaccel.classrun.grading import DECLARING
from gpsaccel.cli import main

from .test_grading import _fake_run

SECRET = b"variants-test-secret-0123456789abcdef"
IDS = ["ana", "ben", "cleo", "dev"]


def _handout():
    return student_package_dir() / "calibration" / "calibration.ipynb"


@pytest.fixture(autouse=True)
def _no_secret_in_env(monkeypatch):
    monkeypatch.delenv("GPSACCEL_GRADING_SECRET", raising=False)


def _class(tmp_path, variants: bool = True):
    """The class as handed out (``sub/<id>/calibration.ipynb``): each student's own variant,
    or the one public notebook for all."""
    sub = tmp_path / "export"
    if variants:
        personalize("calibration", _handout(), IDS, SECRET, sub)
    else:
        for sid in IDS:
            (sub / sid).mkdir(parents=True)
            (sub / sid / "calibration.ipynb").write_bytes(_handout().read_bytes())
    return sub


def _set_variant(path, text):
    """The student's notebook with its variant cell's assignment replaced by ``text``."""
    nb = nbformat.read(str(path), as_version=4)
    cell = next(c for c in nb.cells if c.source.lstrip().lower().startswith("# your variant"))
    cell.source = "\n".join([ln for ln in cell.source.splitlines() if ln.startswith("#")]
                            + ([text] if text else []))
    nbformat.write(nb, str(path))


def _faked(monkeypatch) -> list:
    seen: list = []
    monkeypatch.setattr(running, "run", _fake_run(seen))
    return seen


def test_a_personalized_notebook_declares_its_variant_and_the_public_one_does_not(tmp_path):
    sub = _class(tmp_path)
    assert [declares_variant(sub / s / "calibration.ipynb", "calibration") for s in IDS] == \
        [True] * 4
    assert declares_variant(_handout(), "calibration") is False
    bad = tmp_path / "deep.ipynb"
    bad.write_text("[" * 100_000 + "]" * 100_000)  # json's recursion: read in the child only
    assert declares_variant(bad, "calibration") is None


def test_grading_the_handed_out_class_without_the_secret_is_refused_before_any_box(
        tmp_path, monkeypatch):
    sub, seen = _class(tmp_path), _faked(monkeypatch)
    with pytest.raises(ValueError, match=r"--secret-file.*4 of the 4 notebooks declare a variant"
                       r".*--no-variants") as err:
        grade(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    assert "no_variants=True" in str(err.value)
    assert seen == [] and not (tmp_path / "out").exists()
    # with the secret they were handed out with, the class is graded
    grades = grade(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False,
                   secret=SECRET)
    assert sorted(g.student for g in grades) == IDS


def test_the_command_exits_2_naming_the_flag_and_the_count(tmp_path, monkeypatch, capsys):
    sub, seen = _class(tmp_path), _faked(monkeypatch)
    argv = ["grade", str(sub), "--assignment", "calibration", "--out", str(tmp_path / "out"),
            "--seed", "1", "--no-similarity"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("gpsaccel grade: error: secret_file (--secret-file): 4 of the 4 "
                          "notebooks declare a variant of their own")
    assert "--no-variants" in err and seen == []
    # --no-variants: graded on the public numbers, and grading.json says so
    assert main([*argv, "--no-variants"]) == 0
    assert len(seen) == 4
    info = json.loads((tmp_path / "out" / "grading.json").read_text())
    assert info["variants"].startswith("none (--no-variants")
    # a secret and --no-variants contradict each other
    secret = tmp_path / "secret"
    secret.write_bytes(SECRET)
    secret.chmod(0o600)
    assert main([*argv, "--no-variants", "--secret-file", str(secret), "--regrade"]) == 2
    assert "--no-variants" in capsys.readouterr().err.splitlines()[-1]


@pytest.mark.parametrize("forged", ["", 'VARIANT = {"rate_hz": 200}', "VARIANT = 'mine'"])
def test_a_student_who_deletes_the_marker_changes_nothing(tmp_path, monkeypatch, forged):
    """Deleted, set to the public numbers, or not a dict: that notebook declares nothing, and
    the others still tell the class was handed variants."""
    sub, seen = _class(tmp_path), _faked(monkeypatch)
    _set_variant(sub / "ben" / "calibration.ipynb", forged)
    with pytest.raises(ValueError, match=r"3 of the 4 notebooks declare"):
        grade(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False)
    assert seen == []


def test_a_student_who_adds_a_marker_cannot_stop_a_class_without_variants(tmp_path,
                                                                          monkeypatch):
    """One forged variant (below DECLARING), then two of four (not more than half): the class is
    graded, and the terminal's lines say how many declared one."""
    assert DECLARING == 2
    sub, seen = _class(tmp_path, variants=False), _faked(monkeypatch)
    for k, sid in enumerate(("ana", "ben")):
        _set_variant(sub / sid / "calibration.ipynb", 'VARIANT = {"rate_hz": 35}')
        graded = grade_class(sub, "calibration", out=tmp_path / f"out{k}", seed=1,
                             similarity=False)
        assert sorted(g.student for g in graded.grades) == IDS
        assert len(seen) == 4 * (k + 1)
        assert [ln for ln in graded.classwide if ln.startswith("variants:")] == [
            f"variants: {k + 1} of the 4 notebooks declare numbers of their own, too few to "
            f"tell a class handed variants (at least 2 and more than half); all graded on the "
            f"public notebook's numbers (handed out with variants? grade again with "
            f"--secret-file)"]
    _set_variant(sub / "cleo" / "calibration.ipynb", 'VARIANT = {"rate_hz": 35}')
    with pytest.raises(ValueError, match=r"3 of the 4 notebooks declare"):
        grade(sub, "calibration", out=tmp_path / "out2", seed=1, similarity=False)


def test_the_instructors_record_of_variants_refuses_a_rerun_without_the_secret(tmp_path,
                                                                                monkeypatch):
    """Every marker deleted (a class whose notebooks say nothing), but the earlier run in the
    same output graded with the secret: regrading one student without it is refused."""
    sub, seen = _class(tmp_path), _faked(monkeypatch)
    grade(sub, "calibration", out=tmp_path / "out", seed=1, similarity=False, secret=SECRET)
    for sid in IDS:
        _set_variant(sub / sid / "calibration.ipynb", "")
    with pytest.raises(ValueError, match=r"the earlier run in .*out graded per-student "
                                         r"variants \(its grading.json\), and no secret"):
        grade(sub, "calibration", out=tmp_path / "out", student="ben", similarity=False)
    assert len(seen) == 4


def test_homework_without_variants_reads_no_notebook(tmp_path, monkeypatch):
    calls: list = []
    monkeypatch.setattr("gpsaccel.assignments.grading.declares_variant",
                        lambda *a: calls.append(a))
    sub = tmp_path / "export"
    (sub / "ana").mkdir(parents=True)
    (sub / "ana" / "coop.ipynb").write_text("{}")
    _faked(monkeypatch)
    grade(sub, "coop", out=tmp_path / "out", seed=1, similarity=False)
    assert calls == []
