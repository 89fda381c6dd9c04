"""Hostile (issue 20): reads the checker's own source through '//path/to/gpsaccel' (the audit
hook compared the path as written, and '//x' is not '/x' to a string test)."""
import ctypes
import json
import os
import sys

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    with open(os.path.join(sys.argv[1], "plan.json"), encoding="utf-8") as f:
        dirs = json.load(f)["block_dirs"]
    for d in dirs:
        for alias in ("/" + d, d + "/./check/..", d.replace("/", "//")):
            try:
                with open(alias + "/check/problems/calibration.py", encoding="utf-8") as f:
                    f.read(100)
                raise RuntimeError(f"read the checker through {alias}")
            except (FileNotFoundError, PermissionError):
                continue
    raise RuntimeError("nothing read")
