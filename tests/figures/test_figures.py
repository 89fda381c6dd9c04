"""Every figure of reports 000, 001 and 003: written under the right names, labelled, indexed."""

from __future__ import annotations

import itertools
import re

import matplotlib
import pytest

from gpsaccel import registry
from gpsaccel.cli import main
from gpsaccel.figures import iter_report, write_figures

matplotlib.use("Agg")

#: What the files number beyond the figures each report lists (registry.report(r).figures): report
#: 000 draws a zoom of figure 7 (07b); report 001's two figures 10 are 10a (gains) and 10b (the
#: ensemble average).
EXTRA = {"000": ("07b",)}
SPLIT = {"001": {"10": ("10a", "10b")}}


def _file_numbers(report: str) -> list[str]:
    """The figure numbers of ``report``'s files, in order: the registered list, zero-padded."""
    out = list(EXTRA.get(report, ()))
    for n in registry.report(report).figures:
        padded = n.zfill(2) if n[-1].isdigit() else n[:-1].zfill(2) + n[-1]
        out += SPLIT.get(report, {}).get(n, (padded,))
    return sorted(out)


#: The calibration reports (002 and 004 have tests of their own).
EXPECTED = {r: _file_numbers(r) for r in ("000", "001", "003")}
RUNS = 30
NAME = re.compile(r"^r(\d{3})-fig(\d{2}[a-z]?)-[a-z0-9]+(-[a-z0-9]+)*\.png$")


@pytest.fixture(scope="module")
def drawn() -> dict[str, list]:
    """Each report's figures drawn once (RUNS runs, seed 0) and kept open: the files below are
    written from them and the axes tests read them."""
    return {r: list(iter_report(r, runs=RUNS, seed=0)) for r in EXPECTED}


@pytest.fixture(scope="module")
def legend_checks(drawn, legend_watch) -> dict[str, list[dict]]:
    """What the legends' check found when each ``drawn`` figure was drawn to be written
    (conftest's ``watch_legends``; ``written`` draws them)."""
    return {r: [legend_watch(f.figure) for f in figs] for r, figs in drawn.items()}


@pytest.fixture(scope="module")
def written(tmp_path_factory, drawn, legend_checks):
    """write_figures over the three reports, each report's ``figures`` answering with copies of
    the ``drawn`` records (write_figures closes what it saves)."""
    import dataclasses

    from gpsaccel.figures import report_module

    out = tmp_path_factory.mktemp("figures")
    asked = []
    with pytest.MonkeyPatch.context() as mp:
        for report, figs in drawn.items():
            def figures(runs, seed, report=report, figs=figs):
                asked.append((report, runs, seed))
                return iter([dataclasses.replace(f) for f in figs])

            mp.setattr(report_module(report), "figures", figures)
        paths = write_figures(list(EXPECTED), out, runs=RUNS, seed=0, dpi=40)
    assert asked == [(r, RUNS, 0) for r in EXPECTED]
    return out, paths


def test_one_png_per_listed_figure_named_by_report_and_number(written):
    out, paths = written
    got: dict[str, list[str]] = {}
    for p in paths:
        m = NAME.match(p.name)
        assert m, f"bad figure file name {p.name}"
        got.setdefault(m.group(1), []).append(m.group(2))
        assert p.stat().st_size > 5_000, f"{p.name} looks empty"
    assert got == EXPECTED
    assert sorted(out.glob("*.png")) == sorted(paths)


def test_named_sub_figures(written):
    names = {p.name for p in written[1]}
    for name in ("r000-fig03b-bias-error-zoom.png", "r000-fig07-pave-minus-p.png",
                 "r001-fig10a-gains.png", "r001-fig10b-ensemble-mean-error.png",
                 "r001-fig11-pave-minus-p.png", "r001-fig12-orthogonality.png",
                 "r003-fig01-system-diagram.png"):
        assert name in names


def test_index_lists_every_figure_with_its_caption(written):
    out, paths = written
    index = (out / "index.html").read_text(encoding="utf-8")
    for p in paths:
        assert f"src='{p.name}'" in index
    assert index.count("<figcaption>") == len(paths)
    assert f"{RUNS} Monte Carlo runs" in index


@pytest.mark.parametrize("report", list(EXPECTED))
def test_every_axes_is_labelled(report, drawn, legend_checks, written, legends_beside_axes):
    for fig, seen in zip(drawn[report], legend_checks[report], strict=True):
        assert fig.caption.strip()
        for ax in fig.figure.axes:
            if not ax.axison:  # the system diagram: blocks and arrows, no axes
                assert fig.number == "01" and report == "003"
                continue
            where = f"r{report} fig {fig.number} axes {ax.get_title()!r}"
            ylabel = ax.get_ylabel()
            assert ylabel.strip(), f"{where}: no y label"
            assert re.search(r"\(.+\)", ylabel), f"{where}: y label {ylabel!r} has no unit"
            siblings = ax.get_shared_x_axes().get_siblings(ax)
            assert any(s.get_xlabel().strip() for s in siblings), f"{where}: no x label"
        legends = [ax.get_legend() for ax in fig.figure.axes if ax.get_legend() is not None]
        for leg in legends:
            assert all(t.get_text().strip() for t in leg.get_texts())
        legends_beside_axes(fig.figure, f"r{report} fig {fig.number}", seen)  # as written



def test_the_legend_check_sees_a_legend_over_its_axes(tmp_path, legend_watch,
                                                      legends_beside_axes):
    """The check above, in the draw that writes a figure and without it, catches a legend inside
    its axes and passes one beside them."""
    import matplotlib.pyplot as plt

    from gpsaccel.plots import outside_legend

    for place, over in ((lambda ax: ax.legend(loc="center"), True), (outside_legend, False)):
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.plot([0, 1], [0, 1], label="a line")
        ax.set_title("t")
        place(ax)
        seen = legend_watch(fig)
        fig.savefig(tmp_path / "f.png", dpi=40)
        for where, checked in (("as written", seen), ("drawn again", None)):
            if over:
                with pytest.raises(AssertionError, match="lies over the axes 't'"):
                    legends_beside_axes(fig, where, checked)
            else:
                legends_beside_axes(fig, where, checked)
        plt.close(fig)


def test_figures_are_reproducible_from_the_seed(drawn):
    """Report 001's ninth figure drawn again from seed 0 is the ``drawn`` one; from seed 4 not."""
    def lines(fig):
        return [line.get_ydata().copy() for ax in fig.figure.axes for line in ax.get_lines()]

    def data(seed):
        return lines(next(itertools.islice(iter_report("001", runs=RUNS, seed=seed), 8, None)))

    a, b, c = lines(drawn["001"][8]), data(0), data(4)
    assert all((x == y).all() for x, y in zip(a, b, strict=True))
    assert any((x != y).any() for x, y in zip(a, c, strict=True))


def test_cli_figures_one_report(tmp_path, capsys):
    assert main(["figures", "--report", "003", "--out", str(tmp_path), "--runs", "10"]) == 0
    assert len(list(tmp_path.glob("r003-fig*.png"))) == len(EXPECTED["003"])
    assert (tmp_path / "index.html").exists()
    assert "wrote 6 figures" in capsys.readouterr().out


def test_cli_figures_rejects_an_unknown_report(tmp_path, capsys):
    assert main(["figures", "--report", "999", "--out", str(tmp_path)]) == 2
    assert "report must be one of" in capsys.readouterr().err


# `gpsaccel run` writes report 000's figures (EXPECTED["000"], NAME): asserted on the run that
# tests/test_packaging.py::test_the_main_job_needs_only_the_core makes with the core alone.
