"""Commands that run longer than a few seconds show a tqdm bar on stderr when it is a terminal,
and print nothing extra when it is not (a log, a pipe, the tests)."""

from __future__ import annotations

import io

import pytest

from gpsaccel.coop.montecarlo import summary


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _replayed(monkeypatch, module, name: str, calls: list) -> None:
    """``module.name`` records its results into ``calls``; once recorded, it answers with them in
    the same order instead of computing them again."""
    real, played = getattr(module, name), iter(calls) if calls else None

    def fn(*args, **kwargs):
        if played is not None:
            return next(played)
        calls.append(real(*args, **kwargs))
        return calls[-1]

    monkeypatch.setattr(module, name, fn)


@pytest.mark.slow
def test_coop_summary_shows_a_bar_on_a_terminal_only(monkeypatch):
    """The summary computed once on a terminal; on a pipe the same summary (its filters' results
    replayed: what is shown does not depend on them) shows nothing."""
    import gpsaccel.coop.filters as filters
    import gpsaccel.coop.montecarlo as montecarlo

    recorded: dict[str, list] = {"truth_runs": [], "_tests": [], "run_filter": []}
    modules = {"truth_runs": montecarlo, "_tests": montecarlo, "run_filter": filters}
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    with monkeypatch.context() as mp:
        for name, calls in recorded.items():
            _replayed(mp, modules[name], name, calls)
        table = summary(n_runs=2, n_sets=1, seed=0, progress=True)
    shown = terminal.getvalue()
    # The bar opens at 0 of its total: 1 set simulated + 5 filters tested on it.  Its last step is
    # not asserted: tqdm draws a step only 0.1 s (mininterval) after the one before, and leave=False
    # clears the bar on close without drawing it, so "6/6" appears only when the UKF is slow (CI at
    # 2b85b4b failed on it).
    assert "coop" in shown and "0/6 [" in shown
    assert "coop" not in table  # the bar went to stderr, not into the table
    piped = io.StringIO()
    monkeypatch.setattr("sys.stderr", piped)
    with monkeypatch.context() as mp:
        for name, calls in recorded.items():
            _replayed(mp, modules[name], name, calls)
        assert summary(n_runs=2, n_sets=1, seed=0, progress=True).split("\n")[:-5] == \
            table.split("\n")[:-5]  # the replay is the same summary (but the timed runs)
    assert piped.getvalue() == ""


def test_figures_show_a_bar_of_the_figures_on_a_terminal_only(monkeypatch, tmp_path):
    """write_figures' bar, around a report of three empty figures (drawing a real report twice
    cost 20 CPU s; the reports' figures are tests/figures/')."""
    import time
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    import gpsaccel.figures as F
    from gpsaccel.figures import ReportFigure, write_figures

    def figures(runs, seed):
        for n in ("01", "02", "03"):
            time.sleep(0.15)  # longer than tqdm's mininterval (0.1 s): each figure is shown
            yield ReportFigure("001", n, "empty", "An empty figure.", plt.figure(figsize=(1, 1)))

    report = SimpleNamespace(DEFAULT_RUNS=2, TITLE="Report 001", figures=figures)
    monkeypatch.setattr(F, "report_module", lambda name: report)
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    paths = write_figures(["001"], tmp_path / "a", runs=2, progress=True)
    assert len(paths) == 3
    shown = terminal.getvalue()
    assert "figures" in shown and f"{len(paths)}/" not in shown  # a count, no total known ahead
    assert f"{len(paths)}figure" in shown.replace(" ", "") or f"{len(paths)} figure" in shown
    piped = io.StringIO()
    monkeypatch.setattr("sys.stderr", piped)
    write_figures(["001"], tmp_path / "b", runs=2, progress=True)
    assert piped.getvalue() == ""


def test_calibration_monte_carlo_shows_a_bar_on_a_terminal_only(monkeypatch):
    from gpsaccel.calibration.montecarlo import monte_carlo
    from gpsaccel.calibration.reports import report_model

    model = report_model("000").replace(duration=1.0)
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monte_carlo(model, 3, seed=0)
    shown = terminal.getvalue()
    assert "monte carlo (error-model)" in shown and "/3 [" in shown and "run/s" in shown
    piped = io.StringIO()
    monkeypatch.setattr("sys.stderr", piped)
    monte_carlo(model, 3, seed=0)
    monte_carlo(model, 3, seed=0, progress=False)
    assert piped.getvalue() == ""


@pytest.mark.slow
def test_calibration_monte_carlo_shows_the_notebook_bar_in_a_kernel(tmp_path):
    """In a Jupyter kernel (where stderr is never a terminal) a lesson's Monte Carlo cell shows
    tqdm's notebook bar, an ipywidgets view; with progress=False it shows nothing."""
    import nbformat

    from gpsaccel.lessons import execute

    pytest.importorskip("ipywidgets")
    setup = ("from gpsaccel.calibration.montecarlo import monte_carlo\n"
             "from gpsaccel.calibration.reports import report_model\n"
             "model = report_model('000').replace(duration=1.0)")
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(setup),
                                         nbformat.v4.new_code_cell("_ = monte_carlo(model, 3)"),
                                         nbformat.v4.new_code_cell(
                                             "_ = monte_carlo(model, 3, progress=False)")])
    path = tmp_path / "bar.ipynb"
    nbformat.write(nb, path)
    done = execute(path, timeout=120)
    widget = "application/vnd.jupyter.widget-view+json"
    shown = [[o for o in c.outputs if widget in o.get("data", {})] for c in done.cells]
    assert shown[1] and not shown[2], [c.outputs for c in done.cells]
    assert all(o.get("name") != "stderr" for c in done.cells for o in c.outputs)
