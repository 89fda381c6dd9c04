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
             "jacobian-point"),
    "ship": ("zeroed-gain", "report-covariance", "monorate-gain", "no-input"),
    "tracker": ("phi-transposed", "q-without-gamma", "std-as-variance", "m0-order",
                "returns-a-priori", "first-update-skipped", "last-update-missing",
                "covariance-update-skipped", "predict-before-first-update",
                "missing-propagation", "mean-not-propagated"),
}


@pytest.mark.parametrize("name", sorted(CHECKER_CODES))
def test_the_codes_a_problem_printed_are_unchanged(name):
    codes = problems.get(name).codes()
    assert tuple(c for c in codes if c in CHECKER_CODES[name]) == CHECKER_CODES[name], codes
    new = set(codes) - set(CHECKER_CODES[name])
    assert new <= {"covariance-update-skipped", "update-every-step", "phi-sign", "state-order"}


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
