"""expect: information-vector — information form with x̂ = Y·y (it should solve Y x̂ = y): the
estimate runs away (to ~1e100 and beyond), and is the student's own result.
accept: gain-or-residual, nan-output — a run-away estimate cannot be matched to 1e-6 σ (its rounding
alone is larger): its P (right) and where x̂ departs are what can be said, or, where it overflows
to inf and NaN first, where and that it ran away."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
G = -np.array([[dt**2 / 2], [dt], [0]])
Q = 4e-4 * G @ G.T
H = np.array([[1.0, 0, 0], [0, 1, 0]])
Vi = np.linalg.inv(np.diag([1, 0.0016]))


def kalman_filter(z):
    x, M = np.zeros(3), np.diag([100, 1, 0.01])
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k:
            for _ in range(40):
                x, M = Phi @ x, Phi @ M @ Phi.T + Q
        Y = np.linalg.inv(M) + H.T @ Vi @ H
        y = np.linalg.inv(M) @ x + H.T @ Vi @ z[k]
        x = Y @ y
        M = np.linalg.inv(Y)
        xs[k], Ps[k] = x, M
    return xs, Ps
