"""The sandbox's outcomes are worded in one table: the checker's findings, the homework grader's
stop clause and the batch's lost checks all read gpsaccel.sandbox.outcomes.OUTCOMES."""

from __future__ import annotations

from pathlib import Path

from gpsaccel import sandbox as sb
from gpsaccel.assignments import scoring
from gpsaccel.check import batch, findings
from gpsaccel.sandbox.outcomes import OUTCOMES

#: Every failure a box reports (gpsaccel.sandbox's docstring and the runner's problems).
FAILURES = ("timeout", "memory-limit", "output-limit", "file-limit", "process-limit",
            "uses-checker", "result-refused", "crashed", "import-error", "no-function",
            "exception", "return-value", "not-numeric", "wrong-shape", "machine-busy")


def test_every_failure_has_its_wording_and_the_checker_reads_it():
    for code in FAILURES:
        assert OUTCOMES[code].finding, code
        assert findings.MESSAGES[code] == OUTCOMES[code].finding, code


def test_the_grader_stops_with_the_tables_clause():
    stops = {c for c, o in OUTCOMES.items() if o.stop}
    assert stops == {"timeout", "memory-limit", "process-limit", "output-limit", "file-limit",
                     "crashed", "result-refused", "uses-checker", "machine-busy"}
    for code in stops:
        assert scoring._STOPS[code] == OUTCOMES[code].stop


def test_a_lost_check_is_worded_by_the_table():
    for reason in ("error", "not-a-report", "too-long", "died"):
        out = batch._lost(Path("alice.py"), sb.Lost(reason, "signal SIGKILL"), 30.0)
        want = OUTCOMES[f"lost.{reason}"].finding.format(detail="signal SIGKILL",
                                                        limit=30.0 + batch.CHECK_SLACK,
                                                        slack=batch.CHECK_SLACK)
        assert want in str(out), (reason, out)
