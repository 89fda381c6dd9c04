"""A fourth homework problem, written as an instructor adds one: a constant-velocity tracker.

A target moves along a line with a random acceleration; the filter propagates at 10 Hz and a
position fix arrives at 2 Hz (every fifth step), for 20 s.  The student writes
``kalman_filter(z) -> (x_hat, P)`` returning x̂ = [p, v] and P at the 41 fix times.  Everything
else — the simulation, the optimal answer, the tolerance, the catalogue of mistakes (transposed
Φ, Q without Γ, σ for σ², a permuted M0, the a priori returned, a skipped first or last update,
the wrong number of steps, ...) and the feedback — comes from :meth:`gpsaccel.check.Problem.linear`.
"""

from __future__ import annotations

import numpy as np

from gpsaccel.check.problems import Problem
from gpsaccel.problems import PROBLEM_TITLES

DT = 0.1        # s, one propagation step
EVERY = 5       # steps per position fix (2 Hz)
N_FIXES = 41    # t = 0, 0.5, ..., 20 s
SIGMA_A = 0.3   # m/s², the acceleration noise
SIGMA_P = 2.0   # m, a position fix


def model(dt: float = DT, sigma_a: float = SIGMA_A, sigma_p: float = SIGMA_P) -> dict:
    """The tracker's Φ, Γ, W, H, V, M0, x0 for a propagation step ``dt`` (s) (the homework gives
    each student their own ``dt``, σ_a and σ_p)."""
    return dict(Phi=[[1.0, dt], [0.0, 1.0]],          # p += v·Δt
                Gamma=[[dt**2 / 2], [dt]],            # the acceleration enters both
                W=[[sigma_a**2]],
                H=[[1.0, 0.0]],                       # a fix measures the position
                V=[[sigma_p**2]],
                M0=np.diag([25.0, 4.0]),              # σ = 5 m, 2 m/s at t = 0
                x0=[0.0, 1.0])


#: The tracker problem (``gpsaccel check --problem tracker``, ``check.submission(p, problem=...)``).
TRACKER = Problem.linear(
    "tracker", **model(), every=EVERY, n_epochs=N_FIXES, dt=DT,
    states=("p", "v"), measurements=("p",),
    title=PROBLEM_TITLES["tracker"],
    z_meaning="the position fix (m) at t = 0, 0.5, ..., 20 s",
)
