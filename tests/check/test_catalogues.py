"""One catalogue interface for every system: each entry is the core's Mistake (code, variant,
message); the codes are the checker's canonical ones, the same the problems report."""

from __future__ import annotations

import re

import pytest

from gpsaccel import registry
from gpsaccel.calibration import mistakes as cal
from gpsaccel.check import problems
from gpsaccel.check.problems.tracker import TRACKER
from gpsaccel.coop import mistakes as coop
from gpsaccel.kalman.mistakes import Mistake
from gpsaccel.ship import mistakes as ship

CATALOGUES = {
    "calibration": cal.catalogue(),
    "coop-ekf": coop.catalogue(kind="ekf"),
    "coop-lkf": coop.catalogue(kind="lkf"),
    "ship": ship.catalogue(),
    "tracker": TRACKER.catalogue().catalogue(),
}


@pytest.mark.parametrize("name", sorted(CATALOGUES))
def test_every_entry_is_one_type_with_a_stable_code_and_a_message(name):
    for m in CATALOGUES[name]:
        assert isinstance(m, Mistake), (name, m)
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", m.code), m.code
        assert m.variant and len(m.message) > 60, m


def test_the_canonical_codes_are_the_checker_s():
    """Decided in issue 22: these names, not the homework's earlier ones."""
    codes = {m.code for c in CATALOGUES.values() for m in c}
    assert {"no-angle-wrap", "euler-propagation", "jacobian-point", "report-covariance"} <= codes
    assert not {"innovation-not-wrapped", "euler-prediction", "jacobian-at-previous",
                "zeroed-gain-short-form"} & codes


@pytest.mark.parametrize("name, catalogue", [("calibration", "calibration"), ("ship", "ship"),
                                             ("tracker", "tracker")])
def test_a_problem_reports_the_codes_of_its_system_s_catalogue(name, catalogue):
    assert set(problems.get(name).codes()) == {m.code for m in CATALOGUES[catalogue]}


def test_coop_reports_both_filters_codes():
    both = {m.code for m in CATALOGUES["coop-ekf"] + CATALOGUES["coop-lkf"] if m.checker}
    assert set(problems.get("coop").codes()) == both


#: The codes each problem printed before its system's filters were written once (issue 31):
#: they stay, in this order (issue 31's new codes may come between them).
CHECKER_CODES = {
    "calibration": ("phi-sign", "process-noise-interval", "m0-order", "first-update-skipped",
                    "predict-before-first-update", "returns-a-priori", "w-value",
                    "missing-propagation", "std-as-variance", "mean-not-propagated",
                    "x0-total-state"),
    "coop": ("no-angle-wrap", "no-state-wrap", "dt-linearization", "process-noise",
             "std-as-variance", "epoch-shift", "p-not-symmetric", "euler-propagation",
             "jacobian-point"),  # epoch-shift: the outputs a row late (y one row late: issue 40)
    "ship": ("zeroed-gain", "report-covariance", "monorate-gain", "no-input"),
    "tracker": ("phi-transposed", "q-without-gamma", "std-as-variance", "m0-order",
                "returns-a-priori", "first-update-skipped", "last-update-missing",
                "covariance-update-skipped", "predict-before-first-update",
                "missing-propagation", "mean-not-propagated"),
}


#: The codes added since, each an idea every system shares (issue 31's gaps, issue 40's list).
NEW_CODES = {"covariance-update-skipped", "update-every-step", "phi-sign", "state-order",
             "phi-transposed", "q-without-gamma", "last-update-missing", "process-noise",
             "process-noise-interval", "gamma-order", "residual-covariance", "joseph-sign",
             "prior-scale", "fixes-skipped", "measurement-late", "information-vector", "x0-wrong",
             "std-as-variance", "missing-as-zero", "input-shift", "epoch-shift", "jacobian-sign",
             "jacobian-blocks", "mean-not-propagated"}


@pytest.mark.parametrize("name", sorted(CHECKER_CODES))
def test_the_codes_a_problem_printed_are_unchanged(name):
    codes = problems.get(name).codes()
    assert tuple(c for c in codes if c in CHECKER_CODES[name]) == CHECKER_CODES[name], codes
    assert set(codes) - set(CHECKER_CODES[name]) <= NEW_CODES


#: Each idea every system shares (issue 40), and the problems whose catalogue has it: the same
#: code wherever it can occur (a linear problem, an instructor's own, the ship, coop).
SHARED = {
    "std-as-variance": ("calibration", "tracker", "ship", "coop"),
    "phi-sign": ("calibration", "tracker", "ship"),
    "process-noise-interval": ("calibration", "tracker"),
    "epoch-shift": ("ship", "coop"),  # the linear problems recognise it in what is returned
    "prior-scale": ("calibration", "tracker", "ship", "coop"),
    "residual-covariance": ("calibration", "tracker", "ship", "coop"),
    "joseph-sign": ("calibration", "tracker", "ship", "coop"),
    "process-noise": ("calibration", "tracker", "ship", "coop"),
    "gamma-order": ("calibration", "tracker"),
    "measurement-late": ("calibration", "tracker", "ship", "coop"),
    "fixes-skipped": ("calibration", "tracker", "ship"),
    "mean-not-propagated": ("calibration", "tracker", "coop"),
    "information-vector": ("calibration", "tracker"),
    "x0-wrong": ("calibration", "tracker", "ship"),
    "missing-as-zero": ("ship",),
    "input-shift": ("ship",),
    "jacobian-sign": ("coop",),
    "jacobian-blocks": ("coop",),
}


@pytest.mark.parametrize("code", sorted(SHARED))
def test_a_shared_idea_has_one_code_in_every_problem_it_can_occur_in(code):
    for name in SHARED[code]:
        assert code in problems.get(name).codes(), (code, name)


def test_the_homework_codes_are_catalogue_codes():
    from gpsaccel.assignments import coop as hw_coop
    from gpsaccel.assignments import ship as hw_ship

    assert [m.code for m in hw_coop.ekf_mistakes()] == ["no-angle-wrap", "euler-propagation",
                                                        "jacobian-point", "returns-a-priori"]
    assert [m.code for m in hw_ship.update_mistakes()] == ["zeroed-gain", "report-covariance",
                                                           "missing-as-zero"]


def test_every_registered_problem_names_its_system():
    for name in registry.problems():
        assert registry.entry(name).system, name
    assert set(registry.systems()) >= {"calibration", "coop", "ship", "tracker"}
