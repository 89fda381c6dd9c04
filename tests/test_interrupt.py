"""Ctrl-C cannot be lost (:mod:`gpsaccel._interrupt`): a KeyboardInterrupt raised inside a
finaliser is dropped by Python ("Exception ignored"); the latch still has the signal, and the
loops that own one stop at their next boundary (the Monte Carlo between chunks; the sandbox pool's
loop is tested in tests/sandbox)."""

from __future__ import annotations

import os
import signal
import sys

import pytest

from gpsaccel._interrupt import latched_sigint
from gpsaccel.calibration import CalibrationModel
from gpsaccel.calibration.montecarlo import engine


class _InterruptedWhileFinalised:
    """Ctrl-C lands while the garbage collector runs this object's ``__del__``."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # bytecode, where Python runs the handler: inside __del__
            pass


@pytest.fixture
def dropped(monkeypatch):
    """What Python drops (``sys.unraisablehook``): here recorded instead of printed."""
    seen = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: seen.append(u.exc_type))
    return seen


def _lose_an_interrupt():
    obj = _InterruptedWhileFinalised()
    del obj  # the KeyboardInterrupt is raised in __del__ and dropped: nothing comes out here


def test_python_drops_an_interrupt_raised_in_a_finaliser_and_the_latch_keeps_it(dropped):
    with latched_sigint(raise_now=True) as latch:
        _lose_an_interrupt()
        assert dropped == [KeyboardInterrupt] and latch.signals == 1
        with pytest.raises(KeyboardInterrupt):
            latch.check()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # put back


def test_without_raise_now_the_signal_is_only_recorded(dropped):
    with latched_sigint(raise_now=False) as latch:
        assert not latch
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):
            pass
        assert latch and dropped == []
    with pytest.raises(KeyboardInterrupt):
        latch.check()


def test_the_monte_carlo_stops_at_the_next_chunk_after_a_dropped_interrupt(dropped, monkeypatch):
    real, ran = engine._chunk_sums, []

    def chunk_sums(*args):
        ran.append(args[2])
        if len(ran) == 2:
            _lose_an_interrupt()
        return real(*args)

    monkeypatch.setattr(engine, "_chunk_sums", chunk_sums)
    with pytest.raises(KeyboardInterrupt):
        engine.monte_carlo(CalibrationModel(duration=2.0), 10 * 1000, chunk_size=1000,
                           progress=False)
    assert dropped == [KeyboardInterrupt] and ran == [0, 1000]  # not the other eight chunks
