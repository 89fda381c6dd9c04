"""expect: jacobian-blocks — the bearing and range rows of C with the UGV and UAV position blocks
swapped (Δ taken the other way round)."""
import numpy as np

DT, L = 0.1, 0.5
X0 = np.array([10.0, 0.0, np.pi / 2, -60.0, 0.0, -np.pi / 2])
U = np.array([2.0, -np.pi / 18, 12.0, np.pi / 25])
P0 = np.diag([1.0, 1.0, 0.025, 1.0, 1.0, 0.025])


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def move(x):
    vg, phi, va, wa = U
    wg = vg / L * np.tan(phi)
    out = x.copy()
    out[0] += vg / wg * (np.sin(x[2] + wg * DT) - np.sin(x[2]))
    out[1] -= vg / wg * (np.cos(x[2] + wg * DT) - np.cos(x[2]))
    out[2] = wrap(x[2] + wg * DT)
    out[3] += va / wa * (np.sin(x[5] + wa * DT) - np.sin(x[5]))
    out[4] -= va / wa * (np.cos(x[5] + wa * DT) - np.cos(x[5]))
    out[5] = wrap(x[5] + wa * DT)
    return out


def jac_A(x):
    vg, _, va, _ = U
    A = np.zeros((6, 6))
    A[0, 2] = -vg * np.sin(x[2])
    A[1, 2] = vg * np.cos(x[2])
    A[3, 5] = -va * np.sin(x[5])
    A[4, 5] = va * np.cos(x[5])
    return A


def meas(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    return np.array([wrap(np.arctan2(dy, dx) - x[2]), np.sqrt(dx**2 + dy**2),
                     wrap(np.arctan2(-dy, -dx) - x[5]), x[3], x[4]])


def jac_C(x):
    dx, dy = x[3] - x[0], x[4] - x[1]
    q = dx**2 + dy**2
    r = np.sqrt(q)
    C = np.zeros((5, 6))
    C[0] = [-dy / q, dx / q, -1, dy / q, -dx / q, 0]
    C[1] = [dx / r, dy / r, 0, -dx / r, -dy / r, 0]
    C[2] = [-dy / q, dx / q, 0, dy / q, -dx / q, -1]
    C[3, 3] = C[4, 4] = 1
    return C


def ekf(y, Q, R):
    n = len(y)
    xs, Ps = np.zeros((n, 6)), np.zeros((n, 6, 6))
    x, P = X0.copy(), P0.copy()
    xs[0], Ps[0] = x, P
    for k in range(1, n):
        F = np.eye(6) + DT * jac_A(x)
        x = move(x)
        P = F @ P @ F.T + Q
        H = jac_C(x)
        r = y[k] - meas(x)
        r[0], r[2] = wrap(r[0]), wrap(r[2])
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ r
        x[2], x[5] = wrap(x[2]), wrap(x[5])
        A = np.eye(6) - K @ H
        P = A @ P @ A.T + K @ R @ K.T
        xs[k], Ps[k] = x, P
    return xs, Ps
