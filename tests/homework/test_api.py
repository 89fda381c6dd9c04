"""The public API of an instructor's own homework (gpsaccel.homework): what a graded.py builds
with it, the partial credit it gives, each argument checked with an error naming it."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

from gpsaccel import homework as hw
from gpsaccel import registry
from gpsaccel.assignments.linear import matrices
from gpsaccel.assignments.questions import Answer
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_model import LinearIngredients

DT, SA, SP = 0.1, 0.5, 3.0
I2, O2 = np.eye(2), np.zeros((2, 2))


def cv2d(sigma_a: float = SA, sigma_p: float = SP, **kw) -> hw.LinearModel:
    """The example's model (a 2-D constant-velocity target), built here from its equations."""
    return hw.LinearModel(Phi=np.block([[I2, DT * I2], [O2, I2]]),
                          Gamma=np.vstack([DT**2 / 2 * I2, DT * I2]), W=sigma_a**2 * I2,
                          H=np.hstack([I2, O2]), V=sigma_p**2 * I2,
                          M0=np.diag([100.0, 100.0, 1.0, 1.0]), x0=np.array([0, 0, 5.0, 2.0]),
                          every=10, n_epochs=31, dt=DT, states=("px", "py", "vx", "vy"),
                          measurements=("px", "py"), **kw)


def right(model: hw.LinearModel) -> dict[str, np.ndarray]:
    return {k: np.array(v) for k, v in matrices(LinearIngredients.correct(model)).items()}


def ok(*values: np.ndarray) -> Answer:
    return Answer("ok", values=tuple(np.asarray(v, dtype=float) for v in values))


POINTS = {"Phi": 1.0, "Gamma": 0.5, "Q": 1.0, "H": 0.5, "V": 0.5, "M0": 0.5}


def grade(question: hw.Question, given: dict, variant: dict | None = None):
    draw = hw.Draw(seed=1, variant=variant or {"sigma_a": SA, "sigma_p": SP})
    reads = question.reads(draw)
    answers = [ok(given[r.name]) if r.name in given else Answer("not-defined") for r in reads]
    report = question.grade(draw, answers)
    return question.score(report), report


# --------------------------------------------------------------------------- partial credit
def test_a_matrices_question_gives_each_matrix_its_points():
    q = hw.matrices_question("q1", lambda v: cv2d(**v), POINTS)
    assert q.points == 4.0 and dict(q.parts) == POINTS
    good = right(cv2d())
    assert grade(q, good)[0] == 4.0
    score, report = grade(q, {**good, "V": SP * I2})  # V given as σ: only V's half point lost
    assert score == 3.5 and report.codes == ["std-as-variance"]
    assert {f.part for f in report.findings if f.severity == "error"} == {"V"}
    score, report = grade(q, {**good, "V": SP * I2, "Phi": good["Phi"].T})
    assert score == 2.5 and set(report.codes) == {"std-as-variance", "phi-transposed"}
    # a matrix not defined, or of the wrong shape, costs that matrix only; the others are checked
    missing = {k: v for k, v in good.items() if k != "M0"}
    assert grade(q, missing) == (3.5, grade(q, missing)[1])
    assert grade(q, {**missing, "Q": good["Q"][:2]})[0] == 2.5
    # all or nothing when the instructor declares no parts
    whole = hw.matrices_question("q1", lambda v: cv2d(**v), 4)
    assert whole.parts == () and grade(whole, {**good, "V": SP * I2})[0] == 0.0


def test_credit_keeps_the_declared_fraction_of_a_part_with_a_recognised_slip():
    q = hw.matrices_question("q1", lambda v: cv2d(**v), POINTS, credit={"std-as-variance": 0.5})
    good = right(cv2d())
    assert grade(q, {**good, "V": SP * I2})[0] == 3.75          # 0.5 · 0.5 of V kept
    # a part with a slip and an error no credit covers keeps nothing
    both = {**good, "Q": 0.3 * good["Q"], "V": SP * I2}
    score, report = grade(q, both)
    assert report.codes == ["matrix-value", "std-as-variance"] and score == 4.0 - 1.0 - 0.25
    # a question without parts is one part
    whole = hw.Question("q", 2.0, credit={"std-as-variance": 0.25})
    rep = hw.Report("q")
    rep.add("std-as-variance", text="x", part="V")
    assert whole.score(rep) == 0.5
    rep.add("other", text="y")
    assert whole.score(rep) == 0.0


