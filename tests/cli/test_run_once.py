"""``gpsaccel run`` computes report 000's single run and its Monte Carlo once: the figures get
the results the printed summary came from (passed, not found again in a cache)."""

from __future__ import annotations

from gpsaccel.calibration import montecarlo
from gpsaccel.cli import main
from gpsaccel.figures import runs


def test_run_computes_the_ensemble_and_the_single_run_once(tmp_path, monkeypatch):
    calls = {"monte_carlo": 0, "single_run": 0}
    real_mc, real_single = montecarlo.monte_carlo, runs.single_run

    def counted_mc(*args, **kwargs):
        calls["monte_carlo"] += 1
        return real_mc(*args, **kwargs)

    def counted_single(*args, **kwargs):
        calls["single_run"] += 1
        return real_single(*args, **kwargs)

    runs.ensemble.cache_clear()
    monkeypatch.setattr(runs, "monte_carlo", counted_mc)
    monkeypatch.setattr(runs, "single_run", counted_single)
    import gpsaccel.figures.r000 as r000

    monkeypatch.setattr(r000, "single_run", counted_single)
    assert main(["run", "--runs", "20", "--seed", "3", "--out", str(tmp_path)]) == 0
    assert calls == {"monte_carlo": 1, "single_run": 1}
