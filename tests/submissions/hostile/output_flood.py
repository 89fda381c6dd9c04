"""Hostile: prints 50 MB."""
import sys

import numpy as np


def kalman_filter(z):
    line = "x" * 1023 + "\n"
    for _ in range(50 * 1024):
        sys.stdout.write(line)
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