def test_parts_are_checked_and_an_error_of_the_whole_question_costs_it_all():
    q = hw.Question("q3", 2, parts={"x_bar": 1, "M": 1})
    assert q.parts == (("x_bar", 1.0), ("M", 1.0))
    rep = hw.Report("q3")
    rep.add("predict-mean", text="x", part="x_bar")
    assert q.score(rep) == 1.0
    rep.add("exception", text="y")                   # no part: the whole question
    assert q.score(rep) == 0.0
    with pytest.raises(ValueError, match="must add up to its 3 points"):
        hw.Question("q", 3, parts={"a": 1, "b": 1})
    with pytest.raises(ValueError, match="credit of q maps mistake codes to fractions"):
        hw.Question("q", 1, credit={"std-as-variance": 1.5})
    with pytest.raises(ValueError, match="points must give each of Phi, Gamma"):
        hw.matrices_question("q1", cv2d(), {"Phi": 1})
    with pytest.raises(ValueError, match="matrices must be distinct names among"):
        hw.matrices_question("q1", cv2d(), 1, matrices=("Phi", "R"))
    with pytest.raises(ValueError, match="model must be a LinearModel"):
        hw.matrices_question("q1", "cv2d", 1)  # type: ignore[arg-type]


def test_w_may_be_asked_instead_of_q():
    q = hw.matrices_question("q1", cv2d(), 1.5, matrices=("Gamma", "W", "V"))
    assert [r.name for r in q.reads(hw.Draw(0))] == ["Gamma", "W", "V"]
    good = right(cv2d())
    assert grade(q, good)[0] == 1.5
    score, report = grade(q, {**good, "W": SA * I2})
    assert score == 0.0 and report.codes == ["std-as-variance"]


# --------------------------------------------------------------------- the matrices catalogue
def test_q_without_gamma_is_recognised_for_a_noise_of_fewer_components_than_states():
    """Q = σ²I₄ for a 2×2 W = σ²I₂ on four states (the own homework's mistake, which only 1×1
    and n×n W were recognised for)."""
    model = cv2d()
    entries = [m for m in LinearCatalogue(model).covariance_mistakes()
               if m.code == "q-without-gamma"]
    (entry,) = entries
    assert entry.variant == "Q = W on [px, py] and on [vx, vy]"  # the problem's own names
    g = LinearIngredients.correct(model)
    for change in entry.changes:
        g = g.__class__(**{**vars(g), change[0]: change[1]})
    np.testing.assert_array_equal(matrices(g)["Q"], SA**2 * np.eye(4))
    good = right(model)
    report = hw.matrices_answer(model, {**good, "Q": SA**2 * np.eye(4)})
    assert report.codes == ["q-without-gamma"] and report.findings[0].part == "Q"
    # a W that does not divide the states has no such form: another code, never this one
    odd = hw.LinearModel(Phi=np.eye(3), Gamma=np.ones((3, 2)), W=np.eye(2), H=np.eye(3)[:1],
                         V=np.eye(1), M0=np.eye(3), x0=np.zeros(3), every=1, n_epochs=3)
    assert "q-without-gamma" not in {m.code for m in LinearCatalogue(odd).covariance_mistakes()}


def test_compare_names_the_elements_never_the_values():
    rep = hw.Report("q")
    want = np.array([[1.0, 0.1], [0.0, 1.0]])
    assert hw.compare(rep, "F", want.copy(), want)
    assert not hw.compare(rep, "F", np.array([[1.0, 0.2], [0.0, 1.0]]), want, part="F")
    f = rep.findings[-1]
    assert f.part == "F" and f.for_student().message.startswith("F: F₁₂ differs from the "
                                                                 "reference (wrong at 1 of 4")
    assert "0.1" not in f.for_student().message and "0.1" in f.for_instructor()
    assert not hw.compare(rep, "F", np.ones(3), want, part="F")   # the student's shape
    assert rep.findings[-1].code == "shape" and rep.findings[-1].part == "F"


