"""An instructor's own problem: a target moving in the plane at near-constant velocity.

x = [px, py, vx, vy] (m, m/s), propagated at 10 Hz with a white acceleration of σ_a (m/s²) on each
axis, a position fix [px, py] of σ_p (m) at 1 Hz, from t = 0 to 30 s (31 fixes).
``gpsaccel check --problem cv2d/problems.py:cv2d`` checks a student's ``kalman_filter(z)``
against it; ``graded.py`` beside it grades the homework built on it.
"""

import numpy as np

from gpsaccel import check


def model(dt: float = 0.1, sigma_a: float = 0.5, sigma_p: float = 3.0) -> dict:
    """Φ, Γ, W, H, V, M0, x0 of the target propagated every ``dt`` s."""
    I2, O2 = np.eye(2), np.zeros((2, 2))
    return {"Phi": np.block([[I2, dt * I2], [O2, I2]]),
            "Gamma": np.vstack([dt**2 / 2 * I2, dt * I2]), "W": sigma_a**2 * I2,
            "H": np.hstack([I2, O2]), "V": sigma_p**2 * I2,
            "M0": np.diag([10.0**2, 10.0**2, 1.0**2, 1.0**2]), "x0": np.array([0.0, 0.0, 5.0, 2.0])}


cv2d = check.Problem.linear(
    "cv2d", **model(), every=10, n_epochs=31, dt=0.1, states=("px", "py", "vx", "vy"),
    measurements=("px", "py"), title="A 2-D constant-velocity target (10 Hz, fixes at 1 Hz)")
