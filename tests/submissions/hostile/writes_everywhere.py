"""Hostile (issue 20): tries to write 1 MB into /, /root, /etc, /dev, /dev/shm, /tmp and its
working folder; reports what each gave (under bwrap these were unbounded tmpfs)."""
import ctypes
import os

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def kalman_filter(z):
    out = []
    for d in ("/", "/root", "/etc", "/dev", "/dev/shm", "/tmp", os.getcwd()):
        path = os.path.join(d, "gpsacc-hostile-file")
        try:
            with open(path, "wb") as f:
                f.write(b"x" * (1 << 20))
            out.append(f"{d}=written")
        except OSError as exc:
            out.append(f"{d}={exc.strerror}")
    raise RuntimeError("writes: " + ", ".join(out))
