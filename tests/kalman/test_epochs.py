"""kalman.epochs against filterpy, the oracle: the epoch recursion of any linear model equals a
filterpy KalmanFilter that predicts every step and updates at the epochs; each skip and output
switch equals the same filterpy loop with that step left out."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from gpsaccel.kalman.epochs import batch_gains
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_model import LinearIngredients, LinearModel

MODEL = LinearModel(Phi=[[1.0, 0.1], [0.0, 1.0]], Gamma=[[0.005], [0.1]], W=[[0.09]],
                    H=[[1.0, 0.0]], V=[[4.0]], M0=np.diag([25.0, 4.0]), x0=[0.0, 1.0],
                    every=5, n_epochs=12, dt=0.1)


def _filterpy(z: np.ndarray, skip_first=False, skip_last=False, prior=False,
              predict_first=False):
    """x̂ (or x̄) and P (or M) at the epochs, by filterpy; skip_*: True (no update) or
    "covariance" (the mean updated, P left at M); predict_first: predict before every update,
    the first included."""
    kf = KalmanFilter(dim_x=2, dim_z=1)
    kf.F, kf.Q, kf.H, kf.R = MODEL.Phi, MODEL.Gamma @ MODEL.W @ MODEL.Gamma.T, MODEL.H, MODEL.V
    kf.x, kf.P = MODEL.x0.reshape(2, 1).copy(), MODEL.M0.copy()
    xs, Ps = [], []
    for i in range(MODEL.n_epochs):
        if i or predict_first:
            for _ in range(MODEL.every):
                kf.predict()
        x_bar, M = kf.x.copy(), kf.P.copy()
        how = skip_first if i == 0 else skip_last if i == MODEL.n_epochs - 1 else False
        if how is not True:
            kf.update(z[i])
            if how == "covariance":
                kf.P = M
        xs.append((x_bar if prior else kf.x)[:, 0].copy())
        Ps.append((M if prior else kf.P).copy())
    return np.array(xs), np.array(Ps)


@pytest.fixture(scope="module")
def z():
    return MODEL.simulate(np.random.default_rng(11), 3)[0]


@pytest.mark.parametrize("switch", [{}, {"skip_first": True}, {"skip_first": "covariance"},
                                    {"skip_last": True}, {"skip_last": "covariance"},
                                    {"output": "prior"}, {"predict_first": True},
                                    {"predict_first": True, "output": "prior"}])
def test_the_epoch_filter_is_filterpy_stepping(z, switch):
    flt = LinearIngredients.correct(MODEL)
    x, P = replace(flt, **switch).epoch_filter().apply(z)
    kw = {k: v for k, v in switch.items() if k != "output"}
    for r in range(z.shape[0]):
        xf, Pf = _filterpy(z[r], prior=switch.get("output") == "prior", **kw)
        sd = np.sqrt(np.diagonal(Pf, axis1=1, axis2=2))
        assert np.max(np.abs(x[r] - xf) / sd) < 1e-9
        assert np.max(np.abs(P - Pf) / (sd[:, :, None] * sd[:, None, :])) < 1e-9


def test_many_candidates_at_once_equal_each_alone():
    cat = LinearCatalogue(MODEL)
    filters = [cat.build()] + [cat.build((m,)) for m in cat.covariance_mistakes()]
    K, M, P = batch_gains(filters)
    for c, f in enumerate(filters):
        K1, M1, P1 = batch_gains([f])
        assert np.array_equal(P[c], P1[0]) and np.array_equal(K[c], K1[0])


def test_every_generic_mistake_changes_the_output():
    """A catalogue entry that changed nothing could never be told from the right filter."""
    cat = LinearCatalogue(MODEL)
    z = MODEL.simulate(np.random.default_rng(2), 2)[0]
    x_ref, P_ref = cat.build().apply(z)
    for m in cat.catalogue():
        x, P = cat.build((m,)).apply(z)
        assert np.abs(P - P_ref).max() > 1e-6 or np.abs(x - x_ref).max() > 1e-6, m
