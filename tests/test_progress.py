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


@pytest.mark.slow
def test_figures_show_a_bar_of_the_figures_on_a_terminal_only(monkeypatch, tmp_path):
    from gpsaccel.figures import write_figures

    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    paths = write_figures(["001"], tmp_path / "a", runs=2, progress=True)
    shown = terminal.getvalue()
    assert "figures" in shown and f"{len(paths)}/" not in shown  # a count, no total known ahead
    assert f"{len(paths)}figure" in shown.replace(" ", "") or f"{len(paths)} figure" in shown
    piped = io.StringIO()
    monkeypatch.setattr("sys.stderr", piped)
    write_figures(["001"], tmp_path / "b", runs=2, progress=True)
    assert piped.getvalue() == ""
