"""The held-out set of students' filters (tests/check/heldout/, issue 40): each gets the code its
file declares (or, where it says so, one of the generic codes it accepts), each right one passes.

Written as students write them, not as the tests' mutants, before the catalogues grew: at 779d581
7 of its 68 wrong filters were named, 55 got a generic code, 6 a wrong one (the table of
``python tests/check/heldout/confusion.py``).  The checks of one problem share its answers
(:func:`~.heldout.confusion.problem`); 79 boxes, so they are marked slow (``make test-all`` runs
them, ``make test-fast`` leaves them out).
"""

from __future__ import annotations

import pytest

from .heldout import confusion

ENTRIES = confusion.entries()


@pytest.fixture(scope="module")
def kept():
    return {}


@pytest.mark.slow
@pytest.mark.parametrize("entry", ENTRIES, ids=[e.name for e in ENTRIES])
def test_each_held_out_filter_gets_its_code(entry, kept):
    report = confusion.check(entry, kept)
    got = confusion.classify(entry, report)
    if entry.expect == "pass":
        assert got == "right", report
    elif entry.accept:  # its own code cannot be matched (its file says why)
        assert got == "generic", report
    else:
        assert got == "named", report


def test_the_set_is_as_large_as_the_issue_asks():
    wrong = [e for e in ENTRIES if e.expect != "pass"]
    assert len(wrong) >= 40 and len(ENTRIES) - len(wrong) >= 10
    assert {e.problem for e in ENTRIES} == set(confusion.PROBLEMS)


def test_the_docs_table_is_the_set_s():
    """docs/checker.md's "after" row: every wrong filter named but those that accept a generic
    code (each held to it above), none misnamed, no false pass or fail."""
    import re
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[2] / "docs" / "checker.md").read_text("utf-8")
    row = re.search(r"^\| after \| (\d+) \| (\d+) \| (\d+) \| (\d+) \| (\d+) \|$", doc, re.M)
    wrong = [e for e in ENTRIES if e.expect != "pass"]
    generic = sum(1 for e in wrong if e.accept)
    assert row and tuple(map(int, row.groups())) == (len(wrong) - generic, generic, 0, 0, 0)
