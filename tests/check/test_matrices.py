"""check.model_matrices: right matrices pass, each known mistake is named, bad input never raises."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel.calibration.mistakes import gamma, phi
from gpsaccel.kalman.update import epoch_transition

DT, T = 0.005, 0.2
RIGHT = dict(Phi=phi(DT), Gamma=gamma(DT), H=np.eye(2, 3), V=np.diag([1.0, 0.0016]), W=0.0004,
             M0=np.diag([100.0, 1.0, 0.01]))


def _with(**changes):
    return {**RIGHT, **changes}


def test_right_matrices_pass_in_several_forms():
    assert check.model_matrices(**RIGHT).passed
    as_lists = {k: np.asarray(v).tolist() for k, v in RIGHT.items()}
    as_lists["Gamma"] = [-DT**2 / 2, -DT, 0]          # a flat Γ is a column too
    as_lists["W"] = [[0.0004]]
    report = check.model_matrices(**as_lists, Q=gamma(DT) @ gamma(DT).T * 0.0004)
    assert report.passed, report
    assert report.codes == []


def test_gps_rate_matrices_pass_with_the_summed_process_noise():
    Qe = epoch_transition(phi(DT), gamma(DT) @ gamma(DT).T * 0.0004, 40)[1]
    np.testing.assert_allclose(phi(T), np.linalg.matrix_power(phi(DT), 40), atol=1e-15)
    report = check.model_matrices(Phi=phi(T), Q=Qe, dt=T)
    assert report.passed, report


@pytest.mark.parametrize("changes, code, words", [
    (dict(Phi=phi(DT, +1.0)), "phi-sign", ["Φ₁₃", "−Δt²/2", "-1.25e-05"]),
    (dict(Phi=np.array([[1, DT, DT**2 / 2], [0, 1, DT], [0, 0, 1]])), "phi-sign", ["Φ₂₃"]),
    (dict(Phi=phi(T)), "phi-interval", ["Δt = 0.2 s"]),
    (dict(Phi=np.array([[1, DT, -DT**2], [0, 1, -DT], [0, 0, 1]])), "phi-element",
     ["Φ₁₃ = -2.5e-05", "−Δt²/2 = -1.25e-05"]),
    (dict(Gamma=-gamma(DT)), "gamma-sign", ["does not change"]),
    (dict(Gamma=gamma(T)), "gamma-interval", ["0.2 s"]),
    (dict(H=np.array([[1.0, 0, 0], [0, 1, 1]])), "h-element", ["H₂₃ = 1, should be 0"]),
    (dict(V=np.diag([1.0, 0.04])), "std-as-variance", ["V₂₂ = 0.04", "0.0016"]),
    (dict(V=np.diag([1.0, 0.0016**2])), "std-as-variance", ["squared again"]),
    (dict(V=np.diag([1.0, 0.16])), "units", ["0.4"]),
    (dict(W=0.02), "std-as-variance", ["W = 0.02", "0.0004"]),
    (dict(W=0.0016), "w-value", ["report 001"]),
    (dict(M0=np.diag([1.0, 100.0, 0.01])), "m0-order", ["swapped"]),
    (dict(M0=np.diag([10.0, 1.0, 0.01])), "std-as-variance", ["M0₁₁ = 10", "100"]),
    (dict(M0=np.diag([100.0, 1.0, 0.1])), "std-as-variance", ["M0₃₃"]),
    (dict(M0=np.diag([100.0, 100.0, 0.01])), "m0-element", ["mean v̄0"]),
    (dict(Q=gamma(T) @ gamma(T).T * 0.0004), "process-noise-interval", ["Σ"]),
    (dict(dt=0.02), "dt", ["0.005 s"]),
])
def test_each_mistake_is_named(changes, code, words):
    report = check.model_matrices(**_with(**changes))
    assert not report.passed
    assert code in report.codes, report
    text = " ".join(f.for_instructor() for f in report.findings if f.code == code)
    for w in words:
        assert w in text, (w, text)


def test_report_003_gps_step_without_q_is_flagged():
    report = check.model_matrices(Phi=phi(T), Gamma=gamma(T), W=0.0004, dt=T)
    assert report.codes == ["process-noise-interval"], report


@pytest.mark.parametrize("changes, code", [
    (dict(Phi="not a matrix"), "not-a-matrix"),
    (dict(Phi=[[1, 2], [3, 4]]), "shape"),
    (dict(H=np.eye(3)), "shape"),
    (dict(V=[[1.0, np.nan], [0, 0.0016]]), "not-finite"),
    (dict(M0=[[100, 1, 0], [0, 1, 0], [0, 0, 0.01]]), "not-symmetric"),
    (dict(Phi=[[1, DT, None], [0, 1, -DT], [0, 0, 1]]), "not-finite"),
    (dict(Gamma=[[1, 2, 3]]), "shape"),
    (dict(dt="fast"), "dt"),
])
def test_bad_input_becomes_a_finding(changes, code):
    report = check.model_matrices(**_with(**changes))
    assert code in report.codes, report
    str(report)


def test_nothing_to_check():
    assert check.model_matrices().codes == ["nothing-to-check"]


def test_assert_model_matrices_raises_with_the_findings():
    assert check.assert_model_matrices(**RIGHT).passed
    with pytest.raises(AssertionError, match="phi-sign") as info:
        check.assert_model_matrices(**_with(Phi=phi(DT, +1.0), M0=np.diag([1.0, 100.0, 0.01])))
    assert "m0-order" in str(info.value)


def test_report_is_json_ready_and_readable():
    import json

    report = check.model_matrices(**_with(W=0.02))
    d = json.loads(json.dumps(report.to_dict()))
    assert d["passed"] is False and d["codes"] == ["std-as-variance"]
    assert str(report).startswith("model matrices: FAILED (std-as-variance)")
