"""The racetrack plan and the input that makes the noise-free ship follow it exactly."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.ship.plan import driving_input, nominal_plan


def test_designed_input_makes_the_plan_an_exact_solution(model):
    plan, u = nominal_plan(model), driving_input(model)
    assert u.shape == (999, 3)
    x = plan[0]
    for k in range(model.n_steps):
        x = model.Phi @ x + model.B @ u[k]
        np.testing.assert_allclose(x, plan[k + 1], atol=1e-9)
    # the racetrack: cruise at 1 m/s, two 180° left turns, back on the x axis heading east
    assert np.hypot(plan[200, 1], plan[200, 4]) == pytest.approx(1.0, abs=1e-9)
    assert plan[999, 6] == pytest.approx(2 * np.pi, abs=1e-9)
    assert plan[999, 3] == pytest.approx(0.0, abs=1e-9)
    assert u[200, 0] == pytest.approx(12 * 0.4462 * 1.0, rel=1e-9)  # thrust = m βx v at cruise
