"""Report 004's figures, drawn once (10 runs, seed 2) for every test of the module: their legends
are checked in the draw that writes them."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def drawn(tmp_path_factory, legend_watch):
    """The figures drawn once and kept open, and write_figures over them (report 004's
    ``figures`` answering with copies of the records: write_figures closes what it saves); with
    what the legends' check found in the draw that wrote each (conftest's ``watch_legends``)."""
    import dataclasses

    import gpsaccel.figures.r004 as r004
    from gpsaccel.figures import iter_report, write_figures

    figs = list(iter_report("004", runs=10, seed=2))
    seen = [legend_watch(f.figure) for f in figs]
    asked = []

    def figures(runs, seed):
        asked.append((runs, seed))
        return iter([dataclasses.replace(f) for f in figs])

    out = tmp_path_factory.mktemp("r004")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(r004, "figures", figures)
        paths = write_figures(["004"], out, runs=10, seed=2, dpi=40)
    assert asked == [(10, 2)]
    return figs, paths, out, seen


def test_no_legend_lies_over_its_axes(drawn, legends_beside_axes):
    for fig, seen in zip(drawn[0], drawn[3], strict=True):
        legends_beside_axes(fig.figure, f"r004 fig {fig.number}", seen)


def test_report_004_figures(drawn):
    _, paths, out, _ = drawn
    names = [p.name for p in paths]
    assert len(names) == 14
    assert names[10] == "r004-fig11-difference-acceleration.png"
    assert (out / "index.html").read_text(encoding="utf-8").count("<figure>") == 14


def test_acceleration_difference_panels_show_accelerations(drawn):
    figs = {f.number: f for f in drawn[0]}
    labels = [ax.get_ylabel() for ax in figs["11"].figure.axes]
    assert labels == ["Δẍ (m/s²)", "Δÿ (m/s²)", "Δψ̈ (rad/s²)"]
