"""check.submission on the fixtures in tests/submissions: correct variants pass, every catalogue
mutant is flagged with its code, broken submissions become findings (never an exception here).

Small ensembles (N_RUNS) keep this file within its time budget; the checker's decision does not
depend on N (P and x̂ are compared run by run), only the consistency statistics do.  So the
mutants, whose verdicts are those comparisons, and the broken files, whose findings are about
what one call does, are checked on MUTANT_RUNS = 2 runs, the mutants once each
for the module (:func:`mutant`), and share the catalogue's candidate filters
(:func:`keeping_answers`: 2 CPU s a check when computed again after each box).  The tests that
assert a consistency verdict keep an ensemble: the correct forms are "consistent" on the
checker's own default (wf.DEFAULT_RUNS = 10 runs, what a student's check uses; each test at a
family-wise false-alarm rate of 1 %, at fixed seeds), and report 003's "inconsistent", a
question of power, is shown on N_RUNS = 20.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel.check.problems import calibration as wf
from gpsaccel.cli import main

from ..conftest import keeping_answers
from ..heldout.confusion import named

pytestmark = pytest.mark.usefixtures("warm_boxes")  # conftest.py: the course's zygote

HERE = Path(__file__).parents[2] / "submissions"
N_RUNS = 20
MUTANT_RUNS = 2


def _check(name: str, seed: int = 0, **kw) -> check.Report:
    report = check.submission(HERE / name, n_runs=kw.pop("n_runs", N_RUNS), seed=seed, **kw)
    str(report)  # always printable
    json.dumps(report.to_dict())  # always serialisable
    return report


# ------------------------------------------------------------------------ correct variants
CORRECT = [
    ("correct_covariance.py", 0), ("correct_covariance.py", 7),
    ("correct_information.py", 1), ("correct_joseph.py", 2),
    ("correct_filterpy.py", 3), ("correct_gps_rate.py", 4), ("correct_gps_rate.py", 5),
    ("correct_gps_rate.py", 6),
]


@pytest.mark.parametrize("name, seed", CORRECT, ids=[f"{n[:-3]}-seed{s}" for n, s in CORRECT])
def test_correct_forms_pass(name, seed):
    report = _check(name, seed, n_runs=wf.DEFAULT_RUNS)
    assert report.passed, report
    assert report.details["max_dP_sigma"] < check.TOLERANCE / 100
    assert report.details["max_dx_sigma"] < check.TOLERANCE / 100
    # the consistency tests are informative only; at these fixed seeds they hold (each has a
    # family-wise false-alarm rate of 1 %)
    assert "consistent" in [f.code for f in report.findings], report


# ---------------------------------------------------------------------- catalogue mutants
MUTANTS = [
    ("mutant_phi_sign.py", ["phi-sign"]),
    ("mutant_process_noise_interval.py", ["process-noise-interval"]),
    ("mutant_m0_order.py", ["m0-order"]),
    ("mutant_std_as_variance.py", ["std-as-variance"]),
    ("mutant_missing_propagation.py", ["missing-propagation"]),
    ("mutant_mean_not_propagated.py", ["mean-not-propagated"]),
    ("mutant_x0_total_state.py", ["x0-total-state"]),
    ("mutant_returns_a_priori.py", ["returns-a-priori"]),
    ("mutant_first_update_skipped.py", ["first-update-skipped"]),
    ("mutant_predict_before_update.py", ["predict-before-first-update"]),
    ("mutant_w_value.py", ["w-value"]),
    ("mutant_phi_transposed.py", ["phi-transposed"]),
    ("mutant_q_without_gamma.py", ["q-without-gamma"]),
    ("mutant_two_mistakes.py", ["phi-sign", "x0-total-state"]),
    ("report003.py", ["process-noise-interval", "std-as-variance"]),
    ("mutant_residual_index.py", ["measurement-late"]),
    ("mutant_diagonal_q.py", ["p-mismatch"]),
]


def test_every_catalogue_code_has_a_mutant_here():
    covered = {c for _, codes in MUTANTS for c in codes}
    # issue 31's gaps: student-style mutants in tests/check/test_catalogue_gaps.py
    covered |= {"covariance-update-skipped", "update-every-step", "phi-sign", "state-order"}
    # issue 40's: students' filters of the held-out set (tests/check/heldout/calibration)
    covered |= named("calibration")
    assert set(check.codes()) <= covered, set(check.codes()) - covered


@pytest.fixture(scope="module")
def calibration():
    """The calibration problem, keeping the catalogue's candidates between the module's checks."""
    return keeping_answers("calibration")


@pytest.fixture(scope="module")
def mutant(calibration):
    """``mutant(name, n_runs)``: the report of mutant ``name`` at seed 3, checked once for the
    module."""
    problem = calibration
    reports: dict[tuple[str, int], check.Report] = {}

    def get(name: str, n_runs: int = MUTANT_RUNS) -> check.Report:
        if (name, n_runs) not in reports:
            reports[name, n_runs] = _check(name, seed=3, n_runs=n_runs, problem=problem)
        return reports[name, n_runs]

    return get


@pytest.mark.parametrize("name, codes", MUTANTS, ids=[n[:-3] for n, _ in MUTANTS])
def test_mutant_is_flagged_with_its_code(mutant, name, codes):
    report = mutant(name)
    assert not report.passed
    assert report.codes == codes, report
    for f in report.findings:
        if f.severity == "error":
            assert len(f.message) > 60  # a sentence a student can act on, not just a code


def test_report003_shows_both_variance_slips_and_what_they_do(mutant):
    report = mutant("report003.py", N_RUNS)
    variants = [m["variant"] for m in report.details["matched"]]
    assert "V₂₂ = 0.04, the δv measurement's variance" in variants
    assert "M0₁₁ = 10, δp's prior variance" in variants
    # its P is too small for its errors: the NEES test sees it even on 20 runs
    assert "inconsistent" in [f.code for f in report.findings]


def test_p_mismatch_says_where_p_first_differs(mutant):
    report = mutant("mutant_diagonal_q.py")
    msg = next(f.message for f in report.findings if f.code == "p-mismatch")
    assert "P at t = 0 is right" in msg and "propagation" in msg


# ----------------------------------------------------------------------------- broken files
BROKEN = [
    ("broken_raises.py", "exception", ["run 0", "ValueError", "line 8"]),
    ("broken_wrong_shape.py", "wrong-shape", ["(3, 151)", "transposed", "time last"]),
    ("broken_nan.py", "nan-output", ["t = 30 s"]),
    ("broken_import_error.py", "import-error", ["kalman_helpers"]),
    ("broken_no_function.py", "no-kalman-filter", ["my_kalman"]),
    ("broken_returns_one.py", "return-value", ["(151, 3)"]),
    ("broken_exits.py", "exception", ["SystemExit"]),
    ("does_not_exist.py", "not-found", []),
]


@pytest.mark.parametrize("name, code, words", BROKEN, ids=[n[:-3] for n, _, _ in BROKEN])
def test_broken_submission_becomes_a_finding(name, code, words):
    report = _check(name, timeout=20, n_runs=MUTANT_RUNS)  # what a call does: one run shows it
    assert not report.passed
    assert report.codes == [code], report
    msg = next(f.message for f in report.findings if f.code == code)
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("source, code, words", [
    ("def kalman_filter(z)\n    return z\n", "import-error", ["SyntaxError", "line 1"]),
    ("def kalman_filter(z):\n    return (r for r in z), [[1.0]]\n", "not-numeric", ["generator"]),
    ("def kalman_filter(z):\n    return [[1, 2], [3]], [[1.0]]\n", "not-numeric", ["x_hat"]),
    # no return statement: None is named None (it read "a builtins.NoneType")
    ("def kalman_filter(z):\n    x_hat = z\n", "return-value", ["on run 0 it returned None."]),
    ("def kalman_filter(z):\n    return 1.5\n", "return-value", ["it returned a builtins.float."]),
])
def test_files_written_on_the_fly(tmp_path, source, code, words):
    """Cases that cannot live in tests/submissions (a syntax error would break ruff there)."""
    path = tmp_path / "student.py"
    path.write_text(source)
    report = check.submission(path, n_runs=2)
    assert report.codes == [code], report
    msg = report.findings[0].message
    for w in words:
        assert w in msg, (w, msg)
    assert "_runner.py" not in msg and "<frozen" not in msg and "NoneType" not in msg


def test_a_p_that_is_no_covariance_is_flagged(calibration, tmp_path):
    path = tmp_path / "student.py"
    path.write_text("import numpy as np\n\ndef kalman_filter(z):\n"
                    "    P = np.tile(np.eye(3), (len(z), 1, 1))\n    P[:, 0, 1] = 5\n"
                    "    return np.zeros((len(z), 3)), P\n")
    report = check.submission(path, problem=calibration, n_runs=3)
    assert report.codes == ["p-mismatch"], report
    assert "P at t = 0 already differs" in report.findings[0].message
    assert "p-not-positive-definite" in [f.code for f in report.findings]


def test_endless_loop_is_stopped_at_the_time_limit():
    report = _check("broken_infinite_loop.py", timeout=3)
    assert report.codes == ["timeout"]
    assert "completed 0 of" in report.findings[0].message


def test_lists_are_converted_with_a_note():
    report = _check("correct_lists.py", n_runs=MUTANT_RUNS)  # passing: a run-by-run comparison
    assert report.passed, report
    assert "returns-list" in [f.code for f in report.findings if f.severity == "note"]


def test_prints_are_captured_truncated_and_warned_about():
    report = _check("correct_prints_a_lot.py", n_runs=MUTANT_RUNS)
    assert report.passed, report
    warning = next(f for f in report.findings if f.code == "prints-a-lot")
    assert warning.severity == "warning" and "GPS time 150" in warning.message
    assert len(str(report)) < 10_000


def test_assert_submission_for_grader_cells(calibration):
    assert check.assert_submission(HERE / "correct_gps_rate.py", n_runs=2).passed
    with pytest.raises(AssertionError, match="m0-order"):
        check.assert_submission(HERE / "mutant_m0_order.py", problem=calibration, n_runs=2)


def test_bad_arguments_of_the_caller_raise_value_error():
    with pytest.raises(ValueError, match="n_runs"):
        check.submission(HERE / "correct_gps_rate.py", n_runs=1)
    with pytest.raises(ValueError, match="timeout"):
        check.submission(HERE / "correct_gps_rate.py", timeout=0)


# ------------------------------------------------------------------------ instructor's side
def test_cli_check_table_and_json(tmp_path, capsys):
    for name in ("correct_gps_rate.py", "mutant_m0_order.py"):
        (tmp_path / name).write_text((HERE / name).read_text(encoding="utf-8"), encoding="utf-8")
    out = tmp_path / "results.json"
    rc = main(["check", str(tmp_path), "--runs", "2", "--workers", "2", "--json", str(out)])
    assert rc == 1  # one submission fails
    text = capsys.readouterr().out
    assert "m0-order" in text and "1 of 2 passed" in text
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["settings"]["runs"] == 2
    by_name = {r["subject"]: r for r in data["results"]}
    assert by_name["correct_gps_rate.py"]["passed"] is True
    assert by_name["mutant_m0_order.py"]["codes"] == ["m0-order"]


def test_the_answer_is_computed_only_after_the_box_is_empty(monkeypatch, hostile):
    events = []
    real_run, real_answer = sb.run, wf.with_answer

    def run(*args, **kwargs):
        assert wf._candidates.cache_info().currsize == 0  # no cached covariance either
        events.append("box starts")
        box = real_run(*args, **kwargs)
        events.append("box empty")
        return box

    def with_answer(data):
        events.append("answer")
        return real_answer(data)

    monkeypatch.setattr(sb, "run", run)
    monkeypatch.setattr(wf, "with_answer", with_answer)
    wf._candidates(wf._default_data(2, 0).model, 1)  # fill the cache
    report = check.submission(hostile.SUBMISSIONS / "mutant_m0_order.py", n_runs=2)
    assert report.codes == ["m0-order"]
    assert events == ["box starts", "box empty", "answer"]
