"""Hostile (issue 20): streams 20 MB of valid-looking frames down the result channel (it grew the
checker to 550 MiB)."""
import json
import struct
import sys

FRAME = json.dumps({"t": "imported", "seconds": 0.1}).encode()


def kalman_filter(z):
    fd = int(sys.argv[3])
    blob = (struct.pack(">I", len(FRAME)) + FRAME) * 1000
    for _ in range(20_000_000 // len(blob)):
        try:
            _write(fd, blob)
        except OSError:
            break
    raise RuntimeError("flood sent")


def _write(fd, data):
    import os

    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
