"""The calibration homework's own checks: question 1 for the student's accelerometer rate,
question 3's NEES functions on fresh ensembles (the class is graded in test_grading.py)."""

from __future__ import annotations

import numpy as np
from scipy import stats

from gpsaccel.assignments.calibration import nees_answer, nees_data, nees_reference
from gpsaccel.assignments.grading import assignment_module
from gpsaccel.assignments.questions import Answer, Draw

graded = assignment_module("calibration")


def test_fresh_nees_data_is_a_consistent_ensemble():
    # N ε̄ ~ χ²(3N) for a consistent ensemble: inside the two-sided 99 % interval (fixed seed;
    # false-alarm rate 1 % per draw, 10 draws)
    rng = np.random.default_rng(5)
    inside = 0
    for _ in range(10):
        x, xh, P = nees_data(rng, 40)
        eps, _ = nees_reference(x, xh, P)
        lo, hi = stats.chi2.ppf([0.005, 0.995], 120) / 40
        inside += lo <= eps <= hi
    assert inside >= 9


def test_nees_answer_accepts_the_reference_and_names_each_mistake():
    x, xh, P = nees_data(np.random.default_rng(1), 30)
    N = 30
    eps, (lo, hi) = nees_reference(x, xh, P)
    assert nees_answer(eps, (lo, hi), N, x, xh, P).passed
    e = x[:, -1] - xh[:, -1]
    wrong = {
        "nees-sum": N * eps,
        "nees-not-inverted": float((e[:, None, :] @ P[:, -1] @ e[..., None]).mean()),
        "nees-per-state": eps / 3,
        "nees-value": eps * 1.01,
    }
    for code, value in wrong.items():
        assert nees_answer(value, (lo, hi), N, x, xh, P).codes == [code]
    one = tuple(stats.chi2.ppf([0.025, 0.975], 3))
    assert nees_answer(eps, one, N, x, xh, P).codes == ["nees-bounds-one-run"]
    assert nees_answer("abc", "x", N, x, xh, P).codes == ["not-a-number", "nees-bounds"]
    # a function without a return (the handed-out `...` body): None, never read as nan
    missing = nees_answer(None, None, N, x, xh, P)
    assert missing.codes == ["not-a-number", "nees-bounds"]
    assert "nees_30 is None" in str(missing) and "nan" not in str(missing)


def test_question_3_grades_the_functions_on_the_draws_data():
    draw = Draw(99)
    N, (x, xh, P) = graded._q3_draw(draw)
    eps, bounds = nees_reference(x, xh, P)
    ok = [Answer("ok", values=(np.array(eps),)), Answer("ok", values=(np.array(bounds),))]
    assert graded._q3_grade(draw, ok).passed
    summed = [Answer("ok", values=(np.array(N * eps),)), ok[1]]
    assert graded._q3_grade(draw, summed).codes == ["nees-sum"]
    assert graded._q3_grade(draw, [Answer("not-defined"), ok[1]]).codes == ["not-defined"]


def test_question_1_uses_the_students_rate():
    from gpsaccel.assignments.calibration import rate_model

    for rate in graded.RATES_HZ:  # Δt is the student's own; the 5 Hz GPS falls on a step of it
        m = rate_model(rate)
        assert m.dt == 1 / rate and m.gps_every * 5 == rate, rate  # exact: integers, one division
        # GPS interval gps_every·Δt: 0.2 s to two roundings (35 Hz: 7 · (1/35) = 0.19999999999999998)
        assert abs(m.gps_interval - 0.2) <= 2 * np.spacing(0.2), rate
    dt = 1 / 400
    Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
    given = [Phi, -np.array([[dt**2 / 2], [dt], [0.0]]), np.eye(2, 3), np.diag([1.0, 0.04**2]),
             np.array([[0.02**2]]), np.diag([100.0, 1.0, 0.01])]
    answers = [Answer("ok", values=(g,)) for g in given]
    assert graded._q1_grade(Draw(0, {"rate_hz": 400}), answers).passed
    assert not graded._q1_grade(Draw(0, {"rate_hz": 200}), answers).passed


def test_v_given_as_sigma_costs_v_s_half_point():
    """The rule the packaged homeworks share (docs/grading.md's table): a part per matrix, no
    slip keeps any of it; V with σ where σ² belongs is 2.5 / 3."""
    dt = 1 / 400
    Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
    given = [Phi, -np.array([[dt**2 / 2], [dt], [0.0]]), np.eye(2, 3), np.diag([1.0, 0.04]),
             np.array([[0.02**2]]), np.diag([100.0, 1.0, 0.01])]
    q1 = graded.graded_questions()[0]
    report = q1.grade(Draw(0, {"rate_hz": 400}), [Answer("ok", values=(g,)) for g in given])
    assert report.codes == ["std-as-variance"] and q1.score(report) == 2.5
