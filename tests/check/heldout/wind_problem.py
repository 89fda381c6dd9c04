"""An instructor's own problem for the held-out set: a glider's along-track position p, airspeed
va and a slowly drifting wind w (ground speed va + w), 10 Hz propagation, a GPS position and a
pitot airspeed at 1 Hz for 60 s."""

from __future__ import annotations

import numpy as np

from gpsaccel import check

DT, EVERY, N_EPOCHS = 0.1, 10, 61
SIGMA_A, SIGMA_W = 0.2, 0.05       # m/s² (airspeed changes), m/s/√step-ish (wind drift)


def model(dt: float = DT) -> dict:
    return {"Phi": [[1.0, dt, dt], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            "Gamma": [[dt**2 / 2, dt**2 / 2], [dt, 0.0], [0.0, dt]],
            "W": np.diag([SIGMA_A**2, SIGMA_W**2]),
            "H": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            "V": np.diag([3.0**2, 0.5**2]),
            "M0": np.diag([100.0, 1.0, 4.0]),
            "x0": [0.0, 15.0, 0.0]}


WIND = check.Problem.linear(
    "wind-heldout", **model(), every=EVERY, n_epochs=N_EPOCHS, dt=DT,
    states=("p", "va", "w"), measurements=("gps", "pitot"), register=False,
    title="A glider in wind: position, airspeed, wind (10 Hz, GPS and pitot at 1 Hz)")
