"""``gpsaccel check``'s exit status tells a student's failure from a check without a verdict
(:func:`gpsaccel.cli.checking.exit_status`; the reports' wording is in tests/check)."""

from __future__ import annotations

import pytest

from gpsaccel.cli.checking import FAILED, NO_VERDICT, PASSED, exit_status


def _r(passed, *codes):
    return {"passed": passed, "codes": list(codes)}


@pytest.mark.parametrize("results, status", [
    ([_r(True), _r(True)], PASSED),
    ([], PASSED),
    ([_r(True), _r(False, "std-as-variance")], FAILED),
    ([_r(True), _r(False, "machine-busy")], NO_VERDICT),
    ([_r(False, "machine-busy"), _r(False, "timeout")], FAILED),    # a real failure wins
    ([_r(False, "machine-busy", "timeout")], FAILED),                # one reason is the student's
    ([_r(False)], FAILED),                                           # failed, no code: not ours
    ([_r(None, "machine-busy")], NO_VERDICT),                        # no result at all
])
def test_exit_status(results, status):
    assert exit_status(results) == status


def test_the_statuses_are_distinct_and_not_argparses():
    assert len({PASSED, FAILED, NO_VERDICT, 2, 130}) == 5
