"""Report 002's figures: every listed figure (1-19) written, named, labelled with units, captioned."""

from __future__ import annotations

import re

import matplotlib
import pytest

from gpsaccel import registry
from gpsaccel.figures import write_figures
from gpsaccel.figures.r002 import ALL_NUMBERS, DEFAULT_RUNS

matplotlib.use("Agg")

NAME = re.compile(r"^r002-fig(\d{2}[a-z]?)-[a-z0-9]+(-[a-z0-9]+)*\.png$")
#: The figures the report lists (registered by gpsaccel.figures.r002), as the files number them;
#: the lettered ones go beyond the report.
LISTED = [n.zfill(2) for n in registry.report("002").figures]
EXTRA = ["08b", "14b", "15b", "14c", "15c", "18b", "19b", "19c"]


@pytest.fixture(scope="module")
def drawn(tmp_path_factory, legend_watch):
    """Report 002's figures drawn once (12 runs): written by write_figures, and kept open for
    the axes tests (write_figures closes what it writes: it gets copies of the records).  The
    legends are checked in the draw that writes each PNG (conftest's ``watch_legends``: a second
    draw of each figure was half of this file's time), at the PNG's dpi: the layout scales."""
    import dataclasses

    import gpsaccel.figures.r002 as r002

    out = tmp_path_factory.mktemp("r002")
    figs = list(r002.figures(12, 0))
    seen = {f.number: legend_watch(f.figure) for f in figs}
    asked = []

    def figures(runs, seed):
        asked.append((runs, seed))
        return iter([dataclasses.replace(f) for f in figs])

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(r002, "figures", figures)
        paths = write_figures(["002"], out, runs=12, seed=0, dpi=40)
    assert asked == [(12, 0)]
    return figs, paths, out, seen


def test_every_listed_figure_and_the_extras_are_written(drawn):
    _, paths, out, _ = drawn
    numbers = []
    for p in paths:
        m = NAME.match(p.name)
        assert m, p.name
        numbers.append(m.group(1))
        assert p.stat().st_size > 5_000, f"{p.name} looks empty"
    assert sorted(numbers) == sorted(LISTED + EXTRA)
    assert tuple(f.number for f in drawn[0]) == ALL_NUMBERS  # the order figures() keeps
    index = (out / "index.html").read_text(encoding="utf-8")
    assert index.count("<figcaption>") == len(paths)
    assert DEFAULT_RUNS == 100  # the report's EKF Monte Carlo size


def test_every_axes_has_labels_with_units_and_every_figure_a_caption(drawn):
    figs = drawn[0]
    for fig in figs:
        assert fig.caption.strip()
        for ax in fig.figure.axes:
            where = f"fig {fig.number} axes {ax.get_title()!r}"
            assert re.search(r"\(.+\)", ax.get_ylabel()), f"{where}: y label without unit"
            siblings = ax.get_shared_x_axes().get_siblings(ax)
            assert any(s.get_xlabel().strip() for s in siblings), f"{where}: no x label"


def test_no_legend_lies_over_its_axes(drawn, legends_beside_axes):
    for fig in drawn[0]:   # as write_figures drew it (a figure never drawn fails)
        legends_beside_axes(fig.figure, f"r002 fig {fig.number}", drawn[3][fig.number])


def test_captions_carry_the_measured_numbers(drawn):
    figs = drawn[0]
    by_number = {f.number: f for f in figs}
    assert re.search(r"\d+\.\d% of steps inside", by_number["14"].caption)
    assert "Q = diag(" in by_number["14"].caption
    assert re.search(r"NIS time-average \d+\.\d\d", by_number["18"].caption)


def test_a_lesson_that_stops_after_figure_09_runs_the_lkf_alone(monkeypatch):
    # lesson 10b draws figures 01-09: the EKFs and the UKF of figures 10-15c must not run for it
    import gpsaccel.figures.r002 as r002

    ran = []
    real = r002.consistency_test

    def spy(model, method, *args, **kwargs):
        ran.append(method)
        return real(model, method, *args, **kwargs)

    monkeypatch.setattr(r002, "consistency_test", spy)
    for f in r002.figures(3, 0, numbers=("09", "10")):   # (01-08b: only drawing, no filter)
        if f.number == "09":
            break
    assert ran == ["lkf"]
    assert sorted(r002.monte_carlo(r002.CoopModel(), 3, 0)) == ["ekf", "ekf-qtrue", "lkf", "ukf"]


def _data(fig):
    """What a figure shows: every line's and filled region's points, and the axes' labels."""
    out = []
    for ax in fig.axes:
        out += [line.get_xydata().tobytes() for line in ax.get_lines()]
        out += [p.vertices.tobytes() for c in ax.collections for p in c.get_paths()]
        out.append((ax.get_title(), ax.get_xlabel(), ax.get_ylabel()))
    return out


