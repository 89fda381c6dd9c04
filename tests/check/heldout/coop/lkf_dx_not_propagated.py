"""expect: mean-not-propagated — the LKF's δx̄ not propagated (δx̄ = δx̂; F only in P)."""
import numpy as np

DT, L = 0.1, 0.5
X0 = np.array([10.0, 0.0, np.pi / 2, -60.0, 0.0, -np.pi / 2])
VG, PHI, VA, WA = 2.0, -np.pi / 18, 12.0, np.pi / 25
P0 = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def nominal(n):
    """The noiseless trajectory in closed form (constant turn rates)."""
    t = np.arange(n) * DT
    wg = VG / L * np.tan(PHI)
    xn = np.zeros((n, 6))
    xn[:, 2] = X0[2] + wg * t
    xn[:, 0] = X0[0] + VG / wg * (np.sin(xn[:, 2]) - np.sin(X0[2]))
    xn[:, 1] = X0[1] - VG / wg * (np.cos(xn[:, 2]) - np.cos(X0[2]))
    xn[:, 5] = X0[5] + WA * t
    xn[:, 3] = X0[3] + VA / WA * (np.sin(xn[:, 5]) - np.sin(X0[5]))
    xn[:, 4] = X0[4] - VA / WA * (np.cos(xn[:, 5]) - np.cos(X0[5]))
    xn[:, [2, 5]] = wrap(xn[:, [2, 5]])
    return xn


def F_at(x):
    F = np.eye(6)
    F[0, 2], F[1, 2] = -DT * VG * np.sin(x[2]), DT * VG * np.cos(x[2])
    F[3, 5], F[4, 5] = -DT * VA * np.sin(x[5]), DT * VA * np.cos(x[5])
    return F


def h(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    return np.array([wrap(np.arctan2(dy, dx) - x[2]), np.hypot(dx, dy),
                     wrap(np.arctan2(-dy, -dx) - x[5]), x[3], x[4]])


def H_at(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    q = dx * dx + dy * dy
    r = np.sqrt(q)
    return np.array([[dy / q, -dx / q, -1, -dy / q, dx / q, 0],
                     [-dx / r, -dy / r, 0, dx / r, dy / r, 0],
                     [dy / q, -dx / q, 0, -dy / q, dx / q, -1],
                     [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0.0]])


def lkf(y, Q, R):
    n = len(y)
    xn = nominal(n)
    dx, P = np.zeros(6), P0.copy()
    xs, Ps = np.zeros((n, 6)), np.zeros((n, 6, 6))
    xs[0], Ps[0] = X0, P
    for k in range(1, n):
        F = F_at(xn[k - 1])
        P = F @ P @ F.T + Q
        H = H_at(xn[k])
        r = y[k] - h(xn[k]) - H @ dx
        r[[0, 2]] = wrap(r[[0, 2]])
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        dx = dx + K @ r
        P = (np.eye(6) - K @ H) @ P @ (np.eye(6) - K @ H).T + K @ R @ K.T
        x = xn[k] + dx
        x[[2, 5]] = wrap(x[[2, 5]])
        xs[k], Ps[k] = x, P
    return xs, Ps
