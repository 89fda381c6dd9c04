"""What every student can read (gpsaccel.assignments.published) and the instructor's private copy
of a packaged homework (``gpsaccel assignment NAME --copy DIR``)."""

from __future__ import annotations

import json
from pathlib import Path

import nbformat
import pytest

from gpsaccel.assignments import answercode, fingerprint, published, similarity
from gpsaccel.assignments.generate import master_notebook, student_package_dir
from gpsaccel.assignments.notebook import transform
from gpsaccel.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_every_published_solution_is_a_reference():
    asked = similarity.questions_asked("calibration")
    refs = published.references("calibration", master_notebook("calibration"), asked)
    labels = [r.label for r in refs]
    assert labels[:3] == [f"the published solution of calibration {q}" for q in asked]
    for name in ("calibration", "coop", "ship", "tracker"):
        assert f"homework {name} (master with solutions, published)" in labels
    assert "the example homework cv2d (master with solutions, published)" in labels
    lessons = sorted(p.stem for p in (ROOT / "lessons" / "solutions").glob("*.ipynb"))
    assert [lb.split()[1] for lb in labels if lb.startswith("lesson ")] == lessons
    assert all(r.prints for r in refs)


@pytest.mark.parametrize("name", ["calibration", "tracker"])
def test_the_handout_is_the_packaged_student_notebook(name):
    """The hand-out derived from the master (otter's rules) covers the student notebook the
    package ships: every fingerprint of what a student was given is boilerplate."""
    asked = similarity.questions_asked(name)
    bp = published.boilerplate(master_notebook(name), asked)
    nb = nbformat.read(str(student_package_dir() / name / f"{name}.ipynb"), as_version=4)
    sources = [c.source for c in nb.cells if c.cell_type == "code"]
    rec = answercode.record([(i, transform(s)) for i, s in enumerate(sources, 1)],
                            answercode.written_files(sources), asked)
    for q, a in rec["questions"].items():
        given = fingerprint.kgrams(answercode.unpack(a["tokens"]))
        assert given <= bp[q], (q, len(given - bp[q]))


def test_copy_refuses_what_it_cannot_do(tmp_path, capsys):
    assert main(["assignment", "calibration", "--copy", str(tmp_path / "calibration")]) == 2
    assert "name of a homework of the package" in capsys.readouterr().err
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "x").write_text("")
    assert main(["assignment", "calibration", "--copy", str(tmp_path / "full")]) == 2
    assert "not an empty folder" in capsys.readouterr().err
    assert main(["assignment", "calibration", "--copy", str(tmp_path / "a b")]) == 2
    assert "letters, digits" in capsys.readouterr().err
    assert main(["assignment", "calibration", "--copy", str(tmp_path / "c1"), "--out",
                 str(tmp_path / "o")]) == 2
    assert "--out" in capsys.readouterr().err and not (tmp_path / "c1").exists()
    assert main(["assignment", "calibration"]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["grade", str(tmp_path), "--assignment", "calibration", "--no-similarity",
                 "--compare-with", str(tmp_path)]) == 2
    assert "--compare-with" in capsys.readouterr().err


@pytest.mark.slow
def test_a_private_copy_is_handed_out_and_graded_as_a_folder_of_ones_own(tmp_path, capsys,
                                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["assignment", "calibration", "--copy", "private/calib26"]) == 0
    out = capsys.readouterr().out
    assert "keep this folder private" in out and "gpsaccel assignment" in out
    copied = tmp_path / "private" / "calib26"
    assert sorted(p.name for p in copied.iterdir()) == ["calib26.ipynb", "graded.py",
                                                         "requirements.txt"]
    config = json.loads((copied / "calib26.ipynb").read_text())["cells"][0]["source"]
    assert "name: calib26\n" in config
    # the package's own hand-out says its solutions are public; the copy's does not
    assert main(["assignment", "calibration", "--out", "hw0", "--no-run-tests"]) == 0
    assert "public:    the solutions of calibration are in every install" in \
        capsys.readouterr().out
    assert main(["assignment", "private/calib26", "--out", "hw", "--no-run-tests"]) == 0
    assert "public:" not in capsys.readouterr().out
    assert (tmp_path / "hw" / "student" / "calib26.ipynb").is_file()
    # graded as a folder of one's own; the unchanged copy's solution is the published one
    (tmp_path / "class" / "ann").mkdir(parents=True)
    solved = nbformat.read(str(tmp_path / "hw" / "autograder" / "calib26.ipynb"), as_version=4)
    nbformat.write(solved, str(tmp_path / "class" / "ann" / "calib26.ipynb"))
    assert main(["grade", "class", "--assignment", "private/calib26", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert "10 / 10  graded" in out
    assert "q2: ann matches the published solution of calibration" in out \
        or "q2: ann matches homework calibration (master with solutions, published)" in out, out
