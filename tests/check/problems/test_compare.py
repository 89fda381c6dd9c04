"""check.problems.compare: the nearest catalogue entry, found from every candidate's first rows
and whole runs of only those still in play, is the exhaustive search's whenever a check reads it;
and the coop and ship filters' first rows are those rows of their whole runs, bit for bit (what
makes the first rows' distance a lower bound)."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.check.problems.compare import HEAD, _ratio, nearest_within


def _exhaustive(cands, x, P, P_ref, tol_x, tol_P):
    """The definition: every candidate run in full, the nearest (the earlier one on a tie)."""
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    best, best_d = None, np.inf
    for i, (xm, Pm) in enumerate(cands):
        d = _ratio(xm, Pm, x, P, sd, tol_x, tol_P)
        if d < best_d:
            best, best_d = i, d
    return None if best is None else (best, best_d)


def _candidates(rng, n_cand, scale, runs=2, rows=60, n=3):
    """A student's (x, P), the reference P, and candidates departing from the student at random
    rows by random amounts (some never, some equal to each other: ties)."""
    x = rng.normal(size=(runs, rows, n))
    A = rng.normal(size=(rows, n, n))
    P_ref = np.broadcast_to(A @ np.swapaxes(A, -1, -2) + np.eye(n), (runs, rows, n, n)).copy()
    P = P_ref.copy()
    cands = []
    for _ in range(n_cand):
        xm, Pm = x.copy(), P.copy()
        start = int(rng.integers(0, rows + 1))
        xm[:, start:] += rng.choice([0, 1, -1]) * scale * rng.random() * rng.random(
            (runs, rows - start, n))
        Pm[:, start:] += scale * rng.random() * rng.random((runs, rows - start, n, n))
        cands.append((xm, Pm))
    if n_cand > 3:
        cands[2] = cands[1]  # a tie: the earlier one wins
    if n_cand > 4 and rng.random() < 0.5:
        cands[3][0][:, :HEAD] = np.nan  # no bound from the first rows
    return x, P, P_ref, cands


@pytest.mark.filterwarnings("ignore:All-NaN slice:RuntimeWarning")
@pytest.mark.parametrize("seed", range(40))
def test_the_pruned_search_finds_what_the_exhaustive_one_finds(seed):
    rng = np.random.default_rng(seed)
    scale = [1e-7, 1e-6, 1e-5, 1e-4][seed % 4]
    x, P, P_ref, cands = _candidates(rng, 1 + seed % 9, scale)
    tol_x, tol_P = 1e-6, 2e-6
    runs: list[tuple[int, int | None]] = []

    def run(i, steps):
        runs.append((i, steps))
        xm, Pm = cands[i]
        return (xm, Pm) if steps is None else (xm[:, :steps], Pm[:, :steps])

    full = _exhaustive(cands, x, P, P_ref, tol_x, tol_P)
    found = nearest_within(list(range(len(cands))), run, x, P, P_ref, tol_x, tol_P)
    assert full is not None
    if full[1] <= 10.0:
        assert found == full
    else:
        assert found is None
    assert all(steps in (HEAD, None) for _, steps in runs)


def test_only_the_candidates_in_play_run_in_full():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(2, 60, 3))
    P = np.broadcast_to(np.eye(3), (2, 60, 3, 3)).copy()
    late = x.copy()
    late[:, 50:] += 1e-3  # departs after the first rows: its bound is 0, it must run in full
    cands = [(x + 1.0, P), (late, P), (x.copy(), P.copy()), (x + 1e-5, P)]
    whole: list[int] = []

    def run(i, steps):
        if steps is None:
            whole.append(i)
            return cands[i]
        return cands[i][0][:, :steps], cands[i][1][:, :steps]

    assert nearest_within(list(range(4)), run, x, P, P, 1e-6, 1e-6) == (2, 0.0)
    assert whole == [1, 2]  # the bounds 0, 0 first (in order); 10 and 1e6 tolerances: pruned


def test_coop_filters_first_rows_are_their_whole_runs_rows():
    from gpsaccel.coop import mistakes as cm
    from gpsaccel.coop.filters import run_batch
    from gpsaccel.coop.model import CoopModel

    model = CoopModel()
    y = model.log()[None]
    entries = {m.code: m for m in cm.catalogue(model, "ekf")}
    for kind, mistakes in [("lkf", ()), ("ekf", (entries["epoch-shift"],))]:
        whole = run_batch(kind, model, y, ingredients=cm.ingredients(mistakes))
        first = run_batch(kind, model, y, ingredients=cm.ingredients(mistakes), steps=HEAD)
        for name in ("x_hat", "P", "x_bar", "M"):
            np.testing.assert_array_equal(getattr(first, name), getattr(whole, name)[:, :HEAD])
        np.testing.assert_array_equal(first.t, model.t[:HEAD])


def test_ship_filters_first_rows_are_their_whole_runs_rows():
    from gpsaccel.check.problems.ship import ShipProblem
    from gpsaccel.ship.mistakes import variants

    problem = ShipProblem()
    cases = problem.cases(2, 0)
    for v in variants()[-1:]:  # every mistake at once, the monorate gain among them
        whole = problem.run_variant(cases, v)
        first = problem.run_variant(cases, v, HEAD)
        for a, b in zip(first, whole, strict=True):
            np.testing.assert_array_equal(a, b[:, :HEAD])
    problem.forget()