def test_figures_asked_for_by_number_are_those_of_the_whole_report_and_need_only_their_filters(
        drawn, monkeypatch):
    # lessons 10b, 11 and 11b draw only the figures they show (11b: no Monte Carlo set at all)
    import gpsaccel.figures.r002 as r002

    ran = []
    real = r002.consistency_test
    monkeypatch.setattr(r002, "consistency_test",
                        lambda model, method, Q=None, **kw: ran.append(method) or
                        real(model, method, Q, **kw))
    whole = {f.number: f for f in drawn[0]}
    some = list(r002.figures(12, 0, numbers=("19c", "08b", "14b")))
    assert [f.number for f in some] == ["08b", "14b", "19c"]   # the report's order
    assert ran == ["ekf"]                                         # 14b's EKF with Q = Qtrue
    for f in some:
        assert (f.caption, f.slug) == (whole[f.number].caption, whole[f.number].slug)
        assert _data(f.figure) == _data(whole[f.number].figure), f.number
    with pytest.raises(ValueError, match="numbers must be one of"):
        next(r002.figures(12, 0, numbers=("8b",)))


def test_filters_run_already_are_used_not_run_again_and_must_be_those_of_the_set(
        drawn, monkeypatch):
    # lesson 11 hands its two EKFs on its own set (seed 7) to the figures: nothing is filtered
    # twice, and the figures are those the report draws when it filters them itself
    import dataclasses

    import gpsaccel.figures.r002 as r002
    from gpsaccel.coop.montecarlo import consistency_test, truth_runs

    model = r002.CoopModel()
    truth = truth_runs(model, 12, 0)
    plain = consistency_test(model, "ekf", model.Qtrue, truth=truth, keep=True)
    ran = []
    monkeypatch.setattr(r002, "consistency_test", lambda *a, **kw: ran.append(a[1]))
    whole = {f.number: f for f in drawn[0]}
    some = list(r002.figures(12, 0, numbers=("14b", "15b"), done={"ekf-qtrue": plain}))
    assert ran == []
    for f in some:
        assert f.caption == whole[f.number].caption
        assert _data(f.figure) == _data(whole[f.number].figure), f.number
    moved = r002.Truth(truth.t, truth.x + 1.0, truth.y)
    other = dataclasses.replace(plain, truth=moved)           # as if filtered on another set
    for done in ({"ekf-qtrue": other}, {"ekf": plain}, {"ukf": plain}):   # another set, another Q
        with pytest.raises(ValueError, match=r"done\["):
            next(r002.figures(12, 0, numbers=("14b",), done=done))
    with pytest.raises(ValueError, match="done must be one of"):
        next(r002.figures(12, 0, numbers=("14b",), done={"pf": plain}))


def test_the_log_filters_given_are_used_not_run_again_and_must_be_those_on_the_log(
        drawn, monkeypatch):
    # lesson 11b runs the three filters on the course log itself (and times them), then draws
    # figures 16-19c from them: the report's figures, with no filter run twice
    import dataclasses

    import gpsaccel.figures.r002 as r002

    model = r002.CoopModel()
    logs = r002.on_the_log(model)
    monkeypatch.setattr(r002, "on_the_log", lambda model: pytest.fail("ran the log's filters"))
    whole = {f.number: f for f in drawn[0]}
    some = list(r002.figures(12, 0, numbers=("17", "19c"), log=logs))
    for f in some:
        assert f.caption == whole[f.number].caption
        assert _data(f.figure) == _data(whole[f.number].figure), f.number
    bent = dataclasses.replace(logs["ekf"], x_hat=logs["ekf"].x_hat + 1e-12)
    for log in ({**logs, "ekf": bent}, {"lkf": logs["lkf"], "ekf": logs["ekf"]},
                {**logs, "ukf": logs["ekf"]}):
        with pytest.raises(ValueError, match=r"log\["):
            next(r002.figures(12, 0, numbers=("16",), log=log))


def test_an_executor_filters_the_monte_carlo_at_once_with_the_same_numbers():
    # lessons 11 and 11b pass a pool: the four filters are submitted together, awaited when drawn
    import concurrent.futures as cf

    import numpy as np

    from gpsaccel.coop.montecarlo import truth_runs
    from gpsaccel.figures import r002

    model = r002.CoopModel(duration=2.0)
    truth = truth_runs(model, 3, 0)
    with cf.ThreadPoolExecutor(2) as pool:
        pooled = r002._MonteCarlo(model, truth, executor=pool)
        assert sorted(pooled.futures) == ["ekf", "ekf-qtrue", "lkf", "ukf"]
        here = r002._MonteCarlo(model, truth)
        for m in pooled.futures:
            assert np.array_equal(pooled[m].nees_mean, here[m].nees_mean), m
            assert np.array_equal(pooled[m].result.x_hat, here[m].result.x_hat), m


def test_an_executor_starts_only_the_filters_asked_for_and_the_rest_run_when_drawn():
    # lesson 11 stops at figure 15b: the UKF (five EKFs' cost) is not started on its pool
    import concurrent.futures as cf

    import numpy as np
    import pytest

    from gpsaccel.coop.montecarlo import truth_runs
    from gpsaccel.figures import r002

    model = r002.CoopModel(duration=2.0)
    truth = truth_runs(model, 3, 0)
    with cf.ThreadPoolExecutor(2) as pool:
        some = r002._MonteCarlo(model, truth, executor=pool, filters=("ekf", "lkf", "ekf"))
        assert sorted(some.futures) == ["ekf", "lkf"]
        assert np.array_equal(some["ukf"].result.x_hat, r002._MonteCarlo(model, truth)["ukf"]
                              .result.x_hat)  # not started: run here when asked for
        with pytest.raises(ValueError, match="filters must be one of"):
            r002._MonteCarlo(model, truth, executor=pool, filters=("ukf", "pf"))
