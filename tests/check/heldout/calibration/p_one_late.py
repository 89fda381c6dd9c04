"""expect: epoch-shift — P stored before the update of the next step's loop: row k holds P of k − 1
(x̂ stored right)."""
import numpy as np

dt = 0.005
Phi = np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1.0]])
Gam = -np.array([[dt**2 / 2], [dt], [0]])
H = np.array([[1.0, 0, 0], [0, 1, 0]])
R = np.diag([1, 0.04**2])


def kalman_filter(z):
    N = z.shape[0]
    X = np.zeros((N, 3))
    PP = np.zeros((N, 3, 3))
    x = np.zeros(3)
    P = np.diag([100, 1, 0.01])
    PP[0] = P            # the prior goes in first ...
    for k in range(N):
        if k > 0:
            PP[k] = P    # ... and each row gets the P of the step before
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Gam @ Gam.T * 0.0004
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
        x = x + K @ (z[k] - H @ x)
        IKH = np.eye(3) - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        X[k] = x
    return X, PP
