"""The result channel: the runner's frames read against the outputs the parent declared
(:class:`FrameReader`); anything else is :class:`Refused`, never loaded."""

from __future__ import annotations

import json
import struct
from collections.abc import Callable, Sequence
from typing import TypeGuard

import numpy as np

from gpsaccel.sandbox.spec import Call
from gpsaccel.sandbox.submission import _shown

#: Longest frame header (JSON) the parent accepts from the runner, and longest text field in it
#: (the runner keeps a traceback's last lines, each cut to a line's worth).
MAX_HEADER = 1 << 16
MAX_TEXT = 8000
#: Bytes of the result channel beyond the declared outputs: per call (a result header), and for
#: the other frames (imported, uses-checker, problem, done: each at most MAX_HEADER).
HEADER_ALLOWANCE = 1024
CHANNEL_ALLOWANCE = 4 * MAX_HEADER

class Refused(Exception):
    """The runner's channel carried something other than the declared frames."""


def _is_int(v: object) -> TypeGuard[int]:
    return isinstance(v, int) and not isinstance(v, bool) and -(1 << 31) < v < 1 << 31


def _is_seconds(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < 1e9


def _is_text(v: object) -> bool:
    return isinstance(v, str) and len(v) <= MAX_TEXT


def _is_shape(v: object) -> bool:
    return isinstance(v, list) and len(v) <= 32 and all(_is_int(n) and n >= 0 for n in v)


def _is_described(v: object) -> bool:
    """What the runner's ``_describe`` makes: {"type": str, "shape": list | None, "dtype": str}."""
    return (isinstance(v, dict) and _is_text(v.get("type"))
            and set(v) <= {"type", "shape", "dtype"}
            and (v.get("shape") is None or _is_shape(v["shape"]))
            and ("dtype" not in v or _is_text(v["dtype"])))


def _optional(check):  # noqa: ANN001, ANN202
    return lambda v: v is None or check(v)


#: Every field a frame may carry and the test its value must pass (what the runner sends; the
#: parent's code reads these and nothing else, so a value of another type never reaches it).
FRAME_FIELDS: dict[str, dict[str, Callable[[object], bool]]] = {
    "uses-checker": {"module": _is_text},
    "imported": {"seconds": _is_seconds},
    "result": {"call": _is_int,
               "returned": lambda v: isinstance(v, dict) and len(v) <= 64 and all(
                   _is_text(k) and _is_described(d) for k, d in v.items())},
    "problem": {"kind": lambda v: v in ("import-error", "no-function", "exception",
                                        "return-value", "not-numeric", "wrong-shape"),
                "exception": _is_text, "limit": _optional(_is_text),
                "traceback": _is_text, "call": lambda v: _is_int(v) and v >= 0,
                "function": _is_text, "name": _is_text, "error": _is_text,
                "callables": lambda v: isinstance(v, list) and len(v) <= 64 and all(
                    map(_is_text, v)),
                "found": _optional(_is_described), "returned": _is_described,
                "length": _optional(_is_int), "expected": _is_int, "got": _is_shape,
                "shapes": lambda v: isinstance(v, dict) and len(v) <= 64 and all(
                    _is_text(k) and (s is None or _is_shape(s)) for k, s in v.items())},
    "done": {"import_seconds": _is_seconds, "run_seconds": _is_seconds},
    "forked": {"call": lambda v: _is_int(v) and v >= 0},
}
#: How many frames of each kind a box may send ("result": one per call, counted apart).
FRAME_COUNTS = {"uses-checker": 2, "imported": 1, "problem": 1, "done": 1, "forked": 1}
#: Fields a problem frame must have.
PROBLEM_NEEDS = ("kind",)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number the runner sends")


class FrameReader:
    """Parse the runner's frames against the declared outputs; raise :class:`Refused` otherwise.

    Bounded by what was declared, never by the bytes read: the channel may carry at most
    :attr:`budget` bytes (the declared outputs' bytes plus :data:`HEADER_ALLOWANCE` per call and
    :data:`CHANNEL_ALLOWANCE` for the rest), a header at most :data:`MAX_HEADER` bytes, each kind
    of frame at most :data:`FRAME_COUNTS` times; every header field must pass its test in
    :data:`FRAME_FIELDS` (type, size, range, nesting).  What a declared result holds is the
    student's value, whatever it is (NaN, ±inf, 1e308: a filter that runs away returns such
    numbers, and the checker judges them as its result); a breach is a frame that is not what
    was declared (its kind, size, shape or dtype, its header), never a number.  The parent holds
    at most one header plus one declared result of undecoded bytes at a time.

    A result is taken only as the answer to the call expected next, in order, and what was taken
    stays when a later frame is refused (:attr:`results`: the box's failure is then
    ``result-refused``, and a notebook's grade keeps the answers complete before it).  This is
    safe whoever wrote the frames: the student's code runs in the runner's process and could
    write any frame itself, but a frame it forges for call i only says what its own function
    could have returned on call i, it cannot be taken for another call, and nothing on this
    channel reaches a classmate's box or the grader's answers (no verdict is read from it).  A
    process the student's code forked never speaks for the runner (the runner's
    ``_send``); ``forked`` is the runner's word that one was made, during call :attr:`forked`
    (-1: while the student's file was imported), for the feedback only.
    """

    def __init__(self, calls: Sequence[Call]) -> None:
        self.calls = calls
        self.buf = bytearray()
        self.results: list[dict[str, np.ndarray]] = []
        self.events: list[dict] = []
        self.done = False
        self.problem: dict | None = None
        self.forked: int | None = None
        self.received = 0
        self.counts: dict[str, int] = {}
        self.budget = (sum(o.nbytes for c in calls for o in c.outputs)
                       + HEADER_ALLOWANCE * len(calls) + CHANNEL_ALLOWANCE)

    def feed(self, data: bytes) -> None:
        if self.done or self.problem is not None:
            if data:
                raise Refused("bytes after the last frame")
        self.received += len(data)
        if self.received > self.budget:
            raise Refused(f"more than {self.budget:,} bytes (the declared outputs and their "
                          f"headers need at most that)")
        self.buf += data
        while len(self.buf) >= 4:
            (n,) = struct.unpack(">I", self.buf[:4])
            if n > MAX_HEADER:
                raise Refused(f"a frame header of {n} bytes (at most {MAX_HEADER})")
            if len(self.buf) < 4 + n:
                return
            header = self._header(bytes(self.buf[4:4 + n]))
            size = self._payload_size(header)
            if len(self.buf) < 4 + n + size:
                return
            payload = bytes(self.buf[4 + n:4 + n + size])
            del self.buf[:4 + n + size]
            self._take(header, payload)
            if (self.done or self.problem is not None) and self.buf:
                raise Refused("bytes after the last frame")

    def _payload_size(self, header: dict) -> int:
        """Bytes after the header: a result's declared outputs, nothing for the other frames."""
        if header["t"] != "result":
            return 0
        i = len(self.results)
        if header.get("call") != i or i >= len(self.calls):
            raise Refused(f"a result for call {_shown(repr(header.get('call')), 40)} "
                          f"where call {i} was expected ({len(self.calls)} declared)")
        return sum(o.nbytes for o in self.calls[i].outputs)

    def _take(self, header: dict, payload: bytes) -> None:
        kind = header["t"]
        if kind == "result":
            self.results.append(self._arrays(payload, self.calls[len(self.results)]))
            if len(self.results) == 1:
                self.events.append(header)  # what the first call returned, for notes
        else:
            self.events.append(header)
        if kind == "forked":
            self.forked = self._forked_call(header)
        elif kind == "problem":
            self.problem = header
        elif kind == "done":
            if len(self.results) != len(self.calls):
                raise Refused(f"'done' after {len(self.results)} of {len(self.calls)} "
                              f"results")
            self.done = True

    def _forked_call(self, header: dict) -> int:
        """The call a ``forked`` frame names: the one in progress (its results not yet sent),
        or none while the file was imported (-1), before its ``imported`` frame."""
        call = header.get("call", -1)
        if call == -1 and "imported" in self.counts or call >= 0 and call != len(self.results):
            raise Refused(f"a 'forked' frame for call {call} while call {len(self.results)} "
                          f"was in progress")
        return call

    def _header(self, raw: bytes) -> dict:
        """The header, checked field by field against :data:`FRAME_FIELDS`."""
        try:
            header = json.loads(raw, parse_constant=_reject_constant)
        except RecursionError:
            raise Refused("a frame header nested too deep") from None
        except (UnicodeDecodeError, ValueError) as exc:
            raise Refused(f"a frame header that is not JSON ({_shown(str(exc), 80)})") from None
        if not isinstance(header, dict):
            raise Refused("a frame header that is not a JSON object")
        kind = header.get("t")
        if not isinstance(kind, str) or kind not in FRAME_FIELDS:
            raise Refused(f"a frame of unknown kind {_shown(repr(kind), 40)}")
        fields = FRAME_FIELDS[kind]
        if kind != "result":
            self.counts[kind] = self.counts.get(kind, 0) + 1
            if self.counts[kind] > FRAME_COUNTS[kind]:
                raise Refused(f"more than {FRAME_COUNTS[kind]} {kind!r} frame(s)")
        for key, value in header.items():
            if key == "t":
                continue
            test = fields.get(key)
            if test is None:
                raise Refused(f"a {kind!r} frame with an unknown field {_shown(repr(key), 40)}")
            if not test(value):
                raise Refused(f"a {kind!r} frame whose field {key!r} is not what the runner "
                              f"sends")
        if kind == "problem" and not all(k in header for k in PROBLEM_NEEDS):
            raise Refused("a 'problem' frame without its kind")
        return header

    @staticmethod
    def _arrays(payload: bytes, call: Call) -> dict[str, np.ndarray]:
        out, at = {}, 0
        for o in call.outputs:
            a = np.frombuffer(payload, dtype=o.dtype, count=o.nbytes // np.dtype(o.dtype).itemsize,
                              offset=at).reshape(o.shape).copy()
            at += o.nbytes
            out[o.name] = a
        return out
