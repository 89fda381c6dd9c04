"""Report 003's filter as printed: three mistakes at once.

process-noise-interval (Φ, Γ on the GPS interval), std-as-variance M0₁₁ = 10 (posiSigma used as a
variance) and std-as-variance V₂₂ = 0.04.
"""
import numpy as np

dtGps = 0.2
phi = np.array([[1, dtGps, -dtGps**2 / 2], [0, 1, -dtGps], [0, 0, 1]])
gamma = -np.array([[dtGps**2 / 2], [dtGps], [0]])
noiseVar = 0.0004
gpsCorr = np.array([[1, 0], [0, 0.04]])
h = np.array([[1, 0, 0], [0, 1, 0]])


def kalman_filter(z):
    mIter = np.diag([10.0, 1.0, 0.01])
    xbar = np.zeros((3, 1))
    xhat_all = np.zeros((len(z), 3))
    p_all = np.zeros((len(z), 3, 3))
    for it in range(len(z)):
        K = mIter @ h.T @ np.linalg.inv(h @ mIter @ h.T + gpsCorr)
        xhat = xbar + K @ (z[it].reshape(2, 1) - h @ xbar)
        pIter = (np.eye(3) - K @ h) @ mIter @ (np.eye(3) - K @ h).T + K @ gpsCorr @ K.T
        xhat_all[it], p_all[it] = xhat[:, 0], pIter
        xbar = phi @ xhat
        mIter = phi @ pIter @ phi.T + gamma * noiseVar @ gamma.T
    return xhat_all, p_all
