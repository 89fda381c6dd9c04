"""Hostile: kills the process that runs it (the checker), hoping to take the batch down."""
import ctypes
import os
import signal
import time

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    os.kill(os.getppid(), signal.SIGKILL)
    time.sleep(1.0)
    raise RuntimeError(f"my parent {os.getppid()} survived SIGKILL")
