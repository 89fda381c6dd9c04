"""One gain sequence applied to a whole ensemble (kalman.gain_sequence)."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.kalman.gain_sequence import apply_gains
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.simulation import simulate_ensemble
from gpsaccel.ship.zeroed_gain import run_zeroed_gain


@pytest.fixture(scope="module")
def model():
    return ShipModel()


def test_gain_sequence_reproduces_the_filters_run_by_run(model):
    ens = simulate_ensemble(model, 3, np.random.default_rng(5))
    sched = model.schedule(multirate=True)
    z = ens.measurements(sched)
    for run_filter in (lambda zz: run_multirate(model, zz, schedule=sched, u=ens.u),
                       lambda zz: run_zeroed_gain(model, zz, schedule=sched, u=ens.u,
                                                  covariance="report")):
        first = run_filter(z[0])
        est = apply_gains(model.Phi, model.H, model.x0, sched, first.K, z, B=model.B, u=ens.u)
        for r in range(3):
            np.testing.assert_allclose(est.x_hat[r], run_filter(z[r]).x_hat, atol=1e-9)
