"""The catalogue half of the linear checker (:mod:`gpsaccel.check.linear`): the cases, the
optimal answer, and the match of a student's (x̂, P) against a catalogue's candidate filters.

P does not depend on the data, so :func:`candidates` computes the covariance of every covariance
entry and every combination of up to three that touch different ingredients once (stacked,
:func:`gpsaccel.kalman.epochs.batch_gains`); :func:`diagnose` ranks them by run 0's P, confirms a
match on every run, then matches x̂ against the matched entry with each combination of the mean
entries.  Nothing here words a finding: :class:`gpsaccel.check.linear.LinearProblem` does.

The checker computes them after each box (no answer is kept while a student's code runs), so
:class:`Candidates` computes only what the diagnosis reads: every candidate's first
:data:`HEAD` epochs, whose distance to run 0's P is a lower bound of its whole distance, then
whole runs only of the candidates that bound leaves in play (for report 000 a few of its
thousands).  The result is the diagnosis of the whole stack, bit for bit: a candidate's
rows are the same whichever candidates share its stack, and the maximum of some of the same
numbers is the maximum of all of them or below it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gpsaccel.kalman.consistency import covariance_distance
from gpsaccel.kalman.epochs import EpochFilter, batch_gains
from gpsaccel.kalman.linear_model import shared_transitions
from gpsaccel.kalman.mistakes import Catalogue, Mistake, combinations

#: Largest distance (units of the optimal σ) at which P and x̂ count as equal; also the distance
#: within which a catalogue entry counts as matching.
TOLERANCE = 1e-6

#: Epochs of every candidate computed first, to bound its distance from below (:class:`Candidates`).
HEAD = 8

#: What a match allows beyond the tolerance, ROUNDING·√|P_c,ii P_c,jj|, from the first row where
#: a candidate's P runs away (a variance ≤ 0, or one beyond RUNAWAY times the optimal filter's):
#: a mistaken filter that runs away (Joseph's form with a minus: negative variances at the first
#: fix, P at 1e10 times the optimal after a few) computes the same numbers in another order only
#: to about 1e-6 of their size (measured on report 000's), far beyond the tolerance in units of
#: the optimal σ.  A candidate that stays a covariance in the optimal filter's range (σ for σ²
#: gives 25 times a variance) gets no allowance, so a filter 2e-7 from one still reads as near
#: it, not as it.  The row decides from the rows up to it, so a candidate's first rows bound its
#: whole distance from below (:class:`Candidates`) as before.
ROUNDING = 1e-5
RUNAWAY = 1e3

#: The same for x̂, relative to |x̂_c| (rounding only: a mean that runs away, 1e100, is matched
#: to 1e-9 of itself).
ROUNDING_X = 1e-9


def match_distance(P: np.ndarray, P_c: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """|P − P_c|_ij / (σ_i σ_j) elementwise (σ = ``sd``, the optimal filter's), less the
    :data:`ROUNDING` allowance from where the candidate has run away (never below 0).  P_c
    (..., rows, n, n), rows the second-to-last axis of its leading ones."""
    var = np.diagonal(P_c, axis1=-2, axis2=-1)                     # (..., rows, n)
    s = np.sqrt(np.abs(var))
    scale = sd[..., :, None] * sd[..., None, :]
    with np.errstate(invalid="ignore", over="ignore"):
        away = (var <= 0).any(axis=-1) | (var > RUNAWAY * sd**2).any(axis=-1)
        away = np.logical_or.accumulate(away, axis=-1)            # from that row on
        slack = np.where(away[..., None, None], ROUNDING * s[..., :, None] * s[..., None, :], 0.0)
        return np.maximum(covariance_distance(P, P_c, sd) - slack / scale, 0.0)


def mean_distance(x: np.ndarray, x_c: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """|x̂ − x̂_c| / σ less the :data:`ROUNDING_X` allowance of |x̂_c| (never below 0)."""
    with np.errstate(invalid="ignore", over="ignore"):
        return np.maximum((np.abs(x - x_c) - ROUNDING_X * np.abs(x_c)) / sd, 0.0)


@dataclass(frozen=True, eq=False)
class Cases:
    """The realizations a check runs on (no answer in it): z (n_runs, n_epochs, p) and the true
    states x_true (n_runs, n_epochs, n)."""

    seed: int
    z: np.ndarray
    x_true: np.ndarray


@dataclass(frozen=True, eq=False)
class Answer:
    """The optimal filter on the cases: x_ref (n_runs, n_epochs, n), P_ref (n_epochs, n, n),
    sd = √diag P_ref."""

    x_ref: np.ndarray
    P_ref: np.ndarray
    sd: np.ndarray


def answer(flt: EpochFilter, z: np.ndarray) -> Answer:
    """The filter ``flt`` (the optimal one) run on z."""
    x_ref, P_ref = flt.apply(z)
    return Answer(x_ref, P_ref, np.sqrt(np.diagonal(P_ref, axis1=1, axis2=2)))


@dataclass(frozen=True)
class Diagnosis:
    """The catalogue entries that reproduce the student's (x̂, P), or the nearest P entry."""

    covariance: tuple[Mistake, ...] | None
    mean: tuple[Mistake, ...] | None
    nearest: tuple[Mistake, ...] | None
    nearest_distance: float


def _combinations(catalogue: Catalogue, max_combined: int) -> list[tuple[Mistake, ...]]:
    cov = catalogue.covariance_mistakes()
    combos: list[tuple[Mistake, ...]] = [()]
    for k in range(1, max_combined + 1):
        combos += list(combinations(cov, k))
    return combos


def _returned(filters: Sequence[EpochFilter], n_epochs: int | None = None) -> np.ndarray:
    """The covariance each filter returns (P, or M with ``output="prior"``), stacked."""
    _, M, P = batch_gains(filters, n_epochs)
    prior = np.array([f.output == "prior" for f in filters])
    return np.where(prior[:, None, None, None], M, P)


def candidates(catalogue: Catalogue, max_combined: int
               ) -> tuple[list[tuple[Mistake, ...]], np.ndarray]:
    """Every covariance entry and combination of up to ``max_combined`` (the first is the optimal
    filter, ``()``) and the covariance each returns, (C, n_epochs, n, n)."""
    c = Candidates(catalogue, max_combined)
    return c.combos, _returned(c.filters)


@dataclass(frozen=True, eq=False)
class CandidateFilters:
    """Every candidate of :func:`candidates` (``combos``, the first ``()``) and its filter, built
    and never run: the model's matrices changed by each combination (Φⁿ, Q_e, H, V, M0, x0 and
    the recursion's switches), no gain, covariance or estimate.  What every file's diagnosis
    shares, so a class builds it once (:meth:`gpsaccel.check.problem.Problem.prepare`) before
    its boxes; running a candidate makes a :class:`Candidates` of its own, and
    :func:`gpsaccel.kalman.epochs.batch_gains` caches nothing on a filter it runs."""

    combos: tuple[tuple[Mistake, ...], ...]
    filters: tuple[EpochFilter, ...]


def candidate_filters(catalogue: Catalogue, max_combined: int) -> CandidateFilters:
    """The :class:`CandidateFilters` of ``catalogue``: its covariance entries and every
    combination of up to ``max_combined`` of them, each built (not run)."""
    combos = tuple(_combinations(catalogue, max_combined))
    with shared_transitions():
        return CandidateFilters(combos, tuple(catalogue.build(c) for c in combos))


class Candidates:
    """The candidates of :func:`candidates`, their covariances computed as the diagnosis needs
    them (module docstring): :meth:`head` for all, :meth:`rows` for some.  ``built``: the
    catalogue's :class:`CandidateFilters` built before (a class's, shared by its files); none
    builds them here.  The covariances are this object's alone: it lives for one diagnosis."""

    def __init__(self, catalogue: Catalogue, max_combined: int,
                 built: CandidateFilters | None = None) -> None:
        built = candidate_filters(catalogue, max_combined) if built is None else built
        self.combos = list(built.combos)
        self.filters = built.filters
        self._rows: dict[int, np.ndarray] = {}

    def head(self, n_epochs: int) -> np.ndarray:
        """Every candidate's first ``n_epochs`` covariances, (C, n_epochs, n, n)."""
        return _returned(self.filters, n_epochs)

    def rows(self, idx: Sequence[int] | np.ndarray) -> np.ndarray:
        """The whole covariances of the candidates ``idx``, (len(idx), n_gps, n, n)."""
        new = [int(c) for c in idx if int(c) not in self._rows]
        if new:
            for c, P in zip(new, _returned([self.filters[c] for c in new]), strict=True):
                self._rows[c] = P
        return np.stack([self._rows[int(c)] for c in idx])


def _distances(P_student: np.ndarray, sd: np.ndarray, P_out: np.ndarray | Candidates,
               tol: float) -> np.ndarray:
    """Each candidate's distance to run 0's P, and to every run's where run 0's is within
    ``tol``; with :class:`Candidates`, +inf (NaN where its bound is NaN) for those that cannot
    be the nearest nor match."""
    if isinstance(P_out, np.ndarray):
        d = match_distance(P_student[0][None], P_out, sd).reshape(len(P_out), -1).max(axis=1)
        for c in np.flatnonzero(d <= tol):
            d[c] = match_distance(P_student, P_out[c][None], sd).max()
        return d
    k = min(HEAD, P_student.shape[1])
    C = len(P_out.combos)
    lower = match_distance(P_student[0][None, :k], P_out.head(k), sd[:k]).reshape(
        C, -1).max(axis=1)
    d = np.where(np.isnan(lower), np.nan, np.inf)
    done = np.zeros(C, dtype=bool)
    todo = lower <= tol
    if not np.isnan(lower).all():
        todo[int(np.nanargmin(lower))] = True
    while todo.any():
        idx = np.flatnonzero(todo)
        P_idx = P_out.rows(idx)
        d[idx] = match_distance(P_student[0][None], P_idx, sd).reshape(len(idx), -1).max(
            axis=1)
        for j, c in enumerate(idx):
            if d[c] <= tol:
                d[c] = match_distance(P_student, P_idx[j][None], sd).max()
        done[idx] = True
        finite = d[done][~np.isnan(d[done])]
        bound = max(tol, float(finite.min())) if finite.size else np.inf
        todo = ~done & (lower <= bound)
    return d


def diagnose(P_student: np.ndarray, x_student: np.ndarray, z: np.ndarray, sd: np.ndarray,
             catalogue: Catalogue, combos: list[tuple[Mistake, ...]],
             P_out: np.ndarray | Candidates, tol: float = TOLERANCE) -> Diagnosis:
    """Match (x̂, P) of the student (all runs) against the catalogue; see the module docstring.
    ``P_out``: the candidates' covariances (:func:`candidates`), or :class:`Candidates` to
    compute only what the match reads (the same diagnosis)."""
    # run 0's P against every candidate ranks them; a candidate within the tolerance must then
    # also match every other run's P (a P that varies with the data matches nothing)
    d = _distances(P_student, sd, P_out, tol)
    order = np.argsort(d, kind="stable")
    means = catalogue.mean_mistakes()
    mean_combos = [()] + [(m,) for m in means] + list(combinations(means, 2))
    matching = [int(c) for c in order if d[c] <= tol]
    for ci in matching:
        for mc in mean_combos:
            x, _ = catalogue.build(combos[ci] + mc).apply(z)
            if np.max(mean_distance(x_student, x, sd)) <= tol:
                return Diagnosis(combos[ci], mc, None, float(d[ci]))
    if matching:
        return Diagnosis(combos[matching[0]], None, None, float(d[matching[0]]))
    return Diagnosis(None, None, combos[int(order[0])], float(d[int(order[0])]))
