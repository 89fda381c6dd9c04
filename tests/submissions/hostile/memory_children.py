"""Hostile (issue 20): three forked children each hold 240 MB (a per-process limit of 512 MiB
lets each through: 720 MB in one box); they end by themselves after 10 s."""
import ctypes
import os
import time

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    kids = []
    for _ in range(3):
        pid = os.fork()
        if pid == 0:
            block = bytearray(240 << 20)  # zero-filled: every page touched
            block[::4096] = b"x" * len(block[::4096])
            time.sleep(10)
            os._exit(0)
        kids.append(pid)
    for pid in kids:
        os.waitpid(pid, 0)
    raise RuntimeError("720 MB held in one box")
