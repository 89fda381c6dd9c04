"""The example of an instructor's own homework, as shipped (gpsaccel/homework/example/cv2d):
written out by ``gpsaccel assignment --example``, its problem checked from its file, handed out and
graded with partial credit per declared part, its feedback in the problem's own names."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import nbformat
import numpy as np
import pytest

from gpsaccel import check
from gpsaccel import homework as hw
from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.linear import FINDINGS
from gpsaccel.check.report import Report
from gpsaccel.check.wording import STUDENT
from gpsaccel.cli import main


def _filter_file(course: Path, target: Path, edit: tuple[str, str] | None = None) -> Path:
    """The master's q2 solution as a student's file (with one edit)."""
    nb = nbformat.read(str(course / "cv2d.ipynb"), as_version=4)
    src = next(c.source for c in nb.cells if "%%writefile" in c.source)
    body = src.split("\n", 1)[1].replace("    # BEGIN SOLUTION\n", "").replace(
        "    # END SOLUTION", "")
    if edit:
        assert edit[0] in body
        body = body.replace(*edit)
    target.write_text(body)
    return target


def test_example_is_written_out_by_the_command_and_refuses_what_it_cannot_do(tmp_path, capsys):
    assert main(["assignment", "--example", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert f"gpsaccel assignment {tmp_path / 'cv2d'} --out hw/cv2d" in out
    assert sorted(p.name for p in (tmp_path / "cv2d").iterdir()) == [
        "cv2d.ipynb", "graded.py", "problems.py"]
    assert main(["assignment", "--example", str(tmp_path)]) == 2          # nothing replaced
    assert "already exists" in capsys.readouterr().err
    for extra in (["calibration"], ["--out", "x"], ["--no-run-tests"]):
        assert main(["assignment", "--example", str(tmp_path / "new"), *extra]) == 2
        assert "does nothing else: leave out" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()
    assert main(["assignment"]) == 2 and "give the homework NAME" in capsys.readouterr().err
    assert main(["assignment", "calibration"]) == 2 and "--out" in capsys.readouterr().err


def test_the_examples_problem_is_checked_from_its_file(tmp_path, capsys):
    course = hw.write_example(tmp_path)
    good = _filter_file(course, tmp_path / "good.py")
    bad = _filter_file(course, tmp_path / "bad.py", ("3.0**2 * I2", "3.0 * I2"))
    spec = f"{course / 'problems.py'}:cv2d"
    assert main(["check", str(good), str(bad), "--problem", spec, "--runs", "3",
                 "--seed", "1"]) == 1
    out = capsys.readouterr().out
    verdict = {ln.split()[0].rsplit("/", 1)[-1]: ln.split()[1] for ln in out.splitlines()
               if ".py " in ln}
    assert verdict == {"good.py": "yes", "bad.py": "NO"}, out
    assert "std-as-variance" in out and "problem cv2d" in out
    assert main(["check", str(good), "--problem", f"{course / 'problems.py'}:other"]) == 2
    assert "defines no problem 'other'" in capsys.readouterr().err
    assert main(["check", str(good), "--problem", spec, "--dask", "dask-local"]) == 2
    assert "--dask" in capsys.readouterr().err


# ------------------------------------------------------------ the instructor's own names
#: Words of report 000's problem (the calibration): never in an own problem's feedback.
REPORT_000 = re.compile(r"accelerometer|report 00|δp|δv|\bbias\b|\bGPS\b|a \+ b|a − b")


def test_an_own_problems_feedback_speaks_its_own_names_never_report_000s():
    """A wind model of the instructor's: every catalogue entry, as the student reads it, and the
    wording of every code its check can give, name its states and never the accelerometer."""
    states = ("wind_x", "wind_y", "drift_x", "drift_y")
    I2, O2 = np.eye(2), np.zeros((2, 2))
    wind = check.Problem.linear(
        "wind-own-names", Phi=np.block([[I2, 0.5 * I2], [O2, I2]]),
        Gamma=np.vstack([O2, 0.5 * I2]), W=0.01 * I2, H=np.hstack([I2, O2]), V=0.3 * I2,
        M0=np.diag([4.0, 4.0, 0.5, 0.5]), x0=np.zeros(4), every=4, n_epochs=11, dt=0.5,
        states=states, measurements=("wind_x", "wind_y"), register=False)
    signs = []
    for m in wind.catalogue().catalogue():
        report = Report("wind")
        mistake_finding(report, m, "kalman_filter: ")
        text = report.findings[-1].for_student().message
        assert not REPORT_000.search(text), (m, text)
        if m.code == "phi-sign":
            signs.append(text)
    assert signs and all(re.search(r"how (drift_x|drift_y) enters (wind_x|wind_y)", t)
                         for t in signs), signs
    for code in set(wind.codes()) | set(FINDINGS) | {"matrix-value", "q-without-gamma"}:
        assert not REPORT_000.search(STUDENT.get(code.split(".")[0], "")), code
    # the matrices question of such a problem too
    model = wind.model
    good = {"Phi": model.Phi, "Gamma": model.Gamma, "Q": model.Gamma @ model.W @ model.Gamma.T,
            "H": model.H, "V": model.V, "M0": model.M0}
    for name, wrong in (("Phi", np.where(model.Phi == 0.5, -0.5, model.Phi)),
                        ("Q", 0.01 * np.eye(4)), ("V", np.sqrt(model.V)), ("H", model.H.T.T * 2)):
        report = hw.matrices_answer(model, {**good, name: wrong})
        assert not report.passed
        assert not REPORT_000.search(str(report)), str(report)


# --------------------------------------------------------------------- handed out, graded
def _rows(path: Path) -> dict[str, list[str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return {r[0]: r for r in csv.reader(f)}


#: Each student's notebook: the solution with one edit (old, new) in its code cells.
CLASS = {
    "ann": [],
    "ben": [('V = VARIANT["sigma_p"] ** 2 * I2', 'V = VARIANT["sigma_p"] * I2')],  # σ for σ²
    "cy": [('Q = Gamma @ Gamma.T * VARIANT["sigma_a"] ** 2',                        # Q = σ²I₄
            'Q = VARIANT["sigma_a"] ** 2 * np.eye(4)')],
    "dee": [("    for _ in range(10):\n        x_bar, M = Phi @ x_bar, Phi @ M @ Phi.T + Q\n",
             "    F = np.linalg.matrix_power(Phi, 10)\n    x_bar, M = F @ x_bar, F @ M @ F.T + Q\n")],
    "eve": [("H, V = np.hstack([I2, O2]), 3.0**2 * I2", "H, V = np.hstack([I2, O2]), 3.0 * I2")],
    "fay": [("def predict(x, P, Phi, Q):", "def predict_later(x, P, Phi, Q):")],
}

#: What each gets: partial credit per declared part (q1: Φ 1, Γ ½, Q 1, H ½, V ½, M0 ½, σ for σ²
#: keeping half its matrix; q2 all or nothing; q3 a point per output).
SCORES = {"ann": (4, 4, 2), "ben": (3.75, 4, 2), "cy": (3, 4, 2), "dee": (4, 4, 1),
          "eve": (4, 0, 2), "fay": (4, 4, 0)}
CODES = {"ben": {"q1": ["std-as-variance"]}, "cy": {"q1": ["q-without-gamma"]},
         "dee": {"q3": ["process-noise-interval"]}, "eve": {"q2": ["std-as-variance"]},
         "fay": {"q3": ["not-defined"]}}


@pytest.mark.slow
def test_the_example_is_handed_out_and_graded_with_partial_credit(tmp_path, capsys, monkeypatch):
    """From the example alone: otter assign with the solution's tests run, per-student variants,
    grading in the sandbox, each mistake costing its own part, the exports."""
    monkeypatch.chdir(tmp_path)
    hw.write_example(tmp_path / "course")
    (tmp_path / "secret").write_text("s" * 40)
    (tmp_path / "roster.csv").write_text("id,name,email\n" + "".join(
        f"{who},{who.title()} Lee,{who}@u.edu\n" for who in CLASS))
    assert main(["assignment", "course/cv2d", "--out", "hw", "--roster", "roster.csv",
                 "--secret-file", "secret"]) == 0      # the master's solution passes its tests
    capsys.readouterr()
    ann = tmp_path / "hw" / "students" / "ann"
    assert (ann / "problems.py").is_file()  # what grader.check needs, beside the notebook
    text = (ann / "cv2d.ipynb").read_text()
    assert "'sigma_a'" in text and "BEGIN SOLUTION" not in text and "def predict(" in text
    assert "VARIANT = {'sigma_a': 0.5, 'sigma_p': 3.0}" not in text  # never the public numbers
    solution = nbformat.read(str(tmp_path / "hw" / "autograder" / "cv2d.ipynb"), as_version=4)
    for who, edits in CLASS.items():
        nb = nbformat.from_dict(solution)
        for old, new in edits:
            (cell,) = [c for c in nb.cells if c.cell_type == "code" and old in c.source]
            cell.source = cell.source.replace(old, new)
        (tmp_path / "class" / who).mkdir(parents=True)
        nbformat.write(nb, str(tmp_path / "class" / who / "cv2d.ipynb"))
    assert main(["grade", "class", "--assignment", "course/cv2d", "--secret-file", "secret",
                 "--roster", "roster.csv", "--seed", "3"]) == 0
    grades = tmp_path / "class-grades"
    rows = _rows(grades / "grades.csv")
    total = rows["student"].index("total")
    record = {g["id"]: g for g in json.loads((grades / "grades.json").read_text())}
    for who, (q1, q2, q3) in SCORES.items():
        g = record[who]
        feedback = (grades / "feedback" / f"{who}.txt").read_text()
        assert (g["scores"], g["status"]) == ({"q1": q1, "q2": q2, "q3": q3}, "graded"), (
            who, feedback)
        assert {q: c for q, c in g["codes"].items() if c} == CODES.get(who, {}), who
        assert float(rows[who][total]) == q1 + q2 + q3
    moodle = _rows(grades / "moodle.csv")
    assert moodle["Ben"][-1] == "9.75"
    # the feedback names the mistake in the problem's words, never the student's right V
    ben = (grades / "feedback" / "ben.txt").read_text()
    sigma_p = float(re.search(r"sigma_p = ([\d.]+)", ben).group(1))
    assert "std-as-variance" in ben and "q1: 3.75 / 4" in ben
    assert f"{sigma_p**2:g}" not in ben.split("q1:")[1]
    assert "q-without-gamma" in (grades / "feedback" / "cy.txt").read_text()


def test_one_notebook_graded_with_the_public_numbers_gives_the_docs_feedback(tmp_path):
    """docs/grading.md quotes this feedback: V given as σ costs half of V's half point."""
    from gpsaccel.assignments.grading import grade_notebook
    from gpsaccel.assignments.homework import use_folder

    name = use_folder(hw.write_example(tmp_path / "course"))
    nb = nbformat.read(str(tmp_path / "course" / "cv2d" / "cv2d.ipynb"), as_version=4)
    cells = []
    for c in nb.cells:  # the master as an honest student hands it in: solutions in, otter out
        if c.cell_type == "code" and not c.source.lstrip().startswith("def test_"):
            c.source = "\n".join(ln.replace("  # SOLUTION", "") for ln in c.source.splitlines()
                                 if ln.strip() not in ("# BEGIN SOLUTION", "# END SOLUTION"))
            c.source = c.source.replace('V = VARIANT["sigma_p"] ** 2 * I2',
                                        'V = VARIANT["sigma_p"] * I2')
            cells.append(c)
        elif c.cell_type == "markdown":
            cells.append(c)
    nb.cells = cells
    nbformat.write(nb, str(tmp_path / "ben.ipynb"))
    g = grade_notebook(tmp_path / "ben.ipynb", name, "ben", seed=1)
    assert g.scores == {"q1": 3.75, "q2": 4.0, "q3": 2.0}, g.feedback
    block = g.feedback.split("\n\nq1: ")[1].split("\n\n")[0]
    docs = (Path(__file__).resolve().parents[2] / "docs" / "grading.md").read_text()
    for line in ("q1: " + block).splitlines():
        assert line in docs, line
