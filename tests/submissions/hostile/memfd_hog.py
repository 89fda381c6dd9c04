"""Hostile (issue 20): holds 40 memfds of 15 MB (each below the file-size limit; 600 MB in all,
memory no address-space limit sees)."""
import ctypes
import os
import time

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    fds = []
    chunk = b"x" * (1 << 20)
    for i in range(40):
        fd = os.memfd_create(f"hog{i}")
        for _ in range(15):
            os.write(fd, chunk)
        fds.append(fd)
    time.sleep(2)
    raise RuntimeError(f"{len(fds)} memfds of 15 MB held")
