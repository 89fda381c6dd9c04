r"""Comparing a student's (x̂, P) with a reference filter, for the problems that are not linear
(coop's EKF and LKF, the ship's multirate filter): NaN in the output, distances in units of the
reference σ, where the output first departs, and the nearest catalogue entry.  The linear problems
have their own pipeline (:mod:`gpsaccel.check.linear`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from gpsaccel.check.report import Report


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


def nearest(candidates: Sequence[tuple[Any, np.ndarray, np.ndarray]], x: np.ndarray,
             P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray, tol_x: float, tol_P: float,
             diff=None) -> tuple[Any, float] | None:
    """The candidate (mistake, x̂, P) nearest to the student's (x, P), and its distance in units
    of the tolerance (≤ 1: it matches); None if there are no candidates.  Distances are in units
    of the reference σ, as in the comparison."""
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    best, best_d = None, np.inf
    for m, xm, Pm in candidates:
        d = xm - x if diff is None else diff(xm, x)
        ratio = max(float(np.nanmax(np.abs(d) / sd)) / tol_x,
                    float(np.nanmax(np.abs(Pm - P) / (sd[..., :, None] * sd[..., None, :])))
                    / tol_P)
        if ratio < best_d:
            best, best_d = m, ratio
    return None if best is None else (best, best_d)

