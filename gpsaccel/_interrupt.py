"""Ctrl-C that cannot be lost, and SIGTERM and SIGHUP taken like it.

Python raises ``KeyboardInterrupt`` wherever the signal lands.  Where it lands inside a finaliser
(a generator the garbage collector closes, a ``__del__``, fork's at-fork handlers), the exception is
printed as "Exception ignored" and dropped, and the loop runs on: once, at load 5, a whole
2,000,000-run Monte Carlo ran to its end after Ctrl-C.  :func:`latched_sigint` records every SIGINT
in a :class:`Latch`, which the loop that owns the work reads at its boundaries (between chunks,
between polls), so it stops there even when the exception was dropped.  ``raise_now`` also raises
where the signal lands, as Python does, for a prompt stop in the middle of long work.

:func:`latched_stop` latches the three signals that ask a run to stop: SIGINT (Ctrl-C), SIGTERM
(``timeout``, ``kill``, ``systemctl stop``, ``docker stop``, a batch scheduler) and SIGHUP (the
terminal closed).  The pool of a class's boxes (:func:`gpsaccel.sandbox.run_items`) holds it, so
whichever comes, every box is killed and the caller keeps what finished, as for Ctrl-C: the
``KeyboardInterrupt`` it raises is a :class:`Stopped` naming the signal (and what the pool kept),
and :func:`exit_status` is the shell's 128 + that signal.  :func:`stop_after_cleanup` is for
code that owns processes outside a pool (one box): SIGTERM and SIGHUP raise there, so its
``finally`` kills them, and the process then ends by the same signal, as it would have.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager

#: The signals that ask a run to stop.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Stopped(KeyboardInterrupt):
    """A run stopped by ``signum`` (a KeyboardInterrupt: every handler of Ctrl-C handles it);
    its text names the signal and, when the stopper knows it, what was kept."""

    def __init__(self, signum: int = signal.SIGINT, kept: str = "") -> None:
        self.signum = int(signum)
        self.kept = kept
        super().__init__(signal.Signals(self.signum).name + (f": {kept}" if kept else ""))


class Latch:
    """How many stop signals came while the latch was set (the last one in :attr:`signum`);
    true once one came."""

    def __init__(self) -> None:
        self.signals = 0
        self.signum = int(signal.SIGINT)

    def __bool__(self) -> bool:
        return self.signals > 0

    def check(self, kept: str = "") -> None:
        """Raise if a signal came (even one whose exception was dropped): :class:`Stopped`, or
        for Ctrl-C with nothing to say the KeyboardInterrupt Python raises."""
        if self.signals:
            if self.signum == signal.SIGINT and not kept:
                raise KeyboardInterrupt
            raise Stopped(self.signum, kept)


@contextmanager
def latched(signals: Sequence[int], raise_now: bool) -> Iterator[Latch]:
    """``signals`` recorded in the yielded :class:`Latch` for the block, then the previous
    handlers back.  Signals reach the main thread only: elsewhere the latch is never set (the
    main thread's handlers, whatever they are, stay).  Not nested: an inner latch hides the
    signal from an outer one."""
    latch = Latch()
    if threading.current_thread() is not threading.main_thread():
        yield latch
        return

    def handler(signum: int, frame: object) -> None:
        latch.signals += 1
        latch.signum = signum
        if raise_now:  # where it lands: Ctrl-C as Python raises it, the others named
            raise KeyboardInterrupt if signum == signal.SIGINT else Stopped(signum)

    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield latch
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def latched_sigint(raise_now: bool) -> AbstractContextManager[Latch]:
    """:func:`latched` for Ctrl-C alone."""
    return latched((signal.SIGINT,), raise_now)


def latched_stop(raise_now: bool) -> AbstractContextManager[Latch]:
    """:func:`latched` for SIGINT, SIGTERM and SIGHUP (module docstring)."""
    return latched(STOP_SIGNALS, raise_now)


@contextmanager
def stop_after_cleanup() -> Iterator[None]:
    """SIGTERM and SIGHUP raise :class:`Stopped` in the block, where the default would have
    ended the process at once (a handler the process set, or an ignored signal, is left
    alone); once the block's ``finally`` clauses have run, the process ends by that signal, as
    it would have.  Main thread only (elsewhere nothing changes)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    mine = [s for s in (signal.SIGTERM, signal.SIGHUP) if signal.getsignal(s) == signal.SIG_DFL]

    def handler(signum: int, frame: object) -> None:
        raise Stopped(signum)

    for s in mine:
        signal.signal(s, handler)
    try:
        yield
    except Stopped as exc:
        if exc.signum not in mine:
            raise
        for s in mine:
            signal.signal(s, signal.SIG_DFL)
        os.kill(os.getpid(), exc.signum)
        raise  # pragma: no cover - the signal ended the process
    finally:
        for s in mine:
            signal.signal(s, signal.SIG_DFL)


def why(exc: BaseException) -> str:
    """What follows "interrupted" in a message: ``" by SIGTERM: 2 of 5 finished and kept, ..."``
    (nothing for a plain Ctrl-C)."""
    if not isinstance(exc, Stopped):
        return ""
    by = "" if exc.signum == signal.SIGINT else f" by {signal.Signals(exc.signum).name}"
    return by + (f": {exc.kept}" if exc.kept else "")


def exit_status(exc: BaseException | None) -> int:
    """128 + the signal that stopped the run (130 for Ctrl-C), read from ``exc`` or the
    exceptions it was raised from or during."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, Stopped):
            return 128 + exc.signum
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return 128 + int(signal.SIGINT)
