"""check.jacobians and check.dt_model: right forms pass, each known slip is named with its cause."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.check.jacobians import check_states, dt_model, jacobians
from gpsaccel.coop.model import CoopModel, h, jacobian_A, jacobian_B, jacobian_C, wrap_measurement

M = CoopModel()


def _fd_C(wrap: bool):
    def C(x):
        out = np.empty((5, 6))
        for j in range(6):
            d = np.zeros(6)
            d[j] = 1e-6
            diff = h(x + d) - h(x - d)
            out[:, j] = (wrap_measurement(diff) if wrap else diff) / 2e-6
        return out
    return C


def _edit(fn, *edits):
    def f(*args):
        out = np.array(fn(*args), dtype=float)
        for idx, g in edits:
            out[idx] = g(out[idx], *args)
        return out
    return f


def test_states_include_the_hard_places():
    X, labels = check_states(M)
    bearing = wrap_measurement(h(X))
    assert np.isclose(np.abs(bearing[:, 0]), np.pi, atol=1e-6).any()
    assert np.isclose(np.abs(bearing[:, 2]), np.pi, atol=1e-6).any()
    assert np.isclose(np.abs(X[:, 2]), np.pi, atol=1e-6).any()
    assert (h(X)[:, 1] < 0.02).any()
    assert len(labels) == len(X)


def test_right_forms_pass():
    assert jacobians(A=jacobian_A, B=jacobian_B, C=jacobian_C).passed
    as_lists = jacobians(A=lambda x, u: jacobian_A(x, u).tolist(), C=_fd_C(wrap=True))
    assert as_lists.passed, as_lists
    F = lambda x, u: np.eye(6) + M.dt * jacobian_A(x, u)  # noqa: E731
    from scipy.linalg import expm
    report = dt_model(F=lambda x, u: expm(M.dt * jacobian_A(x, u)),
                      G=lambda x, u: M.dt * jacobian_B(x, u), H=jacobian_C)
    assert report.passed, report
    at_x0 = dt_model(F=F(M.x0, M.u0), G=M.dt * jacobian_B(M.x0, M.u0), H=jacobian_C(M.x0),
                     Omega=np.eye(6), Q=M.Qtrue)
    assert at_x0.passed, at_x0


@pytest.mark.parametrize("kwargs, code, words", [
    (dict(A=_edit(jacobian_A, ((0, 2), lambda a, x, u: -a))), "jacobian-A", ["A₁₃", "sign"]),
    (dict(A=lambda x, u: np.eye(6) + 0.1 * jacobian_A(x, u)), "jacobian-A", ["I + ΔT·A"]),
    (dict(B=_edit(jacobian_B, ((2, 1), lambda b, x, u: u[0] / 0.5))), "jacobian-B",
     ["B₃₂", "sec²"]),
    (dict(C=_edit(jacobian_C, ((0, 2), lambda c, x: 0.0))), "jacobian-C", ["C₁₃", "∂γ/∂θ = −1"]),
    (dict(C=_edit(jacobian_C, ((2, 5), lambda c, x: 1.0))), "jacobian-C", ["C₃₆", "sign is wrong"]),
    (dict(C=_edit(jacobian_C, ((0, [0, 1, 3, 4]), lambda c, x: -c))), "jacobian-C",
     ["∂atan2", "C₁₁"]),
    (dict(C=_fd_C(wrap=False)), "jacobian-C", ["±π", "wrapped h"]),
    (dict(C=lambda x: jacobian_C(x).T), "shape", ["transposed"]),
    (dict(A=lambda x, u: 1 / 0), "exception", ["ZeroDivisionError"]),
    (dict(A=np.zeros((6, 6))), "not-callable", ["A(x, u)"]),
])
def test_each_slip_is_named(kwargs, code, words):
    report = jacobians(**kwargs)
    assert code in report.codes, report
    text = str(report)
    for w in words:
        assert w in text, (w, text)


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
        jacobians()
    with pytest.raises(ValueError, match="x must be"):
        dt_model(F=np.eye(6), x=np.zeros(5))


def test_assert_forms_for_graders():
    from gpsaccel import check

    assert check.assert_jacobians(A=jacobian_A).passed
    assert check.assert_dt_model(H=jacobian_C).passed
    with pytest.raises(AssertionError, match="jacobian-B"):
        check.assert_jacobians(B=lambda x, u: M.dt * jacobian_B(x, u))
    with pytest.raises(AssertionError, match="dt-linearization"):
        check.assert_dt_model(F=jacobian_A)
