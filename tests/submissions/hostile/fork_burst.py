"""Hostile (issue 20): forks as fast as it can (no pause between forks), up to 150 children that
sleep 20 s; a per-process count sampled every 250 ms let 122 run against a limit of 64."""
import ctypes
import os
import time

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    n = 0
    for _ in range(150):
        try:
            pid = os.fork()
        except BlockingIOError:
            continue
        if pid == 0:
            time.sleep(20)  # bounded: each child ends by itself
            os._exit(0)
        n += 1
    time.sleep(2)
    raise RuntimeError(f"{n} children forked")
