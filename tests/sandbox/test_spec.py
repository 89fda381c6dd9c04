"""The sandbox's interface (gpsaccel.sandbox.spec): limits, declared outputs and calls refuse
what they cannot honour when they are made, not when a box runs."""

from __future__ import annotations

import pytest

from gpsaccel import sandbox as sb


def test_limits_outputs_and_calls_check_their_arguments():
    with pytest.raises(ValueError, match="limits.memory"):
        sb.Limits(memory=1 << 20)
    with pytest.raises(ValueError, match="limits.time"):
        sb.Limits(time=float("inf"))
    with pytest.raises(ValueError, match="limits.processes"):
        sb.Limits(processes=0)
    with pytest.raises(ValueError, match="dtype"):
        sb.Output("x", (3,), "object")
    with pytest.raises(ValueError, match="shape"):
        sb.Output("x", (-1,))
    with pytest.raises(ValueError, match="function"):
        sb.Call("not a name", (), (sb.Output("x", (1,)),))
    with pytest.raises(ValueError, match="sandbox must be one of"):
        sb.resolve_backend("docker")
