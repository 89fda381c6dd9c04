"""Hostile (issue 20): returns finite values near the largest float (1.7e308): the checker's
arithmetic on them overflows."""
import numpy as np


def kalman_filter(z):
    x = np.full((len(z), 3), 1.7e308)
    P = np.tile(np.eye(3) * 1.7e308, (len(z), 1, 1))
    return x, P
