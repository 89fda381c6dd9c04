"""check.dt_model: the right DT linearization passes (as functions or as matrices at one state),
each known slip is named, and the student reads what they did, not the right form."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.check.dt_model import dt_model
from gpsaccel.coop.model import CoopModel, jacobian_A, jacobian_B, jacobian_C

M = CoopModel()


def test_right_forms_pass():
    F = lambda x, u: np.eye(6) + M.dt * jacobian_A(x, u)  # noqa: E731
    from scipy.linalg import expm
    report = dt_model(F=lambda x, u: expm(M.dt * jacobian_A(x, u)),
                      G=lambda x, u: M.dt * jacobian_B(x, u), H=jacobian_C)
    assert report.passed, report
    at_x0 = dt_model(F=F(M.x0, M.u0), G=M.dt * jacobian_B(M.x0, M.u0), H=jacobian_C(M.x0),
                     Omega=np.eye(6), Q=M.Qtrue)
    assert at_x0.passed, at_x0


@pytest.mark.parametrize("kwargs, code, words", [
    (dict(F=jacobian_A), "dt-linearization", ["F = A"]),
    (dict(F=lambda x, u: M.dt * jacobian_A(x, u)), "dt-linearization", ["identity"]),
    (dict(F=lambda x, u: np.eye(6) + jacobian_A(x, u)), "dt-linearization", ["ΔT = 0.1 s is"]),
    (dict(G=jacobian_B), "dt-linearization", ["G = B"]),
    (dict(H=lambda x: M.dt * jacobian_C(x)), "dt-linearization", ["H = C"]),
    (dict(Omega=M.dt * np.eye(6)), "omega-dt-gamma", ["Ω = I"]),
    (dict(Q=M.dt * M.Qtrue), "omega-dt-gamma", ["ΔT·Qtrue"]),
    (dict(Q=M.dt**2 * M.Qtrue), "omega-dt-gamma", ["ΔT²"]),
])
def test_each_dt_slip_is_named(kwargs, code, words):
    report = dt_model(**kwargs)
    assert report.codes == [code], report
    for w in words:  # the instructor reads the right form too; the student what they did
        assert w in report.instructor_text(), (w, report.instructor_text())
    assert "H = C" not in str(report) and "Ω = I" not in str(report)


def test_caller_mistakes_raise():
    with pytest.raises(ValueError, match="at least one"):
        dt_model()
    with pytest.raises(ValueError, match="x must be"):
        dt_model(F=np.eye(6), x=np.zeros(5))


def test_assert_forms_for_graders():
    from gpsaccel import check

    assert check.assert_dt_model(H=jacobian_C).passed
    with pytest.raises(AssertionError, match="dt-linearization"):
        check.assert_dt_model(F=jacobian_A)
