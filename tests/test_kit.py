"""The instructor's kit (issue 28): the masters in the package and hidden from a box, the roster,
the gradebook exports, the similarity report (an instructor's own homework: tests/homework/)."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import nbformat
import pytest

from gpsaccel import registry
from gpsaccel.assignments.generate import ASSIGNMENTS_ENV, master_notebook, packaged_masters
from gpsaccel.assignments.grading import Grade
from gpsaccel.assignments.roster import Student, read_roster
from gpsaccel.classrun.classwide import write_gradebooks
from gpsaccel.cli import main

ROOT = Path(__file__).resolve().parents[1]


def solved(name: str) -> nbformat.NotebookNode:
    """An honest student's notebook of homework ``name`` (the homework tests' own maker)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_homework_conftest_kit",
                                                  ROOT / "tests" / "assignments" / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.solved(name)


# ------------------------------------------------------------------ masters in the package
@pytest.mark.parametrize("name", registry.assignments())
def test_every_homework_master_is_in_the_package_under_a_folder_the_box_never_sees(name):
    from gpsaccel.assignments.notebook import BOX_HIDES
    from gpsaccel.sandbox import PACKAGE_DIR

    folder = packaged_masters() / name
    assert (folder / f"{name}.ipynb").is_file() and (folder / "graded.py").is_file()
    assert master_notebook(name) == folder / f"{name}.ipynb"
    hidden = [PACKAGE_DIR / rel for rel in BOX_HIDES]
    assert any(folder.is_relative_to(h) for h in hidden), (folder, hidden)


def test_every_solution_and_graded_file_the_package_ships_is_hidden_from_a_box():
    """Every notebook in the package that holds solutions (otter's SOLUTION markers) and every
    graded.py (hidden checks) sits under a folder the box never sees: a redteam student's box
    walked the site-packages and read homework/example/cv2d/graded.py, which an instructor who
    grades the example homework uses as it ships."""
    from gpsaccel.assignments.notebook import BOX_HIDES
    from gpsaccel.sandbox import PACKAGE_DIR

    hidden = [PACKAGE_DIR / rel for rel in BOX_HIDES]
    secret = [p for p in PACKAGE_DIR.rglob("*")
              if p.is_file() and (p.name == "graded.py" or (
                  p.suffix == ".ipynb" and "SOLUTION" in p.read_text(encoding="utf-8")))]
    assert any(p.name == "graded.py" for p in secret)  # the walk finds what it looks for
    exposed = [p for p in secret if not any(p.is_relative_to(h) for h in hidden)]
    assert exposed == [], exposed


def test_the_override_folder_replaces_the_packaged_masters(tmp_path, monkeypatch):
    shutil.copytree(packaged_masters() / "ship", tmp_path / "ship")
    monkeypatch.setenv(ASSIGNMENTS_ENV, str(tmp_path))
    assert master_notebook("ship") == tmp_path / "ship" / "ship.ipynb"
    with pytest.raises(FileNotFoundError, match="GPSACCEL_ASSIGNMENTS"):
        master_notebook("coop")


# ------------------------------------------------------------------ a flag never ignored
def test_assignment_refuses_a_flag_it_cannot_honour(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("GPSACCEL_GRADING_SECRET", raising=False)
    (tmp_path / "secret").write_text("x" * 32)
    (tmp_path / "roster.txt").write_text("alice\n")
    out = str(tmp_path / "out")
    assert main(["assignment", "ship", "--out", out, "--secret-file",
                 str(tmp_path / "secret")]) == 2
    assert "--secret-file" in capsys.readouterr().err
    assert main(["assignment", "ship", "--out", out, "--roster",
                 str(tmp_path / "roster.txt")]) == 2
    err = capsys.readouterr().err
    assert "--roster" in err and "secret" in err
    assert main(["assignment", "ship", "--out", out, "--roster", str(tmp_path / "none.txt"),
                 "--secret-file", str(tmp_path / "secret")]) == 2
    assert "roster" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # refused before otter assign wrote anything


def test_a_folder_that_is_not_a_homework_is_refused(tmp_path, capsys):
    (tmp_path / "hw").mkdir()
    (tmp_path / "hw" / "hw.ipynb").write_text("{}")
    assert main(["assignment", str(tmp_path / "hw"), "--out", str(tmp_path / "o")]) == 2
    assert "graded.py" in capsys.readouterr().err


# ------------------------------------------------------------------ roster
def test_roster_plain_and_csv(tmp_path):
    plain = tmp_path / "r.txt"
    plain.write_text("Doe, Jane (1001)\n\n# a comment\nbob\n", encoding="utf-8")
    assert [s.id for s in read_roster(plain)] == ["Doe, Jane (1001)", "bob"]
    rich = tmp_path / "r.csv"
    rich.write_text("id,name,email,sis_id,Section\nJane Doe,Jane Doe,jd@u.edu,1001,A\n"
                    "bob,,bob@u.edu,,\n", encoding="utf-8")
    jane, bob = read_roster(rich)
    assert (jane.email, jane.sis_id, jane.section, jane.split_name) == \
        ("jd@u.edu", "1001", "A", ("Jane", "Doe"))
    assert bob.full_name == "bob"
    (tmp_path / "bad.csv").write_text("id,mail\nx,y\n")
    with pytest.raises(ValueError, match="unknown column.*mail"):
        read_roster(tmp_path / "bad.csv")
    (tmp_path / "dup.txt").write_text("a\nb\na\n")
    with pytest.raises(ValueError, match="'a' twice"):
        read_roster(tmp_path / "dup.txt")


# ------------------------------------------------------------------ gradebook exports
def _rows(path: Path) -> list[list[str]]:
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.reader(f))


