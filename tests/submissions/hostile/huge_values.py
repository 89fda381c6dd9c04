"""Hostile (issue 20): returns finite values near the largest float (1.7e308), on which the
checker's arithmetic overflows; a value all the same, judged as the student's result (issue 40)."""
import numpy as np


def kalman_filter(z):
    x = np.full((len(z), 3), 1.7e308)
    P = np.tile(np.eye(3) * 1.7e308, (len(z), 1, 1))
    return x, P
