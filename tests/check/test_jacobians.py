"""check.jacobians: right forms pass, each known slip is named with its cause; the student
reads what their element does, the instructor the derivative that is right."""

from __future__ import annotations

import re

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


#: (the student's Jacobians, the code, what the student reads, what only the instructor reads: the
#: derivative that is right, which is the answer)
SLIPS = [
    (dict(A=_edit(jacobian_A, ((0, 2), lambda a, x, u: -a))), "jacobian-A",
     ["A₁₃", "sign is wrong: check the sign of each derivative"], ["−vg·sin θg", "∂cos θ/∂θ = −sin θ"]),
    (dict(A=lambda x, u: np.eye(6) + 0.1 * jacobian_A(x, u)), "jacobian-A",
     ["identity plus ΔT = 0.1 s", "∂f/∂x"], ["F = I + ΔT·A"]),
    (dict(A=lambda x, u: 0.1 * jacobian_A(x, u)), "jacobian-A", ["multiplied by ΔT"],
     ["ΔT·A"]),
    (dict(B=lambda x, u: 0.1 * jacobian_B(x, u)), "jacobian-B", ["multiplied by ΔT"],
     ["G = ΔT·B"]),
    (dict(B=_edit(jacobian_B, ((2, 1), lambda b, x, u: u[0] / 0.5))), "jacobian-B",
     ["B₃₂", "steering angle φg", "derivative of tan φg"], ["sec²", "vg / (L·cos² φg)"]),
    (dict(C=_edit(jacobian_C, ((0, 2), lambda c, x: 0.0))), "jacobian-C",
     ["C₁₃", "missing", "so it depends on θ"], ["∂γ/∂θ = −1"]),
    (dict(C=_edit(jacobian_C, ((2, 5), lambda c, x: 1.0))), "jacobian-C",
     ["C₃₆", "sign is wrong", "how does γ change when θ grows"], ["∂γ/∂θ = −1"]),
    (dict(C=_edit(jacobian_C, ((0, [0, 1, 3, 4]), lambda c, x: -c))), "jacobian-C",
     ["C₁₁", "atan2(Δη, Δξ) through Δξ = ξa − ξg", "chain rule"], ["∂atan2", "Δη/ρ²"]),
    (dict(C=_edit(jacobian_C, ((1, [0, 1, 3, 4]), lambda c, x: -c))), "jacobian-C",
     ["C₂₁", "ρ depends on the two positions"], ["∂ρ/∂ξa = +Δξ/ρ", "−Δξ/ρ"]),
    (dict(C=_fd_C(wrap=False)), "jacobian-C", ["±π", "wrapped h"], []),
    (dict(C=lambda x: jacobian_C(x).T), "shape", ["transposed"], []),
    (dict(A=lambda x, u: 1 / 0), "exception", ["ZeroDivisionError"], []),
    (dict(A=np.zeros((6, 6))), "not-callable", ["A(x, u)"], []),
]


@pytest.mark.parametrize("kwargs, code, student, instructor", SLIPS)
def test_each_slip_is_named_and_the_student_reads_no_derivative(kwargs, code, student,
                                                               instructor):
    report = jacobians(**kwargs)
    assert code in report.codes, report
    text = " ".join(f.for_student().message for f in report.findings)  # unwrapped
    full = " ".join(f.for_instructor() for f in report.findings)
    for w in student:
        assert w in text and w in full, (w, text)
    for w in instructor:  # the right derivative or form: the instructor's, never the student's
        assert w in full and w not in text, (w, text)
    assert not DERIVATIVE.search(text), text


#: A derivative stated with its value (∂γ/∂θ = −1, ∂ρ/∂ξa = +Δξ/ρ): an answer of question 1.
DERIVATIVE = re.compile(r"∂[^=;:]{1,30}/∂\S{1,12}\s*=(?!=)")


def test_the_derivative_rule_sees_what_it_must():
    for leak in ("∂γ/∂θ = −1", "∂ρ/∂ξa = +Δξ/ρ", "∂(vg tan φg / L)/∂φg = vg / (L cos² φg)",
                 "∂atan2(Δη, Δξ)/∂Δξ = −Δη/ρ²"):
        assert DERIVATIVE.search(leak), leak
    for fine in ("A = ∂f/∂x", "B is the continuous-time Jacobian ∂f/∂u of ẋ = f(x, u)",
                 "C = ∂h/∂x, with Δξ = ξa − ξg"):
        assert not DERIVATIVE.search(fine), fine


def test_caller_mistakes_raise():
    with pytest.raises(ValueError, match="at least one"):
        jacobians()


def test_assert_forms_for_graders():
    from gpsaccel import check

    assert check.assert_jacobians(A=jacobian_A).passed
    with pytest.raises(AssertionError, match="jacobian-B"):
        check.assert_jacobians(B=lambda x, u: M.dt * jacobian_B(x, u))
