"""Hostile (issue 20): writes a .pth into every site-packages folder it can see and a module into
the checker's package (through the '//' alias), so that the instructor's *next* check runs it."""
import ctypes
import json
import os
import sys

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME

MARK = "# gpsacc-hostile: written by a submission\n"


def _targets():
    for d in sys.path:
        if d.rstrip("/").endswith("site-packages"):
            yield os.path.join(d, "gpsacc_hostile_forged.pth")
    try:  # the runner's plan names the package's folders (argv: control folder first)
        with open(os.path.join(sys.argv[1], "plan.json"), encoding="utf-8") as f:
            for d in json.load(f)["block_dirs"]:
                yield "/" + d + "/gpsacc_hostile_forged.py"
    except (OSError, ValueError, KeyError, IndexError):
        pass


def kalman_filter(z):
    outcome = {}
    for path in _targets():
        try:
            with open(path, "w", encoding="utf-8") as f:
                f.write(MARK)
            outcome[path] = "WRITTEN"
        except OSError as exc:
            outcome[path] = type(exc).__name__
    raise RuntimeError("writes: " + "; ".join(f"{p} {r}" for p, r in outcome.items()))
