"""Broken: fails when imported (a module that does not exist)."""
import numpy as np
from kalman_helpers import propagate  # noqa: F401  (the student forgot to hand this file in)


def kalman_filter(z):
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
