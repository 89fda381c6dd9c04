r"""Comparing a student's (x̂, P) with a reference filter, for the problems that are not linear
(coop's EKF and LKF, the ship's multirate filter): NaN in the output, distances in units of the
reference σ, where the output first departs, and the nearest catalogue entry.  The linear problems
have their own pipeline (:mod:`gpsaccel.check.linear`).

The checker runs the catalogue after each box (no answer is kept while a student's code runs),
and a failing check used to run every catalogue filter in full: 13 coop EKFs of 1000 steps, 11
ship filters.  :func:`nearest_within` runs every candidate's first :data:`HEAD` rows,
whose distance to the student's is a lower bound of its whole distance (the filters are causal:
a row depends only on the rows before it), then whole runs only of the candidates that bound
leaves in play, as the calibration checker does (:mod:`gpsaccel.check.linear_diagnosis`).  Its
answer is the exhaustive search's over every whole run, whenever the caller reads it (within
``far``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from gpsaccel.check.report import Report

#: Rows of every catalogue candidate computed first, to bound its distance from below.
HEAD = 20

#: A candidate whose x̂ has run this far from the reference (units of the reference σ) has lost
#: track, and is compared with the student's output only on the rows before: beyond, the same
#: filter computed in another order differs by rounding alone (measured: the EKF with C's
#: position blocks swapped, 2e4 σ from the reference, separates from a student's copy of it by
#: 1e-4 σ after 755 steps, where both had agreed to 1e-9 σ).
LOST = 1e3


def nan_finding(report: Report, fname: str, name: str, arr: np.ndarray, t: np.ndarray,
                 labels: list[str]) -> bool:
    bad = ~np.isfinite(arr)
    if not bad.any():
        return False
    runs = np.flatnonzero(bad.reshape(bad.shape[0], -1).any(axis=1))
    first = np.argwhere(bad[runs[0]])[0]
    report.add("nan-output", text="{fname}: {name} contains NaN or inf in {bad} of {n} runs; "
               "in {where} first at t = {t:g} s (row {row}). Likely causes: an array from "
               "np.empty never filled at that row, a division by zero, an inverse of a "
               "singular matrix.", where=labels[runs[0]], observed={
                   "fname": fname, "name": name, "bad": runs.size, "n": arr.shape[0],
                   "t": float(t[first[0]]), "row": int(first[0])})
    return True


def distances(x: np.ndarray, P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray,
               diff=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|Δx̂|/σ (..., n) and |ΔP|/(σσ) (..., n, n), σ = √diag P_ref; and σ."""
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    d = (x - x_ref) if diff is None else diff(x, x_ref)
    return (np.abs(d) / sd, np.abs(P - P_ref) / (sd[..., :, None] * sd[..., None, :]), sd)


def first_departure(dx: np.ndarray, dP: np.ndarray, tol_x: float, tol_P: float, t: np.ndarray,
                     states: list[str], labels: list[str], x: np.ndarray, x_ref: np.ndarray,
                     sd: np.ndarray) -> tuple[str, str]:
    """Where the output first leaves the reference (earliest time over runs): the student's
    account (the place and their value) and the instructor's (the reference value too)."""
    bad_x = (dx > tol_x).any(axis=(0, 2))
    bad_P = (dP > tol_P).any(axis=(0, 2, 3))
    kx = int(np.argmax(bad_x)) if bad_x.any() else None
    kP = int(np.argmax(bad_P)) if bad_P.any() else None
    parts, ref = [], ""
    if kP is not None:
        i, j = np.unravel_index(int(np.argmax(dP[:, kP].max(axis=0))), dP.shape[-2:])
        parts.append(f"P first departs at t = {t[kP]:g} s (row {kP}), element P{i + 1}{j + 1}"
                     + (" — P at t = 0 must be the initial P₀" if kP == 0 else ""))
    if kx is not None:
        r, s = np.unravel_index(int(np.argmax(dx[:, kx])), dx[:, kx].shape)
        parts.append(f"x̂ first departs at t = {t[kx]:g} s (row {kx}) in {labels[r]}: "
                     f"{states[s]} = {x[r, kx, s]:.6g}")
        ref = f", the reference gives {x_ref[r, kx, s]:.6g} (σ = {sd[r, kx, s]:.3g})"
    return "; ".join(parts), "; ".join(parts) + ref


def _ratio(xm: np.ndarray, Pm: np.ndarray, x: np.ndarray, P: np.ndarray, sd: np.ndarray,
           tol_x: float, tol_P: float, diff=None, x_ref: np.ndarray | None = None) -> float:
    """The distance of a candidate's (x̂, P) to the student's over the rows it has (axis 1; the
    student's and σ cut to them), in units of the tolerance: the larger of x̂'s and P's; with
    ``x_ref``, only on the rows before the candidate has lost track (:data:`LOST`)."""
    k = xm.shape[1]
    x, P, sd = x[:, :k], P[:, :k], sd[:, :k]
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.abs(xm - x if diff is None else diff(xm, x)) / sd
        dP = np.abs(Pm - P) / (sd[..., :, None] * sd[..., None, :])
        if x_ref is not None:
            off = np.abs(xm - x_ref[:, :k] if diff is None else diff(xm, x_ref[:, :k])) / sd
            kept = ~np.logical_or.accumulate(off.max(axis=-1) > LOST, axis=1)     # (runs, k)
            d, dP = d * kept[..., None], dP * kept[..., None, None]
        return max(float(np.nanmax(d)) / tol_x, float(np.nanmax(dP)) / tol_P)


def nearest_within(candidates: Sequence[Any],
                   run: Callable[[Any, int | None], tuple[np.ndarray, np.ndarray]],
                   x: np.ndarray, P: np.ndarray, P_ref: np.ndarray, tol_x: float, tol_P: float,
                   diff=None, far: float = 10.0, head: int = HEAD,
                   x_ref: np.ndarray | None = None) -> tuple[Any, float] | None:
    """The candidate nearest to the student's (x, P) over the candidates' whole runs, and its
    distance in units of the tolerance (≤ 1: it matches; distances in units of the reference σ,
    as in the comparison), when that distance is at most ``far``, else None; computing only what
    decides it (module docstring).  Its test holds it to the exhaustive search over whole runs.

    ``run(candidate, steps)`` is the candidate's (x̂, P) over its first ``steps`` rows (axis 1;
    None: all of them), each row the same number whatever ``steps``.  The candidates are run in
    full in the order of their lower bounds until the next bound exceeds both ``far`` and the
    nearest whole distance found; a tie goes to the earlier candidate.  ``x_ref``, the
    reference's x̂: each candidate is compared only until it has lost track (:func:`_ratio`).
    """
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    n = x.shape[1]
    lower = np.full(len(candidates), -np.inf)
    if head < n:
        for i, c in enumerate(candidates):
            b = _ratio(*run(c, head), x, P, sd, tol_x, tol_P, diff, x_ref)
            lower[i] = -np.inf if np.isnan(b) else b  # all NaN so far: no bound
    best, best_d = -1, np.inf
    for i in np.argsort(lower, kind="stable"):
        if lower[i] > min(far, best_d):
            break
        d = _ratio(*run(candidates[i], None), x, P, sd, tol_x, tol_P, diff, x_ref)
        if d < best_d or (d == best_d and i < best):
            best, best_d = int(i), d
    return (candidates[best], best_d) if best >= 0 and best_d <= far else None