# --------------------------------------------------------------------------- reads, variants
def test_reads_are_checked_when_the_graded_file_is_written():
    assert hw.variable("Phi", (4, 4)) == hw.Read("Phi", (), ((4, 4),), value=True)
    r = hw.function("predict", np.zeros(4), 3, returns=[(4,), (4, 4)])
    assert r.shapes == ((4,), (4, 4)) and r.args[1].dtype == float and r.args[1].shape == ()
    assert hw.function("f", returns=(2,)).shapes == ((2,),)
    with pytest.raises(ValueError, match="name must be a Python name"):
        hw.variable("my var", (1,))
    with pytest.raises(ValueError, match="returns must be a shape"):
        hw.function("f", returns="(2,)")  # type: ignore[arg-type]


def test_variants_never_give_the_public_point_and_say_how_often_students_share_one():
    v = hw.Variants({"a": (1, 2, 3), "b": (0.5, 1.5)}, {"a": 2, "b": 1.5})
    got = {tuple(v(n).values()) for n in range(5)}
    assert got == {(a, b) for a in (1, 2, 3) for b in (0.5, 1.5)} - {(2, 1.5)}
    assert v.size == 6 and v.shared_pairs(10) == pytest.approx(45 / 5)
    assert v(5) == v(0)
    with pytest.raises(ValueError, match="public must give every parameter of axes"):
        hw.Variants({"a": (1, 2)}, {"b": 1})
    with pytest.raises(ValueError, match="axes must map each parameter"):
        hw.Variants({"a": ()})
    with pytest.raises(ValueError, match="leaves no variant"):
        hw.Variants({"a": (1,)}, {"a": 1})


# ------------------------------------------------------------------------------- problems
def test_a_problem_from_a_file_and_its_model_for_a_variant(tmp_path):
    path = tmp_path / "mine.py"
    path.write_text("import numpy as np\nfrom gpsaccel import check\n"
                    "wind = check.Problem.linear('wind-test', Phi=np.eye(2), Gamma=np.eye(2), "
                    "W=np.eye(2), H=np.eye(2), V=np.eye(2), M0=np.eye(2), x0=np.zeros(2), "
                    "every=2, n_epochs=3, states=('wx', 'wy'), register=False)\n")
    name = hw.load_problem(path, "wind")
    assert name == "wind-test" and name in registry.problems()
    assert hw.load_problem(f"{path}:wind") == name
    m = hw.problem_model(name, V=4 * np.eye(2))
    assert m.states == ("wx", "wy") and m.V[0, 0] == 4 and m.every == 2
    assert hw.load_module(path).wind.name == name
    with pytest.raises(ValueError, match="defines no problem 'other'"):
        hw.load_problem(path, "other")
    with pytest.raises(ValueError, match="expected a Python file"):
        hw.load_problem(tmp_path / "mine.txt", "wind")
    with pytest.raises(ValueError, match="is not a linear problem of your own"):
        hw.problem_model("coop")
    with pytest.raises(ValueError, match="V must be"):
        hw.problem_model(name, V=np.eye(3))
    with pytest.raises(ValueError, match="problem must be one of"):
        hw.filter_question("q2", 4, "kalman_filter.py", "no-such-problem")
    with pytest.raises(ValueError, match="file must be the name of a .py file"):
        hw.filter_question("q2", 4, "../x.py", name)


def test_the_example_is_in_the_package_and_written_out_once(tmp_path):
    folder = hw.write_example(tmp_path)
    assert folder == tmp_path / "cv2d"
    assert sorted(p.name for p in folder.iterdir()) == ["cv2d.ipynb", "graded.py", "problems.py"]
    for p in folder.iterdir():
        assert p.read_bytes() == (hw.example() / p.name).read_bytes()
    with pytest.raises(ValueError, match="already exists"):
        hw.write_example(tmp_path)


def test_the_docstring_examples_run():
    result = doctest.testmod(hw, extraglobs={"hw": hw}, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0 and result.attempted >= 2


def test_the_docstring_examples_of_what_it_re_exports_run():
    import importlib

    for name in ("questions", "_answers", "linear"):  # assignments.questions is also a function
        module = importlib.import_module(f"gpsaccel.assignments.{name}")
        result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
        assert result.failed == 0 and result.attempted >= 1, module.__name__
