"""check.jacobians: right forms pass, each known slip is named with its cause."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.check.jacobians import check_states, jacobians
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


def test_caller_mistakes_raise():
    with pytest.raises(ValueError, match="at least one"):
        jacobians()


def test_assert_forms_for_graders():
    from gpsaccel import check

    assert check.assert_jacobians(A=jacobian_A).passed
    with pytest.raises(AssertionError, match="jacobian-B"):
        check.assert_jacobians(B=lambda x, u: M.dt * jacobian_B(x, u))
