"""What a class's check builds once and shares between its files (:meth:`Problem.prepare`):
report 000's catalogue and its candidate filters, built and never run.  It must give every file
the report that file gets checked alone, and hold no result on the run's data, nor any filter's
covariance, whenever a student's box starts (docs/sandbox.md, "No answer exists while the
student runs")."""

from __future__ import annotations

import dataclasses
import json
import shutil

import numpy as np

from gpsaccel import sandbox as sb
from gpsaccel.check import batch
from gpsaccel.check import linear_diagnosis as ld
from gpsaccel.check.linear import COMBINED
from gpsaccel.check.problems import calibration as wf
from gpsaccel.classrun import check_many

# correct, mistaken (one each of a covariance entry, a mean entry, a combination, a schedule
# entry, an output mistake recognised before the catalogue) and one the catalogue cannot name
FILES = ("correct_covariance.py", "mutant_two_mistakes.py", "mutant_mean_not_propagated.py",
         "mutant_missing_propagation.py", "mutant_epoch_shift.py", "mutant_diagonal_q.py",
         "correct_information.py")


def _clear_shared() -> None:
    wf._default_catalogue.cache_clear()
    wf._default_candidate_filters.cache_clear()


def _without_seconds(result: dict) -> str:
    """A result as JSON, every field but the time it took (the one thing two checks differ in)."""
    r = {k: v for k, v in result.items() if k != "seconds"}
    r["details"] = {k: v for k, v in r["details"].items() if not k.endswith("seconds")}
    return json.dumps(r, sort_keys=True)


def test_a_class_sharing_its_part_gets_the_reports_of_each_file_checked_alone(tmp_path, hostile):
    paths = []
    for name in FILES:
        paths.append(tmp_path / name)
        shutil.copy(hostile.SUBMISSIONS / name, paths[-1])
    alone = []
    for p in paths:  # each file in a process that has built nothing before it
        _clear_shared()
        alone.append(batch.check_file(p, 3, 7, 60, problem="calibration"))
    _clear_shared()
    together = check_many(paths, n_runs=3, seed=7, timeout=60)  # a process per file, warmed
    in_process = check_many(paths, n_runs=3, seed=7, timeout=60, executor=None)
    assert wf._default_candidate_filters.cache_info().currsize == 1  # built once, by warm
    assert [r["codes"] for r in alone][:5] == [[], ["phi-sign", "x0-total-state"],
                                               ["mean-not-propagated"], ["missing-propagation"],
                                               ["epoch-shift"]]
    assert [_without_seconds(r) for r in together] == [_without_seconds(r) for r in alone]
    assert [_without_seconds(r) for r in in_process] == [_without_seconds(r) for r in alone]


def _snapshot(built: ld.CandidateFilters) -> list[dict]:
    """Every candidate filter's own attributes, arrays as bytes: what it holds, all of it."""
    return [{k: (v.tobytes(), v.shape) if isinstance(v, np.ndarray) else repr(v)
             for k, v in vars(f).items()} for f in built.filters]


def test_the_shared_part_holds_no_result_when_a_box_starts(monkeypatch, hostile):
    _clear_shared()
    batch.warm("calibration")  # as a class's check does before its boxes
    built = wf._default_candidate_filters(COMBINED)
    catalogue = wf._default_catalogue()
    fields = {f.name for f in dataclasses.fields(built.filters[0])}
    before = _snapshot(built)
    assert len(built.filters) > 1000 and all(set(vars(f)) == fields for f in built.filters)
    real_run, starts = sb.run, []

    def run(*args, **kwargs):
        # the same objects as before any file ran, each holding exactly its dataclass fields
        # (no gains, M, P or fast_gains cached on it) with the same bytes: built from the model
        # alone, before any data existed, and changed by nothing since
        assert wf._default_candidate_filters(COMBINED) is built and wf._default_catalogue() is catalogue
        assert all(set(vars(f)) == fields for f in built.filters)
        assert _snapshot(built) == before
        assert set(vars(catalogue)) <= {"model", "_covariance", "_mean", "_ingredients"}
        assert wf._candidates.cache_info().currsize == 0  # no candidate covariance either
        starts.append(True)
        return real_run(*args, **kwargs)

    monkeypatch.setattr(sb, "run", run)
    # each file's diagnosis runs candidates of the shared part, the next file's box then starts
    for name in ("mutant_two_mistakes.py", "mutant_std_as_variance.py",
                 "mutant_returns_a_priori.py", "correct_covariance.py"):
        report = wf.submission(hostile.SUBMISSIONS / name, n_runs=2)
        assert report.codes or name.startswith("correct")
    assert len(starts) == 4
    # and running every candidate the way a diagnosis does (those that update at every step
    # have their own loop) leaves nothing on them either
    fast = [c for c, f in enumerate(built.filters) if f.fast is not None]
    assert fast
    candidates = ld.Candidates(catalogue, COMBINED, built)
    candidates.head(ld.HEAD)
    P = candidates.rows(fast + [0, len(built.filters) - 1])
    assert np.array_equal(P[:len(fast)], ld._returned([built.filters[c] for c in fast]))
    assert _snapshot(built) == before
    assert all(set(vars(f)) == fields for f in built.filters)
