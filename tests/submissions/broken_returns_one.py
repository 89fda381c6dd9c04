"""Broken: returns only the estimates."""
import numpy as np


def kalman_filter(z):
    return np.zeros((len(z), 3))
