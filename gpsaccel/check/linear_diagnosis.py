"""The catalogue half of the linear checker (:mod:`gpsaccel.check.linear`): the cases, the
optimal answer, and the match of a student's (x̂, P) against a catalogue's candidate filters.

P does not depend on the data, so :func:`candidates` computes the covariance of every covariance
entry and every combination of up to three that touch different ingredients once (stacked,
:func:`gpsaccel.kalman.epochs.batch_gains`); :func:`diagnose` ranks them by run 0's P, confirms a
match on every run, then matches x̂ against the matched entry with each combination of the mean
entries.  Nothing here words a finding: :class:`gpsaccel.check.linear.LinearProblem` does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel.kalman.consistency import covariance_distance
from gpsaccel.kalman.epochs import EpochFilter, batch_gains
from gpsaccel.kalman.mistakes import Catalogue, Mistake, combinations

#: Largest distance (units of the optimal σ) at which P and x̂ count as equal; also the distance
#: within which a catalogue entry counts as matching.
TOLERANCE = 1e-6


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


def candidates(catalogue: Catalogue, max_combined: int
               ) -> tuple[list[tuple[Mistake, ...]], np.ndarray]:
    """Every covariance entry and combination of up to ``max_combined`` (the first is the optimal
    filter, ``()``) and the covariance each returns, (C, n_epochs, n, n)."""
    cov = catalogue.covariance_mistakes()
    combos: list[tuple[Mistake, ...]] = [()]
    for k in range(1, max_combined + 1):
        combos += list(combinations(cov, k))
    filters = [catalogue.build(c) for c in combos]
    _, M, P = batch_gains(filters)
    prior = np.array([f.output == "prior" for f in filters])
    return combos, np.where(prior[:, None, None, None], M, P)


def diagnose(P_student: np.ndarray, x_student: np.ndarray, z: np.ndarray, sd: np.ndarray,
             catalogue: Catalogue, combos: list[tuple[Mistake, ...]], P_out: np.ndarray,
             tol: float = TOLERANCE) -> Diagnosis:
    """Match (x̂, P) of the student (all runs) against the catalogue; see the module docstring."""
    # run 0's P against every candidate ranks them; a candidate within the tolerance must then
    # also match every other run's P (a P that varies with the data matches nothing)
    d = covariance_distance(P_student[0][None], P_out, sd).reshape(len(combos), -1).max(axis=1)
    for c in np.flatnonzero(d <= tol):
        d[c] = covariance_distance(P_student, P_out[c][None], sd).max()
    order = np.argsort(d, kind="stable")
    means = catalogue.mean_mistakes()
    mean_combos = [()] + [(m,) for m in means] + list(combinations(means, 2))
    matching = [int(c) for c in order if d[c] <= tol]
    for ci in matching:
        for mc in mean_combos:
            x, _ = catalogue.build(combos[ci] + mc).apply(z)
            if np.max(np.abs(x_student - x) / sd) <= tol:
                return Diagnosis(combos[ci], mc, None, float(d[ci]))
    if matching:
        return Diagnosis(combos[matching[0]], None, None, float(d[matching[0]]))
    return Diagnosis(None, None, combos[int(order[0])], float(d[int(order[0])]))
