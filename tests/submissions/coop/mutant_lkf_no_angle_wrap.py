"""LKF whose residual is not wrapped (no-angle-wrap)."""

import numpy as np
from scipy.integrate import solve_ivp

DT, L = 0.1, 0.5
X0 = np.array([10.0, 0.0, np.pi / 2, -60.0, 0.0, -np.pi / 2])
U = np.array([2.0, -np.pi / 18, 12.0, np.pi / 25])
P0 = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def f(t, x):
    vg, phi, va, wa = U
    return [vg * np.cos(x[2]), vg * np.sin(x[2]), vg / L * np.tan(phi),
            va * np.cos(x[5]), va * np.sin(x[5]), wa]


def h(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    return np.array([wrap(np.arctan2(dy, dx) - x[2]), np.hypot(dx, dy),
                     wrap(np.arctan2(-dy, -dx) - x[5]), x[3], x[4]])


def A(x):
    vg, _, va, _ = U
    a = np.zeros((6, 6))
    a[0, 2], a[1, 2] = -vg * np.sin(x[2]), vg * np.cos(x[2])
    a[3, 5], a[4, 5] = -va * np.sin(x[5]), va * np.cos(x[5])
    return a


def C(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    r2 = dx**2 + dy**2
    r = np.sqrt(r2)
    return np.array([[dy / r2, -dx / r2, -1, -dy / r2, dx / r2, 0],
                     [-dx / r, -dy / r, 0, dx / r, dy / r, 0],
                     [dy / r2, -dx / r2, 0, -dy / r2, dx / r2, -1],
                     [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0]])


def lkf(y, Q, R):
    n = y.shape[0]
    t = np.arange(n) * DT
    xn = solve_ivp(f, (0, t[-1]), X0, t_eval=t).y.T
    xn[:, [2, 5]] = wrap(xn[:, [2, 5]])
    dx, P = np.zeros(6), P0.copy()
    x_hat, P_out = np.zeros((n, 6)), np.zeros((n, 6, 6))
    x_hat[0], P_out[0] = X0, P
    for k in range(1, n):
        F = np.eye(6) + DT * A(xn[k - 1])
        dx = F @ dx
        P = F @ P @ F.T + Q
        H = C(xn[k])
        r = y[k] - h(xn[k]) - H @ dx
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        dx = dx + K @ r
        I_KH = np.eye(6) - K @ H
        P = I_KH @ P @ I_KH.T + K @ R @ K.T
        x = xn[k] + dx
        x[[2, 5]] = wrap(x[[2, 5]])
        x_hat[k], P_out[k] = x, P
    return x_hat, P_out
