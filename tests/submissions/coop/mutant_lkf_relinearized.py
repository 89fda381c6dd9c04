"""An "LKF" that linearizes about its own estimate: an EKF under the name lkf (jacobian-point)."""

import numpy as np

DT, L = 0.1, 0.5
X0 = np.array([10.0, 0.0, np.pi / 2, -60.0, 0.0, -np.pi / 2])
U = np.array([2.0, -np.pi / 18, 12.0, np.pi / 25])
P0 = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def arc(xi, eta, th, v, w, dt):
    if abs(w * dt) < 1e-9:
        return xi + v * dt * np.cos(th + w * dt / 2), eta + v * dt * np.sin(th + w * dt / 2), th + w * dt
    k = v / w
    return (xi + k * (np.sin(th + w * dt) - np.sin(th)),
            eta - k * (np.cos(th + w * dt) - np.cos(th)), th + w * dt)


def step(x):
    vg, phi, va, wa = U
    out = np.empty(6)
    out[0:3] = arc(x[0], x[1], x[2], vg, vg / L * np.tan(phi), DT)
    out[3:6] = arc(x[3], x[4], x[5], va, wa, DT)
    out[[2, 5]] = wrap(out[[2, 5]])
    return out


def A(x):
    vg, _, va, _ = U
    a = np.zeros((6, 6))
    a[0, 2], a[1, 2] = -vg * np.sin(x[2]), vg * np.cos(x[2])
    a[3, 5], a[4, 5] = -va * np.sin(x[5]), va * np.cos(x[5])
    return a


def h(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    return np.array([wrap(np.arctan2(dy, dx) - x[2]), np.hypot(dx, dy),
                     wrap(np.arctan2(-dy, -dx) - x[5]), x[3], x[4]])


def C(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    r2 = dx**2 + dy**2
    r = np.sqrt(r2)
    c = np.zeros((5, 6))
    c[0] = [dy / r2, -dx / r2, -1, -dy / r2, dx / r2, 0]
    c[1] = [-dx / r, -dy / r, 0, dx / r, dy / r, 0]
    c[2] = [dy / r2, -dx / r2, 0, -dy / r2, dx / r2, -1]
    c[3, 3] = c[4, 4] = 1
    return c


def lkf(y, Q, R):
    n = y.shape[0]
    x_hat, P_out = np.zeros((n, 6)), np.zeros((n, 6, 6))
    x, P = X0.copy(), P0.copy()
    x_hat[0], P_out[0] = x, P
    for k in range(1, n):
        F = np.eye(6) + DT * A(x)
        x = step(x)
        P = F @ P @ F.T + Q
        H = C(x)
        r = y[k] - h(x)
        r[[0, 2]] = wrap(r[[0, 2]])
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ r
        x[[2, 5]] = wrap(x[[2, 5]])
        I_KH = np.eye(6) - K @ H
        P = I_KH @ P @ I_KH.T + K @ R @ K.T
        x_hat[k], P_out[k] = x, P
    return x_hat, P_out
