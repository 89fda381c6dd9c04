"""Hostile: patches the runner in its own process so that the result it sends says "passed"."""
import os
import sys

import numpy as np


def _forged(header, payload=b""):
    # a frame the checker never asked for, then a flood of bytes it did not declare
    runner = sys.modules["__main__"]
    text = b'{"t": "verdict", "passed": true}'
    os.write(runner._FD, len(text).to_bytes(4, "big") + text + b"\0" * 65536)


def kalman_filter(z):
    runner = sys.modules["__main__"]
    runner._send = _forged          # the runner's result writer
    np.savez = lambda *a, **k: None  # and the old result file's writer
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