def test_gradebook_exports_map_ids_through_the_roster(tmp_path):
    possible = {"q1": 4.0, "q2": 6.0}
    grades = [Grade("jane-folder", "a.ipynb", {"q1": 4.0, "q2": 2.5}, possible, "graded"),
              Grade("bob", "b.ipynb", {"q1": 0.0, "q2": 0.0}, possible, "grader-error"),
              Grade("=stranger", "c.ipynb", {"q1": 1.0, "q2": 0.0}, possible, "graded")]
    roster = [Student("jane-folder", first_name="Jane", last_name="Doe", email="jd@u.edu",
                      sis_id="1001", login_id="jdoe", canvas_id="555", section="A"),
              Student("bob", name="Bob Ray", email="b@u.edu"),
              Student("absent", name="Al Sent", email="al@u.edu", sis_id="1003")]
    missing = write_gradebooks(grades, possible, roster, "Homework 1", tmp_path)
    assert missing == ["=stranger"]  # graded, not on the roster: named, not written
    canvas = _rows(tmp_path / "canvas.csv")
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", "Homework 1"]
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][-1] == "10"
    assert canvas[2] == ["Jane Doe", "555", "1001", "jdoe", "A", "6.5"]
    assert canvas[3][-1] == "" and canvas[4][-1] == ""  # rerun / not handed in: left empty
    moodle = _rows(tmp_path / "moodle.csv")
    assert moodle[0] == ["First name", "Last name", "ID number", "Email address", "Homework 1"]
    assert moodle[1] == ["Jane", "Doe", "1001", "jd@u.edu", "6.5"]
    people = _rows(tmp_path / "gradescope-roster.csv")
    assert people[0] == ["First Name", "Last Name", "Email", "SID", "Section"]
    assert people[2] == ["Bob", "Ray", "b@u.edu", "bob", ""]
    scores = _rows(tmp_path / "gradescope-scores.csv")
    assert scores[0][:5] == ["First Name", "Last Name", "SID", "Email", "Total Score"]
    assert scores[0][-2:] == ["q1 (4.0 pts)", "q2 (6.0 pts)"]
    assert scores[1][-2:] == ["4", "2.5"] and scores[3][6] == "missing"
    text = "".join(p.read_text() for p in tmp_path.glob("*.csv"))
    assert "stranger" not in text


# ------------------------------------------------------------------ similarity
# (tests/assignments/test_similarity.py: the report against a hostile class)


# ------------------------------------------------------------------ variants
def test_pick_covers_the_grid_except_the_public_point():
    from gpsaccel.assignments.variants import pick

    axes = {"a": (1, 2, 3), "b": (0.5, 1.5)}
    got = [tuple(pick(n, axes, {"a": 2, "b": 1.5}).values()) for n in range(5)]
    assert sorted(got) == sorted({(a, b) for a in (1, 2, 3) for b in (0.5, 1.5)} - {(2, 1.5)})
    assert pick(7, axes, {"a": 9, "b": 0.5}) == pick(1, axes, {"a": 9, "b": 0.5})  # off-grid


#: Largest number of pairs sharing a variant among 200 students that the test accepts, for the
#: expected n(n-1)/2/|space| (Poisson): P(X > bound) < 1e-3 for each (one fixed secret: the
#: figures are deterministic; the bound says what a fair draw gives).
SHARED_BOUND = {"calibration": (9.96, 21), "ship": (1.66, 7), "tracker": (0.113, 2)}


