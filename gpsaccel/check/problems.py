r"""One checker, several homework problems: each described by its contract, data, answer and mistakes.

A :class:`Problem` says

* the **contract**: which functions the student's file defines, their inputs and outputs with
  shapes and units (:attr:`Problem.functions`; ``required="any"`` when one of them is enough);
* how the checker **simulates** the data it calls them on (:meth:`Problem.cases`, from a seed);
* the **reference** answer on that data and the **tolerance** that separates every honest way of
  computing it from every catalogued mistake (:meth:`Problem.evaluate`, :attr:`Problem.tolerance`);
* the **catalogue** of known mistakes, from the system's package (:meth:`Problem.codes`).

:meth:`Problem.check` is the same for every problem: load the submission (a file or one
student's folder, :func:`gpsaccel.sandbox.load_submission`), read which functions it defines
(without running it), simulate, call the student's functions in the sandbox
(:func:`gpsaccel.sandbox.run`), turn whatever went wrong into findings with the one
:func:`gpsaccel.check.findings.box_findings` (each problem's wording as data), then compare with
the reference and diagnose.  The result is the one :class:`~gpsaccel.check.report.
Report` type of the package.

The problems (registered in :mod:`gpsaccel.registry`):

``calibration``  report 000: ``kalman_filter(z) -> (x_hat, P)`` (:mod:`gpsaccel.check.whole_filter`,
                 on the linear pipeline of :mod:`gpsaccel.check.linear`).
``tracker``      a constant-velocity tracker (:mod:`gpsaccel.check.tracker`), defined with
                 :meth:`Problem.linear` as an instructor would.
``coop``         report 002: ``ekf(y, Q, R)`` and/or ``lkf(y, Q, R) -> (x_hat, P)``
                 (:class:`CoopProblem`).
``ship``         report 004: ``multirate_filter(z, u) -> (x_hat, P)`` (:class:`ShipProblem`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel import sandbox as sb
from gpsaccel.check.findings import MESSAGES, box_findings, mistake_finding
from gpsaccel.check.report import Report
from gpsaccel.check.wording import STUDENT
from gpsaccel.kalman import consistency
from gpsaccel.sandbox import Call, Output, defines


@dataclass(frozen=True)
class Argument:
    """One input of a contract function: name, shape (None for a size given in the text), meaning."""

    name: str
    shape: tuple[int, ...]
    meaning: str


@dataclass(frozen=True)
class Function:
    """One function of a contract: its name, inputs and outputs (the sandbox's ``Output``)."""

    name: str
    args: tuple[Argument, ...]
    outputs: tuple[Output, ...]
    meaning: str

    @property
    def signature(self) -> str:
        return (f"{self.name}({', '.join(a.name for a in self.args)}) -> "
                f"({', '.join(o.name for o in self.outputs)})")


class Problem:
    """A homework problem (module docstring); subclasses fill in the parts.

    The hooks: :meth:`cases` (the data, from a seed), :meth:`calls` (the sandbox calls of one
    contract function on them), :meth:`evaluate` (compare, diagnose, add statistics),
    :meth:`forget` (drop every cached answer before the student runs), :meth:`labels` (a name per
    call, for messages); the wording: :attr:`messages` (code -> template, over
    :data:`gpsaccel.check.findings.MESSAGES`), :attr:`renames` (a box failure reported under
    another code) and :meth:`message_fields`.
    """

    name: str = ""
    title: str = ""
    functions: tuple[Function, ...] = ()
    required: str = "all"
    #: What the tolerance is and why (shown in reports and the README).
    tolerance: str = ""
    default_runs: int = 4
    #: code -> message template overriding :data:`gpsaccel.check.findings.MESSAGES`.
    messages: dict[str, str] = {}
    #: a box failure -> the code this problem reports it under.
    renames: dict[str, str] = {}

    @staticmethod
    def linear(name: str, **model: object) -> Problem:
        """A problem for any linear model (Φ, Γ, W, H, V, M0, x0 and the schedule ``every``,
        ``n_epochs``, ``dt``), checked against the generic catalogue of linear-filter mistakes:
        see :func:`gpsaccel.check.linear.linear` for the arguments."""
        from gpsaccel.check.linear import linear

        return linear(name, **model)  # type: ignore[arg-type]

    # ---------------------------------------------------------------- the contract
    def describe(self) -> str:
        """The contract as text, for students."""
        lines = [f"{self.title}", "Your file defines " + (
            "one or more of:" if self.required == "any" else "all of:")]
        for f in self.functions:
            lines.append(f"  {f.signature}: {f.meaning}")
            for a in f.args:
                lines.append(f"      {a.name} {a.shape}: {a.meaning}")
            for o in f.outputs:
                lines.append(f"      returns {o.name} {o.shape}")
        return "\n".join(lines)

    def codes(self) -> tuple[str, ...]:
        """The codes of this problem's catalogue of mistakes."""
        raise NotImplementedError

    def forget(self) -> None:
        """Drop every cached reference answer (called before a student's code runs)."""

    # ---------------------------------------------------------------- to fill in
    def cases(self, n_runs: int, seed: int):
        """The data the functions are called on (cached by the subclass)."""
        raise NotImplementedError

    def calls(self, cases, function: Function) -> list[Call]:
        raise NotImplementedError

    def labels(self, cases) -> list[str]:
        """A name for each case ("run 0", "the course log"), in the order of :meth:`calls`."""
        return list(getattr(cases, "labels", ()))

    def message_fields(self, cases) -> dict[str, object]:
        """Fields of this problem's message templates (e.g. ``work``, ``rows``, ``every``)."""
        return {}

    def evaluate(self, report: Report, cases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        """Compare with the reference, diagnose, add the informational statistics.
        ``returned`` describes what the first call returned (type, dtype, shape per output)."""
        raise NotImplementedError

    # ---------------------------------------------------------------- the check
    def check(self, path: str | os.PathLike, n_runs: int | None = None, seed: int = 0,
              timeout: float = 60, sandbox: str = "auto", limits: sb.Limits | None = None,
              allow_gpsaccel: bool = False) -> Report:
        """Check the student's submission ``path`` (a ``.py`` file or one student's folder);
        never raises for what the file does.

        ``sandbox``, ``limits`` and ``allow_gpsaccel`` go to the sandbox
        (:mod:`gpsaccel.sandbox`); the reference answers are computed only after the
        student's box is gone (and no answer of an earlier check is kept meanwhile).
        """
        t0 = time.perf_counter()
        n_runs = self.default_runs if n_runs is None else _v.integer("n_runs", n_runs, minimum=2)
        seed = _v.integer("seed", seed, minimum=0)
        timeout = _v.positive_float("timeout", timeout)
        if limits is not None and not isinstance(limits, sb.Limits):
            raise ValueError(f"limits must be a gpsaccel.sandbox.Limits, got {limits!r}")
        limits = sb.Limits(**{**vars(limits or sb.Limits()), "time": timeout})
        backend = sb.resolve_backend(sandbox)
        path = Path(path)
        report = Report(path.name)
        report.details.update({"path": str(path), "problem": self.name, "n_runs": n_runs,
                               "seed": seed, "timeout": timeout, "sandbox": backend})
        try:
            sub = self._submission(path)
        except sb.SubmissionError as exc:
            report.add(self.renames.get(exc.code, exc.code), text="{error}",
                       observed={"error": str(exc)})  # about the student's own files
            report.seconds = time.perf_counter() - t0
            return report
        if sub.files != (sub.entry,):
            report.details["files"] = list(sub.files)
            report.details["entry"] = sub.entry
        entry = sub.root / sub.entry
        present = [f for f in self.functions if defines(entry, f.name)]
        missing = [f for f in self.functions if f not in present]
        if not present:  # the runner says what the file does define (read by importing it)
            present = [self.functions[0]]
        elif self.required == "all" and missing:
            names = " and ".join(f.signature for f in missing)
            report.add("no-function", text="Your file does not define {names} at top level "
                       "(read without running it). {contract}", observed={
                           "names": names, "contract": self.describe().split("\n", 1)[1]})
            report.seconds = time.perf_counter() - t0
            return report
        cases = self.cases(n_runs, seed)
        calls: list[Call] = []
        spans: list[tuple[Function, int, int]] = []
        for f in present:
            mine = self.calls(cases, f)
            spans.append((f, len(calls), len(calls) + len(mine)))
            calls += mine
        labels = self.labels(cases) * len(present)
        self.forget()  # no reference answer exists while the student's code runs
        box = sb.run(sub, calls, limits, backend, allow_gpsaccel)
        box = self._accept_columns(report, sub, box, calls, limits, backend, allow_gpsaccel)
        report.details["student_seconds"] = round(box.seconds, 3)
        fields = {"signature": " or ".join(f.signature for f in self.functions),
                  **self.message_fields(cases)}
        if box_findings(report, box, calls, limits, self.messages, labels, self.renames,
                        **fields):
            for f, a, b in spans:
                self.evaluate(report, cases, f, box.results[a:b], box.returned or {})
        report.sort()
        report.seconds = time.perf_counter() - t0
        return report

    def _submission(self, path: Path) -> sb.Submission:
        """The submission at ``path``: its entry is the file defining the contract's functions
        (the first of them found; :func:`gpsaccel.sandbox.load_submission`)."""
        error: sb.SubmissionError | None = None
        for f in self.functions:
            try:
                return sb.load_submission(path, f.name)
            except sb.SubmissionError as exc:
                if exc.code != "no-function":
                    raise
                error = error or exc
        if path.is_file():  # a file defining none: the runner names what it does define
            return sb.Submission(path.resolve().parent, path.name, (path.name,))
        assert error is not None
        raise error

    def _accept_columns(self, report: Report, sub: sb.Submission, box: sb.BoxResult,
                        calls: list[Call], limits: sb.Limits, backend: str,
                        allow_gpsaccel: bool) -> sb.BoxResult:
        """A filterpy filter keeps x as a column: an output of shape ``declared + (1,)`` is
        filterpy's own and is accepted (the box is run again declaring that shape, the axis is
        dropped) with a note.  Any other box comes back as it is."""
        found = _column_outputs(box, calls)
        if found is None:
            return box
        column, outs = found
        wide = [Call(c.function, c.args, tuple(
            Output(o.name, tuple(o.shape) + (1,), o.dtype) if o.name in column else o
            for o in c.outputs)) for c in calls]
        self.forget()
        again = sb.run(sub, wide, limits, backend, allow_gpsaccel)
        if again.failure is not None:
            return box
        again.results = [{k: (v[..., 0] if k in column else v) for k, v in r.items()}
                         for r in again.results]
        for name in sorted(column):
            o = next(o for o in outs if o.name == name)
            report.add("filterpy-column", severity="note", text=MESSAGES["filterpy-column"],
                       where=name, observed={"name": name, "shape": tuple(o.shape) + (1,),
                                             "wanted": tuple(o.shape)})
        return again


def _column_outputs(box: sb.BoxResult, calls: list[Call]
                    ) -> tuple[set[str], tuple[Output, ...]] | None:
    """The outputs a box returned as filterpy's columns (declared shape + (1,)) when that is its
    only wrong shape, with the call's outputs; None otherwise."""
    p = box.problem or {}
    shapes = p.get("shapes") or {}
    if box.failure != "wrong-shape" or not isinstance(p.get("call"), int):
        return None
    outs = calls[p["call"]].outputs
    column = {o.name for o in outs if tuple(shapes.get(o.name) or ()) == tuple(o.shape) + (1,)}
    if not column or any(tuple(shapes.get(o.name) or ()) != tuple(o.shape)
                         for o in outs if o.name not in column):
        return None
    return column, outs


def _nan_finding(report: Report, fname: str, name: str, arr: np.ndarray, t: np.ndarray,
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


def _distances(x: np.ndarray, P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray,
               diff=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|Δx̂|/σ (..., n) and |ΔP|/(σσ) (..., n, n), σ = √diag P_ref; and σ."""
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    d = (x - x_ref) if diff is None else diff(x, x_ref)
    return (np.abs(d) / sd, np.abs(P - P_ref) / (sd[..., :, None] * sd[..., None, :]), sd)


def _first_departure(dx: np.ndarray, dP: np.ndarray, tol_x: float, tol_P: float, t: np.ndarray,
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


def _nearest(candidates: Sequence[tuple[Any, np.ndarray, np.ndarray]], x: np.ndarray,
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


# ============================================================================ coop
@dataclass(frozen=True, eq=False)
class CoopCases:
    """The coop checker's data: truth runs (x (R, K+1, 6), y) and the course log as run R."""

    model: Any
    seed: int
    x_true: np.ndarray
    y: np.ndarray
    labels: tuple[str, ...]

    @property
    def n_truth(self) -> int:
        return self.x_true.shape[0]


class CoopProblem(Problem):
    """Report 002: the student's EKF and/or LKF, given Q and R (module docstring of
    :mod:`gpsaccel.coop.mistakes` for the filters and the catalogue).

    The data: ``n_runs`` truth runs simulated with Qtrue and Rtrue from the seed
    (:meth:`gpsaccel.coop.model.CoopModel.simulate`, 100 s at ΔT = 0.1 s) and the course's log.
    Q is the package's documented tuned Q of each filter (:func:`gpsaccel.coop.filters.tuned_q`)
    unless given, R is Rtrue; x̂_0 = x0 and P_0 = P0 of the model are part of the contract.

    Tolerance.  The EKF is compared to 1e-4 σ in x̂ and P (units of the reference √diag P): the
    closed-form step and ``solve_ivp`` over each ΔT at its default tolerances (RK45, rtol 1e-3)
    agree with the reference to 5e-11 σ (measured on 4 runs), while the nearest mistake
    (``jacobian-point``: H at x̂_k) is 0.04 σ away.  The LKF depends on its nominal trajectory:
    one ``solve_ivp`` call over the whole 100 s at default tolerances moves x̂ by up to 0.26 σ and
    P by 3e-4 σσ (measured), so the LKF is compared to 1 σ in x̂ and 1e-2 σσ in P; its nearest
    mistake (``epoch-shift``) is 3.9 σ and 0.8 σσ away.  Headings are compared modulo 2π.
    """

    name = "coop"
    title = "Report 002: cooperative localization, EKF and LKF (6 states, 5 measurements)"
    required = "any"
    default_runs = 4
    TOL = {"ekf": (1e-4, 1e-4), "lkf": (1.0, 1e-2)}
    tolerance = ("EKF 1e-4 σ in x̂ and P; LKF 1 σ in x̂ and 1e-2 σσ in P (its nominal "
                 "trajectory may come from solve_ivp at default tolerances); headings modulo 2π")

    def __init__(self, Q: dict | None = None) -> None:
        from gpsaccel.coop.model import CoopModel

        self.model = CoopModel()
        K1 = self.model.n_steps + 1
        args = (Argument("y", (K1, 5), "the log in rows: y[k] at t_k = k·0.1 s, [γag (rad), ρ (m), "
                                       "γga (rad), ξa (m), ηa (m)], row 0 NaN"),
                Argument("Q", (6, 6), "process-noise covariance per step"),
                Argument("R", (5, 5), "measurement-noise covariance"))
        outs = (Output("x_hat", (K1, 6)), Output("P", (K1, 6, 6)))
        self.functions = (
            Function("ekf", args, outs, "the EKF from x̂_0 = x0 = [10, 0, π/2, −60, 0, −π/2], "
                                        "P_0 = P0 = diag(1, 1, 0.025, 1, 1, 0.025); u = "
                                        "[2, −π/18, 12, π/25], L = 0.5 m, ΔT = 0.1 s; row k "
                                        "is x̂, P at t_k"),
            Function("lkf", args, outs, "the LKF about the nominal from x0 (solve_ivp or closed "
                                        "form); row k is x̂ = x* + δx̂, P at t_k"))
        self._Q = Q or {}
        self._cache: dict = {}

    def forget(self) -> None:
        self._cache.clear()

    def Q(self, kind: str) -> np.ndarray:
        from gpsaccel.coop.filters import tuned_q

        return np.asarray(self._Q.get(kind, tuned_q(kind, self.model)), dtype=float)

    def codes(self) -> tuple[str, ...]:
        from gpsaccel.coop.mistakes import codes

        return tuple(dict.fromkeys(codes("ekf") + codes("lkf")))

    def cases(self, n_runs: int, seed: int) -> CoopCases:
        return _coop_cases(n_runs, seed)

    def calls(self, cases: CoopCases, function: Function) -> list[Call]:
        Q, R = self.Q(function.name), self.model.Rtrue
        return [Call(function.name, (y, Q, R), function.outputs) for y in cases.y]

    def _reference(self, cases: CoopCases, kind: str, mistakes: tuple = ()):
        """The reference (no mistakes) or a catalogue filter on the cases; cached, since every
        check of a class runs on the same cases."""
        from gpsaccel.coop import mistakes as cm

        key = (id(cases), kind, mistakes)
        if key not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            out = cm.run(self.model, cases.y, self.Q(kind), self.model.Rtrue, kind, mistakes)
            self._cache[key] = (out, cases)  # cases kept alive so its id stays unique
        return self._cache[key][0]

    def evaluate(self, report: Report, cases: CoopCases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        from gpsaccel.coop import mistakes as cm
        from gpsaccel.coop.model import STATES

        kind, fname = function.name, function.name
        t = self.model.t
        x = np.stack([r["x_hat"] for r in results])
        P = np.stack([r["P"] for r in results])
        if _nan_finding(report, fname, "x_hat", x, t, list(cases.labels)) or \
                _nan_finding(report, fname, "P", P, t, list(cases.labels)):
            return
        ref = self._reference(cases, kind)
        tol_x, tol_P = self.TOL[kind]
        dx, dP, sd = _distances(x, P, ref.x_hat, ref.P, cm.wrapped_difference)
        states = [s for s, _ in STATES]
        report.details[kind] = {"max_dx_sigma": float(dx.max()), "max_dP_sigma": float(dP.max()),
                                "tolerance_x_sigma": tol_x, "tolerance_P_sigma": tol_P,
                                "Q": self.Q(kind).tolist()}
        report.tables.append(f"{kind}: against the reference {kind.upper()} with the same Q and R "
                             f"on {cases.n_truth} truth runs and the course log (units of the "
                             f"reference σ; tolerance {tol_x:g} in x̂, {tol_P:g} in P):\n"
                             f"  max |Δx̂|/σ = {dx.max():.3g}   max |ΔP|/(σσ) = {dP.max():.3g}")
        heading = cm.heading_range(x)
        if heading > np.pi + 1e-6:
            m = next(m for m in cm.catalogue(self.model, kind) if m.code == "no-state-wrap")
            mistake_finding(report, m, f"{fname}: ", heading=f"{heading:.3g} rad")
        asym = float(np.abs(P - np.swapaxes(P, -1, -2)).max(axis=(0, 1)).max()
                     / np.abs(np.diagonal(P, axis1=-2, axis2=-1)).max())
        if asym > 1e-10:
            m = next(m for m in cm.catalogue(self.model, kind) if m.code == "p-not-symmetric")
            report.add("p-not-symmetric", f"{fname}: your P is not symmetric. {m.message}",
                       "note", text="{fname}: your P is not symmetric (|P − Pᵀ| up to {asym:.2g} "
                       "of the largest variance). " + STUDENT["p-not-symmetric"],
                       observed={"fname": fname, "asym": asym})
        if dx.max() <= tol_x and dP.max() <= tol_P:
            report.add("matches-reference", severity="note", text="{fname}: x̂ and P match the "
                       "reference {kind} to {tol_x:g} σ / {tol_P:g} σσ on all {n} logs{mod}.",
                       observed={"fname": fname, "kind": kind.upper(), "tol_x": tol_x,
                                 "tol_P": tol_P, "n": len(results),
                                 "mod": " (the headings modulo 2π)"
                                 if heading > np.pi + 1e-6 else ""})
        else:
            where = _first_departure(dx, dP, tol_x, tol_P, t, states, list(cases.labels),
                                     x, ref.x_hat, sd)
            self._match_catalogue(report, cases, kind, x, P, ref, (dx, dP), where)
        self._consistency(report, cases, kind, x, P)

    def _match_catalogue(self, report: Report, cases: CoopCases, kind: str, x: np.ndarray,
                         P: np.ndarray, ref, dist: tuple[np.ndarray, np.ndarray],
                         where: tuple[str, str]) -> None:
        """A failing filter against each catalogue entry: its code, or a mismatch with the
        nearest entry as a hint when it is within 10× the tolerance.  ``where``: the first
        departure, the student's account and the instructor's (:func:`_first_departure`)."""
        from gpsaccel.coop import mistakes as cm

        fname = kind
        tol_x, tol_P = self.TOL[kind]
        cands = []
        for m in cm.catalogue(self.model, kind):
            if m.code in ("no-state-wrap", "p-not-symmetric") or not m.checker:
                continue
            o = self._reference(cases, kind, (m,))
            cands.append((m, o.x_hat, o.P))
        found = _nearest(cands, x, P, ref.x_hat, ref.P, tol_x, tol_P, cm.wrapped_difference)
        if found and found[1] <= 1.0:
            m = found[0]
            mistake_finding(report, m, f"{fname}: ")
            report.details[kind]["matched"] = {"code": m.code, "variant": m.variant}
            return
        if found and found[1] <= 10.0:
            hint = (f" The nearest known mistake is {found[0]}, within "
                    f"{found[1]:.2g}× the tolerance of your output; look there first.")
        else:
            hint = " No catalogued mistake matches."
        dx, dP = dist
        student, full = where
        report.add("filter-mismatch", text="{fname}: your x̂, P differ from the "
                   "reference {kind} given the same Q and R (by up to {dx:.3g} σ in x̂ "
                   "and {dP:.3g} σσ in P).{hint} {where}.", where=student, observed={
                       "fname": fname, "kind": kind.upper(), "dx": float(dx.max()),
                       "dP": float(dP.max()), "hint": hint},
                   message=f"{fname}: your x̂, P differ from the reference {kind.upper()} "
                   f"(by up to {dx.max():.3g} σ in x̂ and {dP.max():.3g} σσ in P).{hint} "
                   f"{full}.")

    def _consistency(self, report: Report, cases: CoopCases, kind: str, x: np.ndarray,
                     P: np.ndarray) -> None:
        """NEES and NIS over the truth runs: information about Q, never the verdict."""
        from gpsaccel.coop import mistakes as cm
        from gpsaccel.coop.model import h, measurement_residual

        N, m = cases.n_truth, self.model
        xs, Ps = x[:N, :-1], P[:N, :-1]
        try:
            e = cm.wrapped_difference(cases.x_true[:, 1:], x[:N, 1:])
            nees = consistency.nees(e, P[:N, 1:]).mean(axis=0)
            x_bar = m.step(xs)  # the model's prediction from your x̂_k (headings wrapped)
            F = m.F(xs)
            M = F @ Ps @ np.swapaxes(F, -1, -2) + self.Q(kind)
            H = m.C(x_bar)
            S = H @ M @ np.swapaxes(H, -1, -2) + m.Rtrue
            r = measurement_residual(cases.y[:N, 1:], h(x_bar))
            nis = consistency.nis(r, S).mean(axis=0)
        except np.linalg.LinAlgError:
            report.add("p-not-positive-definite", severity="warning", text="{kind}: P is not "
                       "positive definite at some step, so NEES cannot be formed.",
                       observed={"kind": kind})
            return
        b6, b5 = consistency.chi2_bounds(6, N), consistency.chi2_bounds(5, N)
        f6, f5 = consistency.fraction_inside(nees, b6), consistency.fraction_inside(nis, b5)
        report.details[kind].update({"nees_fraction_inside_95": f6, "nis_fraction_inside_95": f5,
                                     "nees_mean": float(nees.mean()),
                                     "nis_mean": float(nis.mean())})
        report.add("nees-nis", severity="note", text="{kind}: information on the Q passed "
                   "to your filter, not part of the verdict. Over {N} truth runs the average NEES "
                   "is inside its 95 % χ² bounds at {f6:.0f} % of the steps (mean {nees:.3g}) "
                   "and the average NIS (from your x̂, P through the model's prediction) inside "
                   "its bounds at {f5:.0f} % (mean {nis:.3g}); about 95 % is what a well-tuned "
                   "Q gives.", observed={"kind": kind, "N": N, "f6": 100 * f6, "f5": 100 * f5,
                                         "nees": float(nees.mean()), "nis": float(nis.mean())},
                   expected={"nees_bounds": tuple(map(float, b6)),
                             "nis_bounds": tuple(map(float, b5))})


@lru_cache(maxsize=4)
def _coop_cases(n_runs: int, seed: int) -> CoopCases:
    from gpsaccel.coop.model import CoopModel

    model = CoopModel()
    truth = model.simulate(np.random.default_rng(seed), n_runs)
    y = np.concatenate([truth.y, model.log()[None]])
    labels = tuple(f"truth run {i}" for i in range(n_runs)) + ("the course log",)
    return CoopCases(model, seed, truth.x, y, labels)


# ============================================================================ ship
@dataclass(frozen=True, eq=False)
class ShipCases:
    """The ship checker's data: z (R+1, N, 9) in the multirate layout (the last run with sensor
    dropouts), the input u (N−1, 3) and the true states x (R+1, N, 9)."""

    model: Any
    seed: int
    z: np.ndarray
    u: np.ndarray
    x_true: np.ndarray
    labels: tuple[str, ...]


class ShipProblem(Problem):
    """Report 004: the student's ``multirate_filter(z, u)`` against the optimal multirate filter.

    The data: ``n_runs`` voyages of :class:`~gpsaccel.ship.model.ShipModel` from the seed (GPS at
    1 Hz, IMU at 10 Hz, 100 s) and one more with sensor dropouts (each IMU component missing at
    random 5 % of the time, two GPS fixes missing), so a filter must use the rows that arrived,
    not a fixed pattern.  Tolerance 1e-6 σ in x̂ and P: the covariance, Joseph, information and
    filterpy forms agree to ~1e-13 σ; the nearest mistake (``zeroed-gain``) is 0.03 σ away.
    """

    name = "ship"
    title = "Report 004: the ship's multirate GPS/IMU filter (9 states)"
    default_runs = 4
    TOL = 1e-6
    tolerance = "1e-6 σ in x̂ and P"

    def __init__(self) -> None:
        from gpsaccel.ship.model import ShipModel

        self.model = ShipModel()
        N = self.model.n_samples
        self.functions = (Function(
            "multirate_filter",
            (Argument("z", (N, 9), "row k the sensors at t_k = 0.1 k s in state order, NaN "
                                   "where a sensor did not report (row 0 all NaN)"),
             Argument("u", (N - 1, 3), "the known input [F_x (N), F_y (N), τ (N m)] from t_k "
                                       "to t_(k+1)")),
            (Output("x_hat", (N, 9)), Output("P", (N, 9, 9))),
            f"x̂ and P at every step k = 0..{N - 1}; row 0 is x̂_0 = x0 = "
            f"[{', '.join(repr(float(v)) for v in self.model.x0)}] (the plan's start), "
            f"P_0 = M0 = diag{tuple(float(v) for v in np.diag(self.model.M0))} "
            f"(ShipModel's Φ, B, Q = ΓWΓᵀ, H = I, V)"),)

    def codes(self) -> tuple[str, ...]:
        from gpsaccel.ship.mistakes import CODES

        return CODES

    def cases(self, n_runs: int, seed: int) -> ShipCases:
        return _ship_cases(n_runs, seed)

    def calls(self, cases: ShipCases, function: Function) -> list[Call]:
        return [Call(function.name, (z, cases.u), function.outputs) for z in cases.z]

    def forget(self) -> None:
        _VARIANT_CACHE.clear()

    def run_variant(self, cases: ShipCases, variant) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x̂ (R+1, N, 9), P (R+1, N, 9, 9), P_true) of a catalogue variant on the cases."""
        return _ship_variant(cases, variant)

    def evaluate(self, report: Report, cases: ShipCases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        from gpsaccel.ship import mistakes as sm
        from gpsaccel.ship.model import STATES

        fname = function.name
        t = self.model.t
        x = np.stack([r["x_hat"] for r in results])
        P = np.stack([r["P"] for r in results])
        labels = list(cases.labels)
        if _nan_finding(report, fname, "x_hat", x, t, labels) or \
                _nan_finding(report, fname, "P", P, t, labels):
            return
        variants = sm.variants()
        x_ref, P_ref, _ = self.run_variant(cases, variants[0])
        tol = self.TOL
        dx, dP, sd = _distances(x, P, x_ref, P_ref)
        report.details["ship"] = {"max_dx_sigma": float(dx.max()), "max_dP_sigma": float(dP.max()),
                                  "tolerance_sigma": tol}
        report.tables.append(f"against the optimal multirate filter on {len(results)} voyages "
                             f"(units of the optimal σ, tolerance {tol:g}):\n"
                             f"  max |Δx̂|/σ = {dx.max():.3g}   max |ΔP|/(σσ) = {dP.max():.3g}")
        if dx.max() <= tol and dP.max() <= tol:
            report.add("matches-optimal", severity="note", text="x̂ and P match the optimal "
                       "multirate filter to {tol:g} σ on all {n} voyages (the dropout voyage "
                       "included).", observed={"tol": tol, "n": len(results)})
        else:
            cands = []
            for v in variants[1:]:
                xv, Pv, Ptv = self.run_variant(cases, v)
                cands.append(((v, Ptv), xv, Pv))
            found = _nearest(cands, x, P, x_ref, P_ref, tol, tol)
            if found and found[1] <= 1.0:
                (v, Ptv) = found[0]
                self._variant_findings(report, v, Ptv, P_ref)
            else:
                where, full = _first_departure(dx, dP, tol, tol, t, [s for s, _ in STATES],
                                               labels, x, x_ref, sd)
                hint = " No catalogued mistake matches."
                if found and found[1] <= 10.0:
                    hint = (f" The nearest known mistake is {found[0][0]}, within "
                            f"{found[1]:.2g}× the tolerance; look there first.")
                report.add("filter-mismatch", f"Your x̂, P differ from the optimal multirate "
                           f"filter (by up to {dx.max():.3g} σ in x̂ and {dP.max():.3g} σσ in "
                           f"P).{hint} {full}.", text="Your x̂, P differ from the optimal "
                           "multirate filter (by up to {dx:.3g} σ in x̂ and {dP:.3g} σσ in P)."
                           "{hint} {where}.", where=where, observed={
                               "dx": float(dx.max()), "dP": float(dP.max()), "hint": hint})
        self._consistency(report, cases, x, P)

    def _variant_findings(self, report: Report, v, P_true: np.ndarray, P_ref: np.ndarray) -> None:
        from gpsaccel.ship import mistakes as sm
        from gpsaccel.ship.model import STATES

        report.details["ship"]["matched"] = list(v.codes)
        ex = sm.sigma_excess(P_true, P_ref)[:, 1:]  # (R+1, N−1, 9)
        worst = np.unravel_index(int(np.argmax(ex)), ex.shape)
        cost = (f"its true error σ exceeds the optimal by up to {100 * ex.max():.3g} % "
                f"({STATES[worst[2]][0]} at t = {self.model.t[worst[1] + 1]:g} s), "
                f"{100 * ex.mean():.2g} % on average")
        for code in v.codes:  # the cost is the student's own filter's (its true error)
            report.add(code, sm.MESSAGES[code].format(cost=cost),
                       text=STUDENT[code] + " Cost: {cost}.", observed={"cost": cost})

    def _consistency(self, report: Report, cases: ShipCases, x: np.ndarray,
                     P: np.ndarray) -> None:
        R = x.shape[0] - 1  # the regular voyages (the dropout one left out)
        e = cases.x_true[:R, 1:] - x[:R, 1:]
        try:
            nees = consistency.nees(e, P[:R, 1:]).mean(axis=0)
        except np.linalg.LinAlgError:
            report.add("p-not-positive-definite", severity="warning", text="P is not positive "
                       "definite at some step, so NEES cannot be formed.")
            return
        b = consistency.chi2_bounds(9, R)
        f = consistency.fraction_inside(nees, b)
        report.details["ship"]["nees_fraction_inside_95"] = f
        report.add("nees", severity="note", text="Information, not the verdict: over {R} "
                   "voyages the average NEES (your x̂ and P against the truth) is inside its "
                   "95 % χ² bounds at {inside:.0f} % of the steps (mean {mean:.3g}; about 95 % "
                   "is what a consistent filter gives).", observed={
                       "R": R, "inside": 100 * f, "mean": float(nees.mean())},
                   expected={"bounds": (float(b[0]), float(b[1]))})


@lru_cache(maxsize=4)
def _ship_cases(n_runs: int, seed: int) -> ShipCases:
    from gpsaccel.ship.mistakes import schedule_z
    from gpsaccel.ship.model import ShipModel
    from gpsaccel.ship.simulation import simulate_ensemble

    model = ShipModel()
    rng = np.random.default_rng(seed)
    ens = simulate_ensemble(model, n_runs + 1, rng)
    z = schedule_z(model, ens.z)
    drop = z[-1]
    imu = [c for c in range(9) if c not in (0, 3)]
    lost = rng.random((model.n_samples, len(imu))) < 0.05
    drop[:, imu] = np.where(lost, np.nan, drop[:, imu])
    fixes = np.flatnonzero(np.isfinite(drop[:, 0]))
    for k in rng.choice(fixes, 2, replace=False):
        drop[k, [0, 3]] = np.nan
    labels = tuple(f"voyage {i}" for i in range(n_runs)) + ("the voyage with sensor dropouts",)
    return ShipCases(model, seed, z, ens.u, ens.x, labels)


_VARIANT_CACHE: dict = {}


def _ship_variant(cases: ShipCases, variant) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from gpsaccel.ship import mistakes as sm

    key = (id(cases), variant)
    if key not in _VARIANT_CACHE:
        if len(_VARIANT_CACHE) > 64:
            _VARIANT_CACHE.clear()
        mono = _mono(cases.model)
        R = cases.z.shape[0] - 1
        a = sm.run(cases.model, cases.z[:R], cases.u, variant, mono)
        b = sm.run(cases.model, cases.z[R:], cases.u, variant, mono)
        x = np.concatenate([a.x_hat, b.x_hat])
        P = np.concatenate([np.broadcast_to(a.P, (R,) + a.P.shape), b.P[None]])
        Pt = np.concatenate([np.broadcast_to(a.P_true, (R,) + a.P.shape), b.P_true[None]])
        _VARIANT_CACHE[key] = (x, P, Pt, cases)  # cases kept alive so its id stays unique
    return _VARIANT_CACHE[key][:3]


@lru_cache(maxsize=2)
def _mono(model) -> np.ndarray:
    from gpsaccel.ship.mistakes import monorate_gains

    return monorate_gains(model)


# ============================================================================ the registry
def get(problem: str | Problem) -> Problem:
    """The registered problem named ``problem`` (:mod:`gpsaccel.registry`: "calibration",
    "coop", "ship", "tracker", and any an instructor added), or ``problem`` itself."""
    if isinstance(problem, Problem):
        return problem
    from gpsaccel import registry

    if not isinstance(problem, str):
        raise ValueError(f"problem must be a problem name or a Problem, got {problem!r}")
    return registry.problem(problem)  # type: ignore[return-value]


def submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
               **options: object) -> Report:
    """Check the student's submission ``path`` (a ``.py`` file or one student's folder) for
    ``problem``; the options are those of :meth:`Problem.check` (n_runs, seed, timeout, sandbox,
    limits, allow_gpsaccel)."""
    return get(problem).check(path, **options)  # type: ignore[arg-type]


def assert_submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
                      **options: object) -> Report:
    """:func:`submission` for a grader cell: raise AssertionError with the findings if it fails."""
    report = submission(path, problem=problem, **options)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report


def _register() -> None:
    from gpsaccel import registry

    registry.add_problem("coop", CoopProblem, system="coop", title=CoopProblem.title,
                         replace=True)
    registry.add_problem("ship", ShipProblem, system="ship", title=ShipProblem.title,
                         replace=True)


_register()
