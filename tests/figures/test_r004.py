"""Report 004's figures."""

from __future__ import annotations


def test_no_legend_lies_over_its_axes(legends_beside_axes):
    from gpsaccel.figures import iter_report

    for fig in iter_report("004", runs=10, seed=2):
        legends_beside_axes(fig.figure, f"r004 fig {fig.number}")


def test_report_004_figures(tmp_path):
    from gpsaccel.figures import write_figures

    paths = write_figures(["004"], tmp_path, runs=10, seed=2, dpi=40)
    names = [p.name for p in paths]
    assert len(names) == 14
    assert names[10] == "r004-fig11-difference-acceleration.png"
    assert (tmp_path / "index.html").read_text(encoding="utf-8").count("<figure>") == 14


def test_acceleration_difference_panels_show_accelerations():
    from gpsaccel.figures.r004 import figures

    figs = {f.number: f for f in figures(5, 0)}
    labels = [ax.get_ylabel() for ax in figs["11"].figure.axes]
    assert labels == ["Δẍ (m/s²)", "Δÿ (m/s²)", "Δψ̈ (rad/s²)"]
