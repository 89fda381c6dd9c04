"""The coop mistake catalogue: without a mistake it is the reference filter; each entry moves it."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.coop import filters, mistakes
from gpsaccel.coop.model import CoopModel

M = CoopModel(duration=30.0)
TRUTH = M.simulate(np.random.default_rng(3), 3)


def _dist(out, ref):
    sd = np.sqrt(np.diagonal(ref.P, axis1=-2, axis2=-1))
    dx = np.abs(mistakes.wrapped_difference(out.x_hat, ref.x_hat)) / sd
    dP = np.abs(out.P - ref.P) / (sd[..., :, None] * sd[..., None, :])
    return float(dx.max()), float(dP.max())


@pytest.mark.parametrize("kind", mistakes.KINDS)
def test_no_mistake_is_the_reference_filter(kind):
    ref = filters.run_batch(kind, M, TRUTH.y, M.Qtrue, M.Rtrue)
    dx, dP = _dist(mistakes.run(M, TRUTH.y, M.Qtrue, M.Rtrue, kind), ref)
    assert dx < 1e-10 and dP < 1e-12


@pytest.mark.parametrize("kind", mistakes.KINDS)
def test_every_mistake_changes_the_output_or_its_range(kind):
    ref = filters.run_batch(kind, M, TRUTH.y, M.Qtrue, M.Rtrue)
    for m in mistakes.catalogue(M, kind):
        if m.variant == "(I + K H) M (I + K H)ᵀ + K R Kᵀ":  # its P grows until S is singular
            with pytest.raises(np.linalg.LinAlgError):
                mistakes.run(M, TRUTH.y, M.Qtrue, M.Rtrue, kind, (m,))
            continue
        out = mistakes.run(M, TRUTH.y, M.Qtrue, M.Rtrue, kind, (m,))
        dx, dP = _dist(out, ref)
        if m.code == "no-state-wrap":
            assert dx < 1e-9 and mistakes.heading_range(out.x_hat) > np.pi + 1, m
        elif m.code == "p-not-symmetric":
            assert dx < 1e-9 and dP < 1e-12, m  # the same filter in exact arithmetic
        else:
            assert max(dx, dP) > 1e-2, (m, dx, dP)


def test_codes_of_each_kind():
    ekf_points = {m.variant for m in mistakes.catalogue(kind="ekf") if m.code == "jacobian-point"}
    lkf_points = {m.variant for m in mistakes.catalogue(kind="lkf") if m.code == "jacobian-point"}
    assert len(ekf_points) == 3 and lkf_points == {"LKF linearized about the estimate"}
    for code in ("no-angle-wrap", "no-state-wrap", "dt-linearization", "process-noise",
                 "std-as-variance", "epoch-shift", "p-not-symmetric"):
        assert code in mistakes.codes("lkf") and code in mistakes.codes("ekf")
