"""Commands that run longer than a few seconds show a tqdm bar on stderr when it is a terminal,
and print nothing extra when it is not (a log, a pipe, the tests)."""

from __future__ import annotations

import io

import pytest

from gpsaccel.coop.montecarlo import summary


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.mark.slow
def test_coop_summary_shows_a_bar_on_a_terminal_only(monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    table = summary(n_runs=2, n_sets=1, seed=0, progress=True)
    shown = terminal.getvalue()
    assert "coop" in shown and "6/6" in shown  # 1 set simulated + 5 filters tested on it
    assert "coop" not in table  # the bar went to stderr, not into the table
    piped = io.StringIO()
    monkeypatch.setattr("sys.stderr", piped)
    summary(n_runs=2, n_sets=1, seed=0, progress=True)
    assert piped.getvalue() == ""
