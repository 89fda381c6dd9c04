"""Right algorithm, single precision throughout (low-precision)."""
import numpy as np

dt = 0.005
Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
Gamma = -np.array([[dt**2 / 2], [dt], [0.0]])
W = 0.0004
H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
V = np.diag([1.0, 0.04**2])
M0 = np.diag([100.0, 1.0, 0.01])


def kalman_filter(z):
    f = np.float32
    z = z.astype(f)
    Phi_, H_, V_ = Phi.astype(f), H.astype(f), V.astype(f)
    n = len(z)
    x_hat = np.zeros((n, 3), f)
    P = np.zeros((n, 3, 3), f)
    x, M = np.zeros(3, f), M0.astype(f)
    Q = (Gamma @ Gamma.T * W).astype(f)
    I = np.eye(3, dtype=f)
    for k in range(n):
        if k > 0:
            for _ in range(40):
                x = Phi_ @ x
                M = Phi_ @ M @ Phi_.T + Q
        K = M @ H_.T @ np.linalg.inv(H_ @ M @ H_.T + V_)
        x = x + K @ (z[k] - H_ @ x)
        M = (I - K @ H_) @ M
        x_hat[k], P[k] = x, M
    return x_hat, P
