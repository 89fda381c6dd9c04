"""Hostile (issue 20): frames the parent's code would choke on: a header nested 30,000 deep
(60 kB, within the header limit), then (if it is still read) a problem frame whose fields have
the wrong types."""
import json
import os
import struct
import sys


def _send(fd, data):
    blob = struct.pack(">I", len(data)) + data
    view = memoryview(blob)
    while view:
        view = view[os.write(fd, view):]


def kalman_filter(z):
    fd = int(sys.argv[3])
    _send(fd, b'{"t": "problem", "kind": "exception", "shapes": ' + b"[" * 30_000
          + b"]" * 30_000 + b"}")
    _send(fd, json.dumps({"t": "problem", "kind": 5, "call": "zero",
                          "traceback": {"a": 1}}).encode())
    raise RuntimeError("forged frames sent")
