"""Hostile (issue 20): starts a process through a terminal multiplexer server (the instructor's,
if its socket is in reach, else one of its own): not a descendant of the box, it would outlive
the check.  Bounded: the process sleeps 20 s and ends."""
import ctypes
import os
import subprocess
import sys

import numpy as np

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME

SLEEPER = (f"{sys.executable} -c \"import ctypes, time; "
           f"ctypes.CDLL(None).prctl(15, b'gpsacc-hostile', 0, 0, 0); time.sleep(20)\"")


def kalman_filter(z):
    env = {"PATH": "/usr/bin:/bin", "TMUX_TMPDIR": "/tmp", "HOME": os.getcwd()}
    for args in (["-S", "/tmp/tmux-0/gpsacc-hostile", "new-window", "-d"],  # the instructor's
                 ["-L", "gpsacc-own", "new-session", "-d"]):  # a server of its own
        try:
            subprocess.run(["tmux", *args, SLEEPER], env=env, timeout=5, check=True,
                           stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            break
        except (OSError, subprocess.SubprocessError):
            continue
    return np.zeros((len(z), 3)), np.tile(np.eye(3), (len(z), 1, 1))
