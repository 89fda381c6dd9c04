"""Ctrl-C cannot be lost (:mod:`gpsaccel._interrupt`): a KeyboardInterrupt raised inside a
finaliser is dropped by Python ("Exception ignored"); the latch still has the signal, and the
loops that own one stop at their next boundary (the Monte Carlo between chunks; the sandbox pool's
loop is tested in tests/sandbox).  SIGTERM and SIGHUP are latched like it, named, and give the
shell's exit status."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from gpsaccel._interrupt import Stopped, exit_status, latched_sigint, latched_stop, why
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
    """The handler is put back as it was: Python's default_int_handler, or SIG_IGN where the
    suite itself was started with SIGINT ignored (a background job of a script)."""
    was = signal.getsignal(signal.SIGINT)
    with latched_sigint(raise_now=True) as latch:
        _lose_an_interrupt()
        assert dropped == [KeyboardInterrupt] and latch.signals == 1
        with pytest.raises(KeyboardInterrupt):
            latch.check()
    assert signal.getsignal(signal.SIGINT) is was  # put back


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


# ----------------------------------------------------------- SIGTERM and SIGHUP taken like Ctrl-C
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_stop_latch_records_each_stop_signal_and_raises_it_named(sig):
    before = [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)]
    with latched_stop(raise_now=False) as latch:
        os.kill(os.getpid(), sig)
        for _ in range(1000):
            pass
        assert latch and latch.signum == sig
    assert [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)] == \
        before  # put back
    with pytest.raises(KeyboardInterrupt) as info:
        latch.check("2 of 5 finished and kept")
    assert isinstance(info.value, Stopped) and info.value.signum == sig
    assert str(info.value) == f"{signal.Signals(sig).name}: 2 of 5 finished and kept"
    assert exit_status(info.value) == 128 + sig
    by = "" if sig == signal.SIGINT else f" by {signal.Signals(sig).name}"
    assert why(info.value) == f"{by}: 2 of 5 finished and kept"
    with pytest.raises(KeyboardInterrupt) as info:
        latch.check()  # nothing kept: Ctrl-C as Python raises it, the others named
    assert isinstance(info.value, Stopped) == (sig != signal.SIGINT) and why(info.value) == by


def test_the_exit_status_follows_the_signal_through_a_re_raise():
    try:
        try:
            raise Stopped(signal.SIGTERM)
        except KeyboardInterrupt:
            raise RuntimeError("the caller's own exception, raised from None") from None
    except RuntimeError as exc:
        assert exit_status(exc) == 143
    assert exit_status(KeyboardInterrupt()) == 130 and exit_status(None) == 130


_AFTER_CLEANUP = """
import os, signal, sys
from gpsaccel._interrupt import stop_after_cleanup
with stop_after_cleanup():
    try:
        os.kill(os.getpid(), signal.{sig})
        for _ in range(10 ** 6):
            pass
        print("not stopped")
    finally:
        print("cleaned up", flush=True)
print("went on")
"""


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_after_cleanup_the_process_ends_by_the_signal_it_got(sig):
    # the signal's default disposition, as a command started from a shell has it: a suite run
    # under nohup hands its children SIGHUP ignored, which stop_after_cleanup leaves alone
    code = (f"import signal\nsignal.signal(signal.{sig}, signal.SIG_DFL)\n"
            + _AFTER_CLEANUP.format(sig=sig))
    out = subprocess.run([sys.executable, "-c", code],
                         capture_output=True, text=True, timeout=120)
    assert out.stdout == "cleaned up\n" and out.returncode == -getattr(signal, sig), out


def test_after_cleanup_leaves_a_handler_the_process_set_alone():
    code = ("import signal\nsignal.signal(signal.SIGTERM, signal.SIG_IGN)\n"
            + _AFTER_CLEANUP.format(sig="SIGTERM"))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.stdout == "not stopped\ncleaned up\nwent on\n" and out.returncode == 0, out
