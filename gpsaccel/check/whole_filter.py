r"""Check a student's whole filter: run it on simulated data, compare, diagnose, test consistency.

The student's file defines ``kalman_filter(z) -> (x_hat, P)`` for the report-000 problem: ``z`` is
the (n_gps, 2) array of GPS-minus-accelerometer measurements [δp, δv] (m, m/s), ``x_hat`` the
(n_gps, 3) a posteriori estimates of [δp, δv, b] and ``P`` the (n_gps, 3, 3) a posteriori
covariances, at the GPS times t = 0, 0.2, ..., 30 s.

What :func:`submission` does
----------------------------
1. Simulates ``n_runs`` realizations from ``numpy.random.default_rng(seed)`` with the error-model
   truth (:func:`gpsaccel.simulate`), so it knows the true state of each.
2. Runs the student's file (or folder) in a sandbox (:mod:`gpsaccel.check.sandbox`: bwrap or
   basic, with time, memory, file, process and output limits), one call ``kalman_filter(z[r])``
   per run; a crash, an endless loop, wrong shapes, NaN, lists, a flood of prints, a broken limit,
   an import of gpsaccel each become a finding, never an exception here.
3. Only then, with every process of the student's gone, runs the optimal filter on the same data
   and compares P and x̂ with it.  Distances are in units of the
   optimal σ = √diag P_ref::

       d_P = max |P_ij − P_ref,ij| / (σ_i σ_j)     d_x = max |x̂_i − x̂_ref,i| / σ_i

   (max over runs, GPS times and elements).  The filter **passes** when both are at most
   :data:`TOLERANCE` = 1e-6 on every realization.  The problem has one optimal filter, so every
   correct form passes (covariance, information or Joseph update; filterpy or by hand; a filter
   that steps only at GPS times with Φ⁴⁰ and the 40-step process noise): they agree to ~1e-11 σ,
   while the smallest effect of a catalogued mistake (phi-sign on P) is 3e-4 σ.
4. Recognises mistakes in what is returned before anything else
   (:func:`_recognised_output_mistake`): ``aliased-output``, ``state-between-calls`` (naming the
   first wrong run), ``low-precision`` (float32), ``p-scaled``, ``epoch-shift``,
   ``last-update-missing``; each would otherwise read as a wrong M0, H or V.  Then diagnoses a
   failing filter against the catalogue (:mod:`gpsaccel.calibration.mistakes`): P does not
   depend on the data, so P is matched first against every covariance mistake and every
   combination of up to three that touch different ingredients; then x̂ against the matched
   entry with each combination of the mean mistakes.  A match (both within the tolerance) is
   reported under its code; a right P with a wrong x̂ that matches nothing is a gain or residual
   mistake; a P that matches nothing is located (t = 0 or the propagation, and the first element
   that departs), with the nearest catalogue entry as a hint only when it is within
   :data:`HINT_FACTOR` = 10 times the tolerance.
5. Tests consistency over the runs with the student's own P, to show what a mistake does:
   the ensemble-mean error (z = ē_i √N / √P_ii at every time and state) and the ensemble-average
   NEES (N·ε̄ ~ χ²(3N) at every time), each as a family of two-sided tests with a family-wise
   false-alarm rate ``alpha`` (Bonferroni over the times and states).  For a correct filter the
   two together raise a false alarm with probability at most 2·alpha.  These are reported as
   warnings (or notes when they hold): they never decide ``passed``, the comparison does.

Measured false alarms (200 runs per check): 140 checks of five correct forms on 140 seeds, all
passed (largest distances 1.9e-13 in P, 4.1e-11 in x̂); the consistency tests at alpha = 0.01
alarmed once in 540 correct checks (0.19 %; Bonferroni over correlated times is conservative).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration import mistakes as cat
from gpsaccel.calibration.model import STATE_NAMES, CalibrationModel
from gpsaccel.calibration.simulation import simulate
from gpsaccel.check import sandbox as sb
from gpsaccel.check.report import Report
from gpsaccel.kalman.consistency import (
    chi2_bounds,
    covariance_distance,
    format_verdicts,
    nees,
    sigma_distance,
    verdict_from_z,
    z_ensemble_normalized_squared,
    z_sample_mean,
)

#: Largest distance (units of the optimal σ) at which P and x̂ count as equal; also the distance
#: within which a catalogue entry counts as matching.
TOLERANCE = 1e-6

#: The function a submission defines.
FUNCTION = "kalman_filter"

#: Realizations per check.  The pass decision compares with the one optimal answer run by run, so
#: it needs few: measured with benchmarks/check_runs.py, every calibration fixture (6 correct forms,
#: 22 mistakes, sharper diagnoses included) gets exactly its expected codes on 3 seeds at n_runs =
#: 2, 3, 5 and 10 alike; only the informational consistency tests want more (at 10 their χ²(30)
#: average-NEES bounds are [1.6, 4.7]).  A by-hand 200 Hz check takes ~1 s at 10 runs.
DEFAULT_RUNS = 10

#: The nearest catalogued mistake is shown as a hint only within this factor of the tolerance.
HINT_FACTOR = 10.0

#: Largest distances (σσ in P, σ in x̂) at which a float32 filter counts as "right but low
#: precision": float32 rounding (2⁻²⁴ ≈ 6e-8 relative) over 6000 steps.  Measured on the fixture
#: mutant_float32.py (z, matrices and state all float32): 8e-5 σσ in P, 0.035 σ in x̂ (the
#: estimate of δp carries ~100 m totals through 6000 products).
LOW_PRECISION = (1e-3, 0.1)

#: Characters of the student's printed output kept in a finding.
OUTPUT_KEEP = 1500

#: Printed output (characters) beyond which the check warns about prints.
OUTPUT_WARN = 20_000



# ---------------------------------------------------------------------------------- the data
@dataclass(frozen=True, eq=False)
class Data:
    """The realizations a check runs on (no answer in it).

    z : (n_runs, n_gps, 2) measurements; x_true : (n_runs, n_gps, 3) true error states.
    """

    model: CalibrationModel
    seed: int
    z: np.ndarray
    x_true: np.ndarray


@dataclass(frozen=True, eq=False)
class Problem(Data):
    """The realizations and the optimal filter's answer on them.

    x_ref : (n_runs, n_gps, 3) optimal x̂; P_ref : (n_gps, 3, 3) optimal P; sd : √diag P_ref.
    """

    x_ref: np.ndarray
    P_ref: np.ndarray
    sd: np.ndarray


def make_data(model: CalibrationModel, n_runs: int, seed: int) -> Data:
    rng = np.random.default_rng(seed)
    runs = [simulate(model, rng) for _ in range(n_runs)]
    return Data(model, seed, np.stack([r.z for r in runs]), np.stack([r.x_gps for r in runs]))


def with_answer(data: Data) -> Problem:
    """The optimal filter run on ``data`` (computed only once no student process is alive)."""
    x_ref, P_ref = cat.reference(data.model).apply(data.z)
    sd = np.sqrt(np.diagonal(P_ref, axis1=1, axis2=2))
    return Problem(data.model, data.seed, data.z, data.x_true, x_ref, P_ref, sd)


def make_problem(model: CalibrationModel, n_runs: int, seed: int) -> Problem:
    return with_answer(make_data(model, n_runs, seed))


@lru_cache(maxsize=4)
def _default_data(n_runs: int, seed: int) -> Data:
    return make_data(CalibrationModel(), n_runs, seed)


def _data(model: CalibrationModel | None, n_runs: int, seed: int) -> Data:
    if model is None:
        return _default_data(n_runs, seed)
    return make_data(model, n_runs, seed)


def forget_answers() -> None:
    """Drop every cached answer (the catalogue's covariances, the optimal P among them), so none
    is in this process's memory while a student's code runs."""
    _candidates.cache_clear()


# ---------------------------------------------------------------------- running the student
def calls(z: np.ndarray) -> list[sb.Call]:
    """One sandbox call ``kalman_filter(z[r])`` per run, returning x̂ (n_gps, 3), P (n_gps, 3, 3)."""
    n_gps = z.shape[1]
    outputs = (sb.Output("x_hat", (n_gps, 3)), sb.Output("P", (n_gps, 3, 3)))
    return [sb.Call(FUNCTION, (z[r],), outputs) for r in range(z.shape[0])]


def run_student(sub: sb.Submission, z: np.ndarray, limits: sb.Limits, backend: str = "auto",
                allow_gpsaccel: bool = False) -> tuple[sb.BoxResult, np.ndarray, np.ndarray]:
    """Run the submission on every ``z[r]`` in a sandbox; x (n_runs, n_gps, 3) and P (n_runs,
    n_gps, 3, 3) hold what came back, NaN where nothing did."""
    forget_answers()
    box = sb.run(sub, calls(z), limits, backend, allow_gpsaccel)
    n_runs, n_gps = z.shape[:2]
    x = np.full((n_runs, n_gps, 3), np.nan)
    P = np.full((n_runs, n_gps, 3, 3), np.nan)
    for r, out in enumerate(box.results):
        x[r], P[r] = out["x_hat"], out["P"]
    return box, x, P


# --------------------------------------------------------------------------- the findings
def _where(sd: np.ndarray, t: np.ndarray, idx: tuple[int, ...], kind: str) -> str:
    if kind == "x":
        r, i, s = idx
        return f"run {r}, t = {t[i]:g} s, {STATE_NAMES[s]}"
    i, a, b = idx[-3:]
    return f"t = {t[i]:g} s, element P{a + 1}{b + 1}"


def _run_findings(report: Report, box: sb.BoxResult, limits: sb.Limits, n_runs: int,
                  model: CalibrationModel, allow_gpsaccel: bool = False) -> bool:
    """Findings about the box itself; True when there are results to examine."""
    report.details["sandbox"] = box.backend
    report.details["sandbox_limits"] = box.limit_backend  # cgroup2, cgroup1 or rlimit
    failure, problem = box.failure, box.problem or {}
    done = len(box.results)
    if box.output_bytes > OUTPUT_WARN and failure != "output-limit":
        report.add("prints-a-lot", f"Your code printed {box.output_bytes:,} bytes during the "
                   f"check ({n_runs} runs). Remove debug prints from kalman_filter: they slow it "
                   f"down and bury the messages that matter. The last lines were:\n"
                   + _indent_tail(box.output[-OUTPUT_KEEP:], 6), "warning")
    if box.killed:
        report.details["processes_killed"] = box.killed
        report.add("left-processes", f"Your code left {box.killed} process(es) running after "
                   f"it returned; the checker killed them. kalman_filter should not start "
                   f"processes (os.fork, subprocess, multiprocessing).", "warning")
    if failure is None:
        _returned_notes(report, box.returned or {})
        return True
    mib = limits.memory / 2**20
    tb = ("; the traceback ends with:\n" + _indent(problem["traceback"])
          if problem.get("traceback") else ".")
    last = "\nIts last output:\n" + _indent_tail(box.output[-OUTPUT_KEEP:], 8)
    if failure == "timeout":
        rate = (f" (≈ {limits.time / done:.2g} s per run, {n_runs} runs needed)" if done else "")
        report.add("timeout", f"Your kalman_filter did not finish within the time limit of "
                   f"{limits.time:g} s: it completed {done} of {n_runs} runs{rate}. "
                   + ("It never returned once: look for a loop whose condition never changes "
                      "(e.g. while k < n without k += 1) or input() waiting for a keyboard."
                      if done == 0 else f"It is too slow: {model.n_steps} accelerometer steps "
                      f"per run should take well under a second."))
    elif failure == "memory-limit":
        report.add("memory-limit", f"Your code ran out of memory: a check may use {mib:g} MiB "
                   f"of address space, and your file asked for more (after {done} of {n_runs} "
                   f"runs){tb} A filter for {model.n_gps} GPS times needs a few kilobytes: "
                   f"look for an array sized by the accelerometer steps squared, or a list that "
                   f"grows in a loop that never ends.")
    elif failure == "output-limit":
        report.add("output-limit", f"Your code printed more than {limits.output:,} bytes, the "
                   f"most a check keeps, so it was stopped after {done} of {n_runs} runs. "
                   f"Remove the prints from kalman_filter (or print only when debugging)." + last)
    elif failure == "file-limit":
        report.add("file-limit", f"Your code wrote a file larger than the {limits.file_size:,} "
                   f"bytes a check allows (or filled its working folder){tb} A filter needs no "
                   f"files: return x_hat and P instead of saving them.")
    elif failure == "process-limit":
        report.add("process-limit", f"Your code started more processes than the "
                   f"{limits.processes} a check allows (after {done} of {n_runs} runs){tb} "
                   f"kalman_filter must compute its result in its own process: remove "
                   f"os.fork, subprocess and multiprocessing.")
    elif failure == "uses-checker":
        report.add("uses-checker", "Your file imports gpsaccel, the package that checks it. "
                   "During a check the submission must compute x̂ and P with its own code (numpy, "
                   "scipy and filterpy are available); remove the import of gpsaccel"
                   + (". (Your instructor allowed gpsaccel for this check.)" if allow_gpsaccel
                      else "."))
    elif failure == "result-refused":
        report.add("result-refused", f"What your code handed back to the checker was refused "
                   f"({box.detail}). Only kalman_filter's return value counts: do not write to "
                   f"the checker's file descriptors or replace the checker's functions.")
    elif failure == "crashed":
        report.add("crashed", f"The Python process running your file ended without a result "
                   f"({box.detail}) after {done} of {n_runs} runs. Does your file call "
                   f"os._exit() or kill a process?" + last)
    elif failure == "import-error":
        report.add("import-error", "Your file raises an error when it is imported (before "
                   "kalman_filter is called); the traceback ends with:\n"
                   + _indent(problem.get("traceback", "")))
    elif failure == "no-function":
        found = problem.get("found")
        report.add("no-kalman-filter", "Your file does not define a function kalman_filter(z)"
                   + (f" (kalman_filter is a {found['type']}, not a function)" if found else "")
                   + ". Functions it defines: " + (", ".join(problem.get("callables", []))
                                                    or "none")
                   + ". Name your filter kalman_filter, taking z and returning (x_hat, P).")
    elif failure == "exception":
        report.add("exception", f"kalman_filter(z) raised an exception on run "
                   f"{problem.get('call')}; the traceback ends with:\n"
                   + _indent(problem.get("traceback", "")))
    elif failure == "return-value":
        ret = problem["returned"]
        shape_text = f" of shape {tuple(ret['shape'])}" if ret.get("shape") else ""
        length = problem.get("length")
        report.add("return-value", f"kalman_filter(z) must return a pair (x_hat, P); it returned "
                   f"a {ret['type']}{shape_text}"
                   + (f" with {length} items" if length is not None else "")
                   + ". End it with: return x_hat, P.")
    elif failure == "not-numeric":
        report.add("not-numeric", f"{problem['name']} returned by kalman_filter is not an array "
                   f"of numbers ({problem['returned']['type']}): np.array({problem['name']}, "
                   f"dtype=float) fails with: {problem['error'].rstrip('.')}.")
    elif failure == "wrong-shape":
        shapes = problem.get("shapes", {})
        report.add("wrong-shape", _shape_message(tuple(shapes.get("x_hat") or ()),
                                                 tuple(shapes.get("P") or ()), model,
                                                 problem.get("call")))
    else:  # a code this version does not know: say what the sandbox said
        report.add("runner", f"The check could not run your filter: {failure} {box.detail}")
    return False


def _returned_notes(report: Report, ret: dict) -> None:
    for name in ("x_hat", "P"):
        typ = ret.get(name, {}).get("type", "")
        if typ in ("builtins.list", "builtins.tuple"):
            report.add("returns-list", f"{name} is a Python {typ.split('.')[-1]}; it was "
                       f"converted with np.array({name}, dtype=float). Returning numpy arrays "
                       f"is expected (np.array(...) at the end of your function).", "note")
        elif typ == "numpy.matrix":
            report.add("returns-list", f"{name} is a numpy.matrix; it was converted to an "
                       f"array. numpy.matrix is deprecated: use numpy arrays and @.", "note")


def _shape_message(xs: tuple, Ps: tuple, model: CalibrationModel,
                   run: int | None = None) -> str:
    n_gps, every, t = model.n_gps, model.gps_every, model.t_gps
    want_x, want_P = (n_gps, 3), (n_gps, 3, 3)
    on = "" if run is None else f" on run {run}" + (
        " (the earlier runs had the right shapes: does your file keep results between calls, "
        "e.g. a module-level list that grows?)" if run else " (the first call)")
    parts = [f"kalman_filter must return x_hat of shape {want_x} and P of shape {want_P} (one "
             f"row per GPS time t = {t[0]:g}, {t[1]:g}, ..., {t[-1]:g} s); it returned x_hat "
             f"{xs} and P {Ps}{on}."]
    if xs == (3, n_gps):
        parts.append("x_hat looks transposed: one row per GPS time, one column per state.")
    elif xs == (n_gps, 3, 1):
        parts.append("x_hat has a trailing axis of length 1 (filterpy's kf.x is a 3x1 column): "
                     "store kf.x[:, 0] or x.ravel().")
    elif len(xs) == 2 and xs[1] == 3 and xs[0] == (n_gps - 1) * every + 1:
        parts.append(f"x_hat has one row per accelerometer step; return the GPS times only "
                     f"(every {every}th row: x[::{every}]).")
    elif len(xs) == 2 and xs[1] == 3 and xs[0] in (n_gps - 1, n_gps + 1):
        parts.append(f"x_hat has {xs[0]} rows: the GPS times include t = 0 and t = {t[-1]:g} s "
                     f"({n_gps} rows).")
    if Ps == (n_gps, 3):
        parts.append("P looks like the diagonal only (or the standard deviations): return the "
                     "full 3x3 covariance at each GPS time.")
    elif Ps == (3, 3, n_gps):
        parts.append("P has time last (MATLAB's P(:,:,k)); numpy puts it first: P[k] is 3x3.")
    return " ".join(parts)


def _indent(text: str, n: int = 6) -> str:
    return "\n".join(" " * n + line for line in text.splitlines())


def _indent_tail(text: str, lines: int) -> str:
    return _indent("\n".join(text.rstrip().splitlines()[-lines:]) or "(nothing)")


def _value_findings(report: Report, x: np.ndarray, P: np.ndarray, t: np.ndarray) -> bool:
    """NaN/inf in what came back; True when everything is finite."""
    for name, arr in (("x_hat", x), ("P", P)):
        bad = ~np.isfinite(arr)
        if bad.any():
            runs = np.flatnonzero(bad.reshape(bad.shape[0], -1).any(axis=1))
            first = np.argwhere(bad[runs[0]])[0]
            what = "NaN" if np.isnan(arr).any() else "inf"
            report.add("nan-output", f"{name} contains {what} in {runs.size} of {arr.shape[0]} "
                       f"runs; in run {runs[0]} first at t = {t[first[0]]:g} s (row {first[0]}). "
                       f"Likely causes: an array made with np.empty and never filled at that "
                       f"row, a division by zero, or the inverse of a singular matrix.")
            return False
    return True


@dataclass(frozen=True)
class Diagnosis:
    """The catalogue entries that reproduce the student's (x̂, P), or the nearest P entry."""

    covariance: tuple[cat.Mistake, ...] | None
    mean: tuple[cat.Mistake, ...] | None
    nearest: tuple[cat.Mistake, ...] | None
    nearest_distance: float


@lru_cache(maxsize=8)
def _candidates(model: CalibrationModel, max_combined: int
                ) -> tuple[list[tuple[cat.Mistake, ...]], np.ndarray]:
    """Every covariance entry and combination of up to ``max_combined`` (the first is the optimal
    filter, ``()``) and the covariance each returns, (C, n_gps, 3, 3).  Cached per model object."""
    cov = cat.covariance_mistakes(model)
    combos: list[tuple[cat.Mistake, ...]] = [()]
    for k in range(1, max_combined + 1):
        combos += list(cat.combinations(cov, k))
    filters = [cat.build(model, c) for c in combos]
    _, M, P = cat.batch_gains(filters)
    prior = np.array([f.output == "prior" for f in filters])
    return combos, np.where(prior[:, None, None, None], M, P)


def diagnose(P_student: np.ndarray, x_student: np.ndarray, problem: Problem,
             tol: float = TOLERANCE, max_combined: int = 3) -> Diagnosis:
    """Match (x̂, P) of the student (all runs) against the catalogue; see the module docstring."""
    model, sd = problem.model, problem.sd
    combos, P_out = _candidates(model, max_combined)
    # run 0's P against every candidate ranks them; a candidate within the tolerance must then
    # also match every other run's P (a P that varies with the data matches nothing)
    d = covariance_distance(P_student[0][None], P_out, sd).reshape(len(combos), -1).max(axis=1)
    for c in np.flatnonzero(d <= tol):
        d[c] = covariance_distance(P_student, P_out[c][None], sd).max()
    order = np.argsort(d, kind="stable")
    means = cat.mean_mistakes(model)
    mean_combos = [()] + [(m,) for m in means] + list(cat.combinations(means, 2))
    matching = [int(c) for c in order if d[c] <= tol]
    for c in matching:
        for mc in mean_combos:
            x, _ = cat.build(model, combos[c] + mc).apply(problem.z)
            if np.max(np.abs(x_student - x) / sd) <= tol:
                return Diagnosis(combos[c], mc, None, float(d[c]))
    if matching:
        return Diagnosis(combos[matching[0]], None, None, float(d[matching[0]]))
    best = int(order[0])
    return Diagnosis(None, None, combos[best], float(d[best]))


def _comparison(report: Report, problem: Problem, x: np.ndarray, P: np.ndarray,
                tol: float) -> tuple[bool, bool]:
    t = problem.model.t_gps
    dx, dP = sigma_distance(x, P, problem.x_ref, problem.P_ref, problem.sd)
    iP = np.unravel_index(int(np.argmax(dP)), dP.shape)
    ix = np.unravel_index(int(np.argmax(dx)), dx.shape)
    spread = covariance_distance(P, P[:1], problem.sd).max()
    report.details.update({
        "max_dP_sigma": float(dP.max()), "max_dP_where": _where(problem.sd, t, iP, "P"),
        "max_dx_sigma": float(dx.max()), "max_dx_where": _where(problem.sd, t, ix, "x"),
        "P_spread_over_runs_sigma": float(spread), "tolerance_sigma": tol,
    })
    report.tables.append(
        f"against the optimal filter on {x.shape[0]} runs (units of the optimal σ, tolerance "
        f"{tol:g}):\n"
        f"  max |ΔP|/(σσ) = {dP.max():.3g}  at {_where(problem.sd, t, iP, 'P')}\n"
        f"  max |Δx̂|/σ   = {dx.max():.3g}  at {_where(problem.sd, t, ix, 'x')}")
    if spread > tol:
        report.add("p-depends-on-data", f"Your P changes from run to run (by up to {spread:.3g} "
                   f"σσ). In a linear Kalman filter P depends only on Φ, Q, H, V and M0, never on "
                   f"the measurements: compute P without z.", "warning")
    return bool(dP.max() <= tol), bool(dx.max() <= tol)


def _float32_exact(a: np.ndarray) -> bool:
    """Every value of ``a`` is a float32 number (what a float32 computation returns)."""
    return bool(np.all(a.astype(np.float32).astype(np.float64) == a))


def _recognised_output_mistake(report: Report, problem: Problem, x: np.ndarray, P: np.ndarray,
                               returned: dict, tol: float) -> bool:
    """Mistakes in what is returned or how calls share state, recognised before the catalogue of
    filter mistakes (each would otherwise look like a wrong M0, H or V).  True when one was
    reported.

    In order: ``aliased-output`` (every row the same array, written in place), ``state-between-
    calls`` (run 0 right, a later run not), ``low-precision`` (float32 arithmetic, within
    :data:`LOW_PRECISION`), ``p-scaled`` (P = c·P_opt), ``epoch-shift`` (rows shifted by one GPS
    time), ``last-update-missing`` (the last row is the a priori x̄, M).
    """
    ref, sd, t = problem, problem.sd, problem.model.t_gps
    n = x.shape[1]
    dP = covariance_distance(P, ref.P_ref[None], sd)                     # (N, n, 3, 3)
    dx = np.abs(x - ref.x_ref) / sd                          # (N, n, 3)
    per_run = np.maximum(dP.max(axis=(1, 2, 3)), dx.max(axis=(1, 2)))
    # every row identical and equal to the last optimal one: one array object stored at every
    # time (a constant output that is not the last estimate is some other mistake)
    if n > 2 and np.all(P == P[:, -1:]) and np.all(x == x[:, -1:]) and \
            dP[:, -1].max() <= tol and dx[:, -1].max() <= tol:
        report.add("aliased-output", f"Every row of your x_hat and P holds the same values, "
                   f"those of the last GPS time (t = {t[-1]:g} s): each row is the same array "
                   f"object, changed in place at every step (e.g. x += K @ r or P[:] = ..., "
                   f"then appended to a list). Store a copy: x_hat[k] = x (into a preallocated "
                   f"array) or xs.append(x.copy()).")
        return True
    if per_run[0] <= tol and (per_run > tol).any():
        r = int(np.argmax(per_run > tol))
        what = ("P" if dP[r].max() > tol else "x̂")
        report.add("state-between-calls", f"Your filter is right on the first call but not on "
                   f"later ones: {what} first differs on run {r} (by {per_run[r]:.3g} σ), and "
                   f"{int((per_run > tol).sum())} of {len(per_run)} runs differ. Something "
                   f"survives between calls: a module-level list or array that keeps growing, a "
                   f"global M0 or x0 changed in place (M = M0 then M -= ..., x = x0 then "
                   f"x += ...). Copy globals before changing them (M = M0.copy()).")
        report.findings = [f for f in report.findings if f.code != "p-depends-on-data"]
        report.details["first_wrong_run"] = r
        return True
    dtypes = {(returned.get(k) or {}).get("dtype") for k in ("x_hat", "P")}
    if dP.max() <= LOW_PRECISION[0] and dx.max() <= LOW_PRECISION[1] and (
            "float32" in dtypes or (_float32_exact(x) and _float32_exact(P))):
        report.add("low-precision", f"Your filter computes in single precision (float32): its "
                   f"output differs from the optimal filter by up to {dP.max():.2g} σσ in P and "
                   f"{dx.max():.2g} σ in x̂, what float32 rounding (about 6e-8 relative) builds "
                   f"up over {problem.model.n_steps} steps; the tolerance is {tol:g}. This is "
                   f"not a wrong M0, H or V: use float64 throughout (no .astype(np.float32), z "
                   f"as given) and check again — at float32 precision a small mistake could "
                   f"hide.")
        return True
    diag_ref = np.diagonal(ref.P_ref, axis1=-2, axis2=-1)
    c = float(np.median(np.diagonal(P, axis1=-2, axis2=-1) / diag_ref))
    if abs(c - 1) > 1e-3 and covariance_distance(P, c * ref.P_ref[None], sd).max() <= tol * max(c, 1.0):
        x_note = ("Your x̂ is right, so only the returned P is scaled." if dx.max() <= tol else
                  f"Your x̂ differs too (by up to {dx.max():.3g} σ): the scaled P also feeds "
                  f"your gain.")
        report.add("p-scaled", f"Your P is the optimal P multiplied by {c:.6g} at every time"
                   + (" — P + Pᵀ without the /2 when symmetrising" if abs(c - 2) < 1e-6 else "")
                   + f". {x_note} M0, H and V are not the problem: look at the line that "
                   f"symmetrises or scales P.")
        return True
    for shift, where in ((1, "one GPS time late: row k holds the estimate of time k − 1"),
                         (-1, "one GPS time early: row k holds the estimate of time k + 1")):
        a = slice(1, None) if shift == 1 else slice(None, -1)
        b = slice(None, -1) if shift == 1 else slice(1, None)
        if (covariance_distance(P[:, a], ref.P_ref[None, b], sd[b]).max() <= tol
                and (np.abs(x[:, a] - ref.x_ref[:, b]) / sd[b]).max() <= tol):
            report.add("epoch-shift", f"Your outputs are shifted by one epoch, {where} "
                       f"(every row but the {'first' if shift == 1 else 'last'} matches the "
                       f"optimal filter shifted). Store x̂ and P of time t_k in row k, right "
                       f"after the update with z[k].")
            return True
    flt = cat.reference(problem.model)
    _, M_ref, _ = flt.gains
    x_bar = replace(flt, output="prior").apply(problem.z)[0]
    if (covariance_distance(P[:, :-1], ref.P_ref[None, :-1], sd[:-1]).max() <= tol
            and (np.abs(x[:, :-1] - ref.x_ref[:, :-1]) / sd[:-1]).max() <= tol
            and covariance_distance(P[:, -1:], M_ref[None, -1:], sd[-1:]).max() <= tol
            and (np.abs(x[:, -1] - x_bar[:, -1]) / sd[-1]).max() <= tol):
        report.add("last-update-missing", f"Your filter is right except at the last GPS time "
                   f"(t = {t[-1]:g} s), where x̂ and P are the a priori x̄ and M: the update "
                   f"with the last fix z[{n - 1}] is missing (a loop such as range(n - 1), or "
                   f"the update placed before the propagation).")
        return True
    return False


def _diagnosis_findings(report: Report, problem: Problem, x: np.ndarray, P: np.ndarray,
                        tol: float) -> None:
    diag = diagnose(P, x, problem, tol)
    t = problem.model.t_gps
    names = lambda ms: ", ".join(str(m) for m in ms)  # noqa: E731
    if diag.covariance is not None and diag.mean is not None:
        found = diag.covariance + diag.mean
        report.details["matched"] = [{"code": m.code, "variant": m.variant} for m in found]
        for m in found:
            report.add(m.code, m.message)
        report.tables.append(f"catalogue: on every run your (x̂, P) match, to {tol:g} σ, the "
                             f"filter that makes\n" + "\n".join(f"  {m}" for m in found))
        return
    if diag.covariance is not None:  # P recognised, x̂ not
        used_z0 = bool(np.max(np.abs(x[:, 0] - problem.model.x0) / problem.sd[0]) > tol)
        for m in diag.covariance:
            if m.code == "first-update-skipped" and used_z0:
                report.add(m.code, "Your P at t = 0 is the prior M0: the covariance update with "
                           "the GPS fix at t = 0 is missing (your x̂ at t = 0 did use z₀, so "
                           "the mean was updated but not P). Update P at t = 0 too, "
                           "P₀ = (I − K₀H) M0 (I − K₀H)ᵀ + K₀VK₀ᵀ, before the first "
                           "propagation.")
                continue
            report.add(m.code, m.message)
        dx = np.abs(x - cat.build(problem.model, diag.covariance).apply(problem.z)[0]) / problem.sd
        i = np.unravel_index(int(np.argmax(dx)), dx.shape)
        lead = ("Your P is the optimal one, so your model (Φ, Q, H, V, M0) is right, but"
                if not diag.covariance else f"Your P matches {names(diag.covariance)}, and")
        report.add("gain-or-residual", f"{lead} your x̂ differs from what that filter gives on "
                   f"the same z by up to {dx.max():.3g} σ ({_where(problem.sd, t, i, 'x')}). "
                   f"The mistake is in how x̂ is formed: check K = M Hᵀ (H M Hᵀ + V)⁻¹ (or "
                   f"P Hᵀ V⁻¹), x̄ = Φ x̂ at every accelerometer step, the residual r = z − H x̄ "
                   f"and x̂ = x̄ + K r, with z at the matching GPS time.")
        report.details["matched"] = [{"code": m.code, "variant": m.variant}
                                     for m in diag.covariance]
        return
    dP = covariance_distance(P, problem.P_ref[None], problem.sd).max(axis=(0, 2, 3))
    first = int(np.argmax(dP > tol))
    where = ("P at t = 0 already differs: the first update uses only M0, H and V, so one of "
             "them is wrong (or the update formula)." if first == 0 else
             f"P at t = 0 is right (so M0, H, V and the update are), but P differs from "
             f"t = {t[first]:g} s on: the propagation between GPS fixes is wrong (Φ, "
             f"Q = Γ W Γᵀ, or the number of steps).")
    d_optimal = float(dP.max())
    if diag.nearest and diag.nearest_distance <= HINT_FACTOR * tol:  # only a hint that is close
        hint = (f" The nearest known mistake is {names(diag.nearest)}: your P is within "
                f"{diag.nearest_distance:.3g} σσ of it ({diag.nearest_distance / tol:.2g}× the "
                f"tolerance), so look there first.")
    else:
        hint = " No catalogued mistake matches."
    worst = covariance_distance(P[:, first:first + 1], problem.P_ref[None, first:first + 1],
                    problem.sd[first:first + 1])[:, 0]  # (N, 3, 3)
    r, a, b = np.unravel_index(int(np.argmax(worst)), worst.shape)
    depart = (f" Your output first departs at t = {t[first]:g} s: P{a + 1}{b + 1} = "
              f"{P[r, first, a, b]:.6g}, the optimal filter's is "
              f"{problem.P_ref[first, a, b]:.6g}.")
    report.add("p-mismatch", f"Your P does not match the optimal filter (it differs by up to "
               f"{d_optimal:.3g} σσ).{hint} {where}{depart} Check "
               f"your matrices with gpsaccel.check.model_matrices(Phi=..., Gamma=..., H=..., "
               f"V=..., W=..., M0=...).")
    report.details["matched"] = []


def _consistency(report: Report, problem: Problem, x: np.ndarray, P: np.ndarray,
                 alpha: float) -> None:
    t = problem.model.t_gps
    N = x.shape[0]
    e = problem.x_true - x                              # (N, n_gps, 3)
    sym = np.abs(P - np.swapaxes(P, -1, -2)).max(axis=(-1, -2)) <= 1e-9 * np.abs(P).max(
        axis=(-1, -2))
    eig_min = np.linalg.eigvalsh((P + np.swapaxes(P, -1, -2)) / 2).min(axis=-1)
    bad = ~sym | (eig_min <= 0)                        # (N, n_gps)
    if bad.any():
        times = np.flatnonzero(bad.any(axis=0))
        report.add("p-not-positive-definite", f"Your P is not a covariance at {times.size} GPS "
                   f"times (first t = {t[times[0]]:g} s): it is not symmetric positive definite, "
                   f"so NEES cannot be formed. A Joseph update, or symmetrising "
                   f"P = (P + Pᵀ)/2, keeps it one.", "warning")
        return
    var = np.diagonal(P, axis1=-2, axis2=-1)           # (N, n_gps, 3)
    z_mean = z_sample_mean(e.mean(axis=0), var.mean(axis=0), N)  # (n_gps, 3)
    v_mean = verdict_from_z("mean error ē/σ", z_mean,
                            lambda idx: f"t = {t[idx[0]]:g} s, {STATE_NAMES[idx[1]]}", alpha)
    eps = nees(e, (P + np.swapaxes(P, -1, -2)) / 2).mean(axis=0)  # ensemble NEES at each time
    z_nees = z_ensemble_normalized_squared(eps, 3, N)  # + when ε̄ is too large
    v_nees = verdict_from_z("NEES (average)", z_nees, lambda idx: f"t = {t[idx[0]]:g} s", alpha)
    lo, hi = chi2_bounds(3, N, 0.05)
    inside = float(np.mean((eps >= lo) & (eps <= hi)))
    rms = np.sqrt(np.mean(e**2, axis=0))                # (n_gps, 3)
    rms_ref = np.sqrt(np.mean((problem.x_true - problem.x_ref) ** 2, axis=0))
    ratio = rms.mean(axis=0) / rms_ref.mean(axis=0)
    report.details["consistency"] = {
        "alpha": alpha, "n_runs": N,
        "mean_error_max_abs_z": v_mean.max_abs_z, "mean_error_bound": v_mean.threshold,
        "nees_max_abs_z": v_nees.max_abs_z, "nees_bound": v_nees.threshold,
        "nees_fraction_inside_95": inside, "nees_average_first_last": [float(eps[0]),
                                                                       float(eps[-1])],
        "rms_ratio_to_optimal": [float(r) for r in ratio],
    }
    report.tables.append(
        f"consistency over {N} runs, with your P (family-wise false-alarm rate {alpha:g} each):\n"
        + format_verdicts([v_mean, v_nees])
        + f"\nNEES inside its 95% bounds [{lo:.3f}, {hi:.3f}] at {100 * inside:.0f}% of the "
          f"{t.size} GPS times (expected ≈ 95%)."
        + "\nRMS error over time relative to the optimal filter: "
        + ", ".join(f"{s} {r:.3g}" for s, r in zip(STATE_NAMES, ratio, strict=True)))
    i_mean = np.unravel_index(int(np.nanargmax(np.abs(z_mean))), z_mean.shape)
    i_nees = int(np.nanargmax(np.abs(z_nees)))
    for v, what in (
            (v_mean, f"Your errors do not average to zero: at {v_mean.where} the mean error over "
                     f"{N} runs is {e.mean(axis=0)[i_mean]:.3g}, {v_mean.max_abs_z:.3g} times its "
                     f"standard error √(P/N)"),
            (v_nees, f"Your P does not describe your actual errors: at {v_nees.where} the "
                     f"average NEES over {N} runs is {eps[i_nees]:.4g}, outside its 95% bounds "
                     f"[{lo:.3f}, {hi:.3f}] (|z| = {v_nees.max_abs_z:.3g})")):
        if not v.passed:
            report.add("inconsistent", f"{what}; the test fails beyond |z| = {v.threshold:.3g} "
                       f"(family-wise false-alarm rate {alpha:g} over {v.n_tests} tests). This "
                       f"is what the mistake does to the estimates.", "warning")
    if v_mean.passed and v_nees.passed:
        report.add("consistent", f"Over {N} runs your errors average to zero and match your P "
                   f"(mean-error and NEES tests at family-wise α = {alpha:g}).", "note")


def submission(path: str | os.PathLike, n_runs: int = DEFAULT_RUNS, seed: int = 0,
               timeout: float = 60,
               model: CalibrationModel | None = None, alpha: float = 0.01,
               tol: float = TOLERANCE, sandbox: str = "auto", limits: sb.Limits | None = None,
               allow_gpsaccel: bool = False) -> Report:
    """Check the submission ``path`` that defines ``kalman_filter(z) -> (x_hat, P)``.

    Parameters
    ----------
    path : the student's ``.py`` file, or a folder (one student's) holding one file that defines
        kalman_filter and its helper modules and data files (:func:`sandbox.load_submission`).
    n_runs : realizations to run it on (≥ 2; :data:`DEFAULT_RUNS` = 10, see there).
    seed : seed of the realizations (``numpy.random.default_rng(seed)``).
    timeout : wall-clock limit (s) for the student's box (import and all runs).
    model : the problem (report 000's defaults when None).
    alpha : family-wise false-alarm rate of each consistency test.
    tol : distance (units of the optimal σ) within which P and x̂ count as equal.
    sandbox : ``"auto"``, ``"bwrap"`` or ``"basic"`` (:mod:`gpsaccel.check.sandbox`).
    limits : the box's limits (:class:`sandbox.Limits`; its ``time`` is replaced by ``timeout``).
    allow_gpsaccel : let the submission import gpsaccel (e.g. for the model matrices).

    The optimal filter is run only after the box is empty: no process of the student's is alive
    while the answer is in memory.  Returns a :class:`~gpsaccel.check.report.Report`; it does not
    raise for anything the student's file does.  Arguments of the caller are validated
    (ValueError naming the argument).
    """
    t0 = time.perf_counter()
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    seed = _v.integer("seed", seed, minimum=0)
    timeout = _v.positive_float("timeout", timeout)
    alpha = _v.probability("alpha", alpha)
    tol = _v.positive_float("tol", tol)
    if limits is not None and not isinstance(limits, sb.Limits):
        raise ValueError(f"limits must be a gpsaccel.check.sandbox.Limits, got {limits!r}")
    limits = sb.Limits(**{**vars(limits or sb.Limits()), "time": timeout})
    backend = sb.resolve_backend(sandbox)
    path = Path(path)
    report = Report(path.name)
    report.details.update({"path": str(path), "n_runs": n_runs, "seed": seed, "timeout": timeout,
                           "sandbox": backend})
    try:
        sub = sb.load_submission(path, FUNCTION)
    except sb.SubmissionError as exc:
        code = "no-kalman-filter" if exc.code == "no-function" else exc.code
        report.add(code, str(exc))
        report.seconds = time.perf_counter() - t0
        return report
    if sub.files != (sub.entry,):
        report.details["files"] = list(sub.files)
        report.details["entry"] = sub.entry
    data = _data(model, n_runs, seed)
    box, x, P = run_student(sub, data.z, limits, backend, allow_gpsaccel)
    report.details["student_seconds"] = round(box.seconds, 3)
    if _run_findings(report, box, limits, n_runs, data.model, allow_gpsaccel) and \
            _value_findings(report, x, P, data.model.t_gps):
        problem = with_answer(data)  # the box is empty: now the answer may exist
        P_ok, x_ok = _comparison(report, problem, x, P, tol)
        if P_ok and x_ok:
            report.add("matches-optimal", f"P and x̂ match the optimal filter to "
                       f"{tol:g} σ on all {n_runs} runs.", "note")
        elif not _recognised_output_mistake(report, problem, x, P, box.returned or {}, tol):
            _diagnosis_findings(report, problem, x, P, tol)
        if "low-precision" not in report.codes:  # float32's P is not symmetric to 1e-9
            _consistency(report, problem, x, P, alpha)
    report.sort()
    report.seconds = time.perf_counter() - t0
    return report


def assert_submission(path: str | os.PathLike, **kwargs: object) -> Report:
    """:func:`submission` for a grader cell: raise AssertionError with the findings if it fails."""
    report = submission(path, **kwargs)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
