"""Broken: the filter has another name."""
import numpy as np


def my_kalman(z):
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