@pytest.mark.parametrize("name", sorted(SHARED_BOUND))
def test_a_class_of_200_hardly_shares_a_variant_and_nobody_gets_the_public_one(name):
    from collections import Counter

    from gpsaccel.assignments.grading import assignment_module, student_variant
    from gpsaccel.assignments.variants import expected_shared_pairs, size

    mod = assignment_module(name)
    axes = {"calibration": ("RATES_HZ",), "ship": ("MASSES_KG", "GPS_RATES_HZ"),
            "tracker": ("RATES_HZ", "SIGMAS_A", "SIGMAS_P")}[name]
    points = size({a: getattr(mod, a) for a in axes}) - 1  # the public point is never given
    expected, bound = SHARED_BOUND[name]
    assert expected_shared_pairs(200, points) == pytest.approx(expected, rel=1e-2)
    secret = b"fixed-secret-for-the-variant-test"
    got = Counter(tuple(sorted(student_variant(name, f"s{i:03d}", secret).items()))
                  for i in range(200))
    assert tuple(sorted(mod.DEFAULT_VARIANT.items())) not in got
    assert sum(n * (n - 1) // 2 for n in got.values()) <= bound
    first8 = [student_variant(name, f"s{i:03d}", secret) for i in range(8)]
    assert len({tuple(sorted(v.items())) for v in first8}) == 8


# ------------------------------------------------------------------ Gradescope stand-in
#: Ship question 1 answered honestly (6 points): what the honest submission hands in.
_HONEST_UPDATE = """import numpy as np
def update(x_bar, M, z, H, V):
    rows = np.flatnonzero(~np.isnan(z))
    if rows.size == 0:
        return x_bar.copy(), M.copy()
    Hr, Vr = H[rows], V[np.ix_(rows, rows)]
    K = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)
    A = np.eye(len(x_bar)) - K @ Hr
    return x_bar + K @ (z[rows] - Hr @ x_bar), A @ M @ A.T + K @ Vr @ K.T
"""

#: Forging notebooks: each answers nothing honestly and tries to get marks another way.
_FORGERS = {
    "patch otter and gpsaccel": """
import os, glob
try:
    import otter
    otter.Notebook.check = lambda self, *a, **k: None
except Exception:
    pass
import gpsaccel
for f in glob.glob(os.path.join(os.path.dirname(gpsaccel.__file__), "**", "*.py"), recursive=True):
    try:
        with open(f, "a") as h:
            h.write("\\nraise SystemExit('forged')\\n")
    except OSError:
        pass
update = lambda *a: None
""",
    "forge results": """
import json, os
forged = {"score": 1000, "tests": [{"name": "q1", "score": 6, "max_score": 6},
                                   {"name": "q2", "score": 4, "max_score": 4}]}
for d in ("{root}/results", "/autograder/results", "results", "."):
    try:
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, "results.json"), "w") as f:
            json.dump(forged, f)
    except OSError:
        pass
""",
    "read the tests": """
import glob, os
found = ""
for pattern in ("{root}/source/*", "{root}/source/homework/*/*", "/autograder/source/*"):
    for f in glob.glob(pattern):
        try:
            found += open(f, errors="replace").read()
        except OSError:
            pass
if "assignment" in found or "graded_questions" in found:
    exec(compile('''HONEST''', "stolen", "exec"))
""",
}


def _standin(tmp_path: Path, zip_path: Path, cell: str, email: str) -> Path:
    """Gradescope's layout under a temporary root: the zip unpacked into source/, the notebook
    in submission/, the metadata, an empty results/."""
    import json
    import zipfile

    root = tmp_path / "autograder"
    with zipfile.ZipFile(zip_path) as z:
        z.extractall(root / "source")
    (root / "submission").mkdir()
    (root / "results").mkdir()
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(cell.replace("{root}", str(root)))]
    nbformat.write(nb, str(root / "submission" / "ship.ipynb"))
    (root / "submission_metadata.json").write_text(json.dumps(
        {"users": [{"email": email, "id": 1, "name": "A Student"}]}))
    (root / "source").chmod(0o700)  # what setup.sh does (chmod -R go-rwx /autograder/source)
    return root


def _backends() -> list[str]:
    from gpsaccel.sandbox import basic_is_safe, resolve_backend

    out = ["bwrap"] if resolve_backend("auto") == "bwrap" else []
    return out + (["basic"] if basic_is_safe() else [])  # basic: as root, the box user


@pytest.mark.slow
@pytest.mark.parametrize("backend", _backends())
def test_gradescope_standin_honest_marks_and_no_forged_marks(tmp_path, backend):
    import json
    import zipfile

    from gpsaccel.assignments.gradescope import build, run

    secret = b"gradescope-standin-secret-0123456789"
    roster = [Student("Ann", email="ann@u.edu"), Student("Ben", email="ben@u.edu", sis_id="7")]
    zip_path = build("ship", tmp_path, roster, secret)
    names = zipfile.ZipFile(zip_path).namelist()
    assert {"setup.sh", "run_autograder", "config.json", "secret"} <= set(names)
    assert any(n.startswith("gpsaccel-") and n.endswith(".whl") for n in names)
    cases = {"honest": _HONEST_UPDATE, **{k: v.replace("HONEST", _HONEST_UPDATE)
                                          for k, v in _FORGERS.items()}}
    scores = {}
    for i, (case, cell) in enumerate(cases.items()):
        root = _standin(tmp_path / str(i), zip_path, cell, "ann@u.edu")
        run(root, sandbox=backend)
        written = json.loads((root / "results" / "results.json").read_text())
        scores[case] = {t["name"]: t["score"] for t in written["tests"]}
        assert written["score"] == sum(scores[case].values())
        assert "expected" not in written["output"].lower() or case != "honest"
    assert scores["honest"] == {"q1": 6.0, "q2": 0.0}, scores
    for case in _FORGERS:
        assert scores[case] == {"q1": 0.0, "q2": 0.0}, (case, scores[case])
    # an account not on the roster is not graded on someone else's variant
    root = _standin(tmp_path / "stranger", zip_path, _HONEST_UPDATE, "eve@u.edu")
    assert run(root, sandbox=backend)["score"] == 0.0
