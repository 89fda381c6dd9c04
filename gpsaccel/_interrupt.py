"""Ctrl-C that cannot be lost.

Python raises ``KeyboardInterrupt`` wherever the signal lands.  Where it lands inside a finaliser
(a generator the garbage collector closes, a ``__del__``, fork's at-fork handlers), the exception is
printed as "Exception ignored" and dropped, and the loop runs on: once, at load 5, a whole
2,000,000-run Monte Carlo ran to its end after Ctrl-C.  :func:`latched_sigint` records every SIGINT
in a :class:`Latch`, which the loop that owns the work reads at its boundaries (between chunks,
between polls), so it stops there even when the exception was dropped.  ``raise_now`` also raises
where the signal lands, as Python does, for a prompt stop in the middle of long work.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


class Latch:
    """How many SIGINTs came while the latch was set; true once one came."""

    def __init__(self) -> None:
        self.signals = 0

    def __bool__(self) -> bool:
        return self.signals > 0

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if a SIGINT came (even one whose exception was dropped)."""
        if self.signals:
            raise KeyboardInterrupt


@contextmanager
def latched_sigint(raise_now: bool) -> Iterator[Latch]:
    """SIGINT recorded in the yielded :class:`Latch` for the block, then the previous handler
    back.  Signals reach the main thread only: elsewhere the latch is never set (the main
    thread's handler, whatever it is, stays).  Not nested: an inner latch hides the signal from
    an outer one."""
    latch = Latch()
    if threading.current_thread() is not threading.main_thread():
        yield latch
        return

    def handler(signum: int, frame: object) -> None:
        latch.signals += 1
        if raise_now:
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield latch
    finally:
        signal.signal(signal.SIGINT, previous)
