"""Broken: never returns (the loop counter is never advanced)."""
import numpy as np


def kalman_filter(z):
    x_hat = np.zeros((len(z), 3))
    P = np.zeros((len(z), 3, 3))
    k = 0
    while k < len(z):
        x_hat[k] = 0.0
    return x_hat, P
