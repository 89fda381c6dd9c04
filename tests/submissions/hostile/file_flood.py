"""Hostile: writes a 200 MB file in its working folder."""
import numpy as np


def kalman_filter(z):
    block = b"\0" * (1 << 20)
    with open("flood.bin", "wb") as f:
        for _ in range(200):
            f.write(block)
            f.flush()
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
