"""Hostile: allocates (and touches) memory in 64 MiB chunks, up to 2.5 GB."""
import numpy as np


def kalman_filter(z):
    hoard = []
    for _ in range(40):  # 40 x 64 MiB = 2.5 GiB, unless the sandbox stops it first
        hoard.append(np.ones(8 << 20))
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
