"""Hostile: starts 80 background children that sleep (more than a check's process limit)."""
import ctypes
import os
import time

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    for _ in range(80):
        if os.fork() == 0:
            time.sleep(20)  # bounded: each child ends by itself
            os._exit(0)
        time.sleep(0.005)
    time.sleep(20)
    raise RuntimeError("the sandbox let 80 processes run")
