r"""One checker, several homework problems: each described by its contract, data, answer and mistakes.

A :class:`Problem` says

* the **contract**: which functions the student's file defines, their inputs and outputs with
  shapes and units (:attr:`Problem.functions`; ``required="any"`` when one of them is enough);
* how the checker **simulates** the data it calls them on (:meth:`Problem.cases`, from a seed);
* the **reference** answer on that data and the **tolerance** that separates every honest way of
  computing it from every catalogued mistake (:meth:`Problem.evaluate`, :attr:`Problem.tolerance`);
* the **catalogue** of known mistakes, from the system's package (:meth:`Problem.codes`).

:meth:`Problem.check` is the same for every problem: read which functions the file defines
(without running it), simulate, call the student's functions in a child process
(:func:`gpsaccel.check.student.call_functions`), turn whatever went wrong into findings, then
compare with the reference and diagnose.  The result is the one :class:`~gpsaccel.check.report.
Report` type of the package.

The problems (:data:`PROBLEMS`):

``calibration``  report 000: ``kalman_filter(z) -> (x_hat, P)`` (:mod:`gpsaccel.check.whole_filter`).
``coop``         report 002: ``ekf(y, Q, R)`` and/or ``lkf(y, Q, R) -> (x_hat, P)``
                 (:class:`CoopProblem`).
``ship``         report 004: ``multirate_filter(z, u) -> (x_hat, P)`` (:class:`ShipProblem`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.check import sandbox as sb
from gpsaccel.check.report import Report
from gpsaccel.check.student import Call, Output, StudentCalls, call_functions, defines
from gpsaccel.kalman import consistency

#: Characters of printed output beyond which a check warns.
OUTPUT_WARN = 20_000


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
    """A homework problem (module docstring); subclasses fill in the parts."""

    name: str = ""
    title: str = ""
    functions: tuple[Function, ...] = ()
    required: str = "all"
    #: What the tolerance is and why (shown in reports and the README).
    tolerance: str = ""
    default_runs: int = 4

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

    def evaluate(self, report: Report, cases, function: Function,
                 results: list[dict[str, np.ndarray]]) -> None:
        """Compare with the reference, diagnose, add the informational statistics."""
        raise NotImplementedError

    # ---------------------------------------------------------------- the check
    def check(self, path: str | os.PathLike, n_runs: int | None = None, seed: int = 0,
              timeout: float = 60, sandbox: str = "auto", limits: object = None,
              allow_gpsaccel: bool = False) -> Report:
        """Check the student's file ``path``; never raises for what the file does.

        ``sandbox``, ``limits`` and ``allow_gpsaccel`` go to the sandbox
        (:mod:`gpsaccel.check.sandbox`); the reference answers are computed only after the
        student's box is gone (and no answer of an earlier check is kept meanwhile).
        """
        t0 = time.perf_counter()
        n_runs = self.default_runs if n_runs is None else _v.integer("n_runs", n_runs, minimum=2)
        seed = _v.integer("seed", seed, minimum=0)
        timeout = _v.positive_float("timeout", timeout)
        path = Path(path)
        report = Report(path.name)
        report.details.update({"path": str(path), "problem": self.name, "n_runs": n_runs,
                               "seed": seed, "timeout": timeout})
        try:
            entry = self._entry(path)
        except sb.SubmissionError as exc:
            report.add(exc.code, str(exc))
            report.seconds = time.perf_counter() - t0
            return report
        present = [f for f in self.functions if defines(entry, f.name)]
        missing = [f for f in self.functions if f not in present]
        if not present or (self.required == "all" and missing):
            names = " and ".join(f.signature for f in (missing or self.functions))
            report.add("no-function", f"Your file does not define {names} at top level "
                       f"(read without running it). " + self.describe().split("\n", 1)[1])
            report.seconds = time.perf_counter() - t0
            return report
        cases = self.cases(n_runs, seed)
        calls, spans = [], []
        for f in present:
            mine = self.calls(cases, f)
            spans.append((f, len(calls), len(calls) + len(mine)))
            calls += mine
        self.forget()  # no reference answer exists while the student's code runs
        got = call_functions(path, calls, timeout, sandbox=sandbox, limits=limits,
                             allow_gpsaccel=allow_gpsaccel)
        report.details["student_seconds"] = round(got.seconds, 3)
        self._process_findings(report, got, calls, timeout)
        if got.failure is None:
            for f, a, b in spans:
                self._returned_notes(report, got, f)
                self.evaluate(report, cases, f, got.results[a:b])
        report.sort()
        report.seconds = time.perf_counter() - t0
        return report

    def _entry(self, path: Path) -> Path:
        """The file of the submission ``path`` (a ``.py`` file, or one student's folder) that
        defines the contract's functions (the first of them it finds; see
        :func:`gpsaccel.check.sandbox.load_submission`).  Raises ``SubmissionError``."""
        error: sb.SubmissionError | None = None
        for f in self.functions:
            try:
                sub = sb.load_submission(path, f.name)
            except sb.SubmissionError as exc:
                if exc.code != "no-function":
                    raise
                error = error or exc
            else:
                return sub.root / sub.entry
        if path.is_file():
            return path  # a file defining none: the "no-function" finding below names them all
        assert error is not None
        raise error

    def _returned_notes(self, report: Report, got: StudentCalls, f: Function) -> None:
        for name, desc in got.returned.get(f.name, {}).items():
            typ = desc.get("type", "")
            if typ in ("builtins.list", "builtins.tuple"):
                report.add("returns-list", f"{f.name}: {name} is a Python {typ.split('.')[-1]}; "
                           f"it was converted with np.array. Return numpy arrays.", "note")

    def _process_findings(self, report: Report, got: StudentCalls, calls: list[Call],
                          timeout: float) -> None:
        if got.output_chars > OUTPUT_WARN:
            report.add("prints-a-lot", f"Your code printed {got.output_chars:,} characters during "
                       f"the check; remove debug prints. The last lines were:\n"
                       + _indent_tail(got.output, 6), "warning")
        p = got.problem or {}
        call = calls[p["call"]] if "call" in p and p["call"] < len(calls) else None
        what = f"{call.function}(...) on call {p['call'] + 1} of {len(calls)}" if call else ""
        kind = got.failure
        if kind is None:
            return
        if kind == "timeout":
            report.add("timeout", f"Your code did not finish within {timeout:g} s: it completed "
                       f"{p.get('calls_done', 0)} of {len(calls)} calls. "
                       + ("It never returned once: look for a loop that never ends or input()."
                          if not p.get("calls_done") else "It is too slow."))
        elif kind == "crashed":
            report.add("crashed", f"The Python process running your file ended without a result "
                       f"(exit code {p.get('returncode')}). Its last output:\n"
                       + _indent_tail(got.output, 8))
        elif kind == "import-error":
            report.add("import-error", "Your file raises an error when it is imported; the "
                       "traceback ends with:\n" + _indent(p.get("traceback", "")))
        elif kind == "no-function":
            report.add("no-function", f"{p.get('function')} is not a function of your module "
                       f"once it is imported. Functions it defines: "
                       f"{', '.join(p.get('callables', [])) or 'none'}.")
        elif kind == "exception":
            report.add("exception", f"{what} raised an exception; the traceback ends with:\n"
                       + _indent(p.get("traceback", "")))
        elif kind == "return-value":
            ret = p.get("returned", {})
            report.add("return-value", f"{what} must return a pair (x_hat, P); it returned a "
                       f"{ret.get('type')}" + (f" with {p['length']} items"
                                               if p.get("length") is not None else "")
                       + ". End it with: return x_hat, P.")
        elif kind == "not-numeric":
            report.add("not-numeric", f"{p.get('name')} returned by {what} is not an array of "
                       f"numbers: {p.get('error', '').rstrip('.')}.")
        elif kind == "wrong-shape":
            shape, want = tuple(p.get("shape", ())), tuple(p.get("expected", ()))
            hint = ""
            if len(shape) == len(want) and shape == tuple(reversed(want[-2:])) + ():
                hint = " It looks transposed."
            elif shape and want and shape[0] in (want[0] - 1, want[0] + 1):
                hint = (f" It has {shape[0]} rows: one row per time step t_0..t_K, row 0 the "
                        f"initial estimate ({want[0]} rows).")
            elif len(shape) == 3 and len(want) == 3 and shape[1:] == want[:1] + want[1:2]:
                hint = " Time must be the first axis (P[k] is one covariance)."
            report.add("wrong-shape", f"{what} returned {p.get('name')} of shape {shape}; the "
                       f"contract says {want}.{hint}")
        else:  # a limit of the sandbox (memory-limit, output-limit, uses-checker, ...)
            report.add(kind, f"Your code was stopped: {got.detail or kind}"
                       + (f" ({what})" if what else "") + ".")


def _indent(text: str, n: int = 6) -> str:
    return "\n".join(" " * n + line for line in text.splitlines())


def _indent_tail(text: str, lines: int) -> str:
    return _indent("\n".join(text.rstrip().splitlines()[-lines:]) or "(nothing)")


def _nan_finding(report: Report, fname: str, name: str, arr: np.ndarray, t: np.ndarray,
                 labels: list[str]) -> bool:
    bad = ~np.isfinite(arr)
    if not bad.any():
        return False
    runs = np.flatnonzero(bad.reshape(bad.shape[0], -1).any(axis=1))
    first = np.argwhere(bad[runs[0]])[0]
    report.add("nan-output", f"{fname}: {name} contains NaN or inf in {runs.size} of "
               f"{arr.shape[0]} runs; in {labels[runs[0]]} first at t = {t[first[0]]:g} s "
               f"(row {first[0]}). Likely causes: an array from np.empty never filled at that "
               f"row, a division by zero, an inverse of a singular matrix.")
    return True


def _distances(x: np.ndarray, P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray,
               diff=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|Δx̂|/σ (..., n) and |ΔP|/(σσ) (..., n, n), σ = √diag P_ref; and σ."""
    sd = np.sqrt(np.diagonal(P_ref, axis1=-2, axis2=-1))
    d = (x - x_ref) if diff is None else diff(x, x_ref)
    return (np.abs(d) / sd, np.abs(P - P_ref) / (sd[..., :, None] * sd[..., None, :]), sd)


def _first_departure(dx: np.ndarray, dP: np.ndarray, tol_x: float, tol_P: float, t: np.ndarray,
                     states: list[str], labels: list[str], x: np.ndarray, x_ref: np.ndarray,
                     sd: np.ndarray) -> str:
    """Where the output first leaves the reference (earliest time over runs)."""
    bad_x = (dx > tol_x).any(axis=(0, 2))
    bad_P = (dP > tol_P).any(axis=(0, 2, 3))
    kx = int(np.argmax(bad_x)) if bad_x.any() else None
    kP = int(np.argmax(bad_P)) if bad_P.any() else None
    parts = []
    if kP is not None:
        i, j = np.unravel_index(int(np.argmax(dP[:, kP].max(axis=0))), dP.shape[-2:])
        parts.append(f"P first departs at t = {t[kP]:g} s (row {kP}), element P{i + 1}{j + 1}"
                     + (" — P at t = 0 must be the initial P₀" if kP == 0 else ""))
    if kx is not None:
        r, s = np.unravel_index(int(np.argmax(dx[:, kx])), dx[:, kx].shape)
        parts.append(f"x̂ first departs at t = {t[kx]:g} s (row {kx}) in {labels[r]}: "
                     f"{states[s]} = {x[r, kx, s]:.6g}, the reference gives "
                     f"{x_ref[r, kx, s]:.6g} (σ = {sd[r, kx, s]:.3g})")
    return "; ".join(parts)


def _nearest(candidates: list[tuple[object, np.ndarray, np.ndarray]], x: np.ndarray,
             P: np.ndarray, x_ref: np.ndarray, P_ref: np.ndarray, tol_x: float, tol_P: float,
             diff=None) -> tuple[object, float] | None:
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


# ============================================================================ calibration
class CalibrationProblem(Problem):
    """Report 000's filter; checked by :func:`gpsaccel.check.whole_filter.submission`."""

    name = "calibration"
    title = "Report 000: GPS/accelerometer calibration filter (3 states, 200 Hz + 5 Hz GPS)"
    functions = (Function("kalman_filter", (Argument("z", (151, 2), "GPS − integrated "
                                                      "accelerometer [δp (m), δv (m/s)] at t = 0, "
                                                      "0.2, ..., 30 s"),),
                          (Output("x_hat", (151, 3)), Output("P", (151, 3, 3))),
                          "the a posteriori [δp, δv, b] and P at every GPS time"),)
    tolerance = "1e-6 σ in x̂ and P (see gpsaccel.check.whole_filter)"
    default_runs = None

    def codes(self) -> tuple[str, ...]:
        from gpsaccel.calibration.mistakes import codes

        return codes()

    def check(self, path, n_runs=None, seed=0, timeout=60, **options) -> Report:
        from gpsaccel.check.whole_filter import submission

        if n_runs is not None:
            options["n_runs"] = n_runs
        report = submission(path, seed=seed, timeout=timeout, **options)
        report.details["problem"] = self.name
        return report


# ============================================================================ coop
@dataclass(frozen=True, eq=False)
class CoopCases:
    """The coop checker's data: truth runs (x (R, K+1, 6), y) and the course log as run R."""

    model: object
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
                 results: list[dict[str, np.ndarray]]) -> None:
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
            report.add("no-state-wrap", f"{fname}: {m.message} (largest |heading| returned: "
                       f"{heading:.3g} rad).")
        asym = float(np.abs(P - np.swapaxes(P, -1, -2)).max(axis=(0, 1)).max()
                     / np.abs(np.diagonal(P, axis1=-2, axis2=-1)).max())
        if asym > 1e-10:
            m = next(m for m in cm.catalogue(self.model, kind) if m.code == "p-not-symmetric")
            report.add("p-not-symmetric", f"{fname}: your P is not symmetric (|P − Pᵀ| up to "
                       f"{asym:.2g} of the largest variance). {m.message}", "note")
        if dx.max() <= tol_x and dP.max() <= tol_P:
            report.add("matches-reference", f"{fname}: x̂ and P match the reference "
                       f"{kind.upper()} to {tol_x:g} σ / {tol_P:g} σσ on all "
                       f"{len(results)} logs" + (" (the headings modulo 2π)"
                                                  if heading > np.pi + 1e-6 else "") + ".",
                       "note")
        else:
            cands = []
            for m in cm.catalogue(self.model, kind):
                if m.code in ("no-state-wrap", "p-not-symmetric"):
                    continue
                o = self._reference(cases, kind, (m,))
                cands.append((m, o.x_hat, o.P))
            found = _nearest(cands, x, P, ref.x_hat, ref.P, tol_x, tol_P,
                              cm.wrapped_difference)
            if found and found[1] <= 1.0:
                m = found[0]
                report.add(m.code, f"{fname}: {m.message} (your output matches the filter that "
                           f"makes this mistake, variant “{m.variant}”, on every log.)")
                report.details[kind]["matched"] = {"code": m.code, "variant": m.variant}
            else:
                where = _first_departure(dx, dP, tol_x, tol_P, t, states, list(cases.labels),
                                         x, ref.x_hat, sd)
                hint = ""
                if found and found[1] <= 10.0:
                    hint = (f" The nearest known mistake is {found[0]}, within "
                            f"{found[1]:.2g}× the tolerance of your output; look there first.")
                else:
                    hint = " No catalogued mistake matches."
                report.add("filter-mismatch", f"{fname}: your x̂, P differ from the reference "
                           f"{kind.upper()} given the same Q and R (by up to {dx.max():.3g} σ in "
                           f"x̂ and {dP.max():.3g} σσ in P).{hint} {where}.")
        self._consistency(report, cases, kind, x, P)

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
            report.add("p-not-positive-definite", f"{kind}: P is not positive definite at some "
                       f"step, so NEES cannot be formed.", "warning")
            return
        b6, b5 = consistency.chi2_bounds(6, N), consistency.chi2_bounds(5, N)
        f6, f5 = consistency.fraction_inside(nees, b6), consistency.fraction_inside(nis, b5)
        report.details[kind].update({"nees_fraction_inside_95": f6, "nis_fraction_inside_95": f5,
                                     "nees_mean": float(nees.mean()),
                                     "nis_mean": float(nis.mean())})
        report.add("nees-nis", f"{kind}: information on the Q passed to your filter, not part of "
                   f"the verdict. Over {N} truth runs the average NEES is inside its 95 % χ² "
                   f"bounds [{b6[0]:.2f}, {b6[1]:.2f}] at {100 * f6:.0f} % of the steps (mean "
                   f"{nees.mean():.3g}, expected 6) and the average NIS (from your x̂, P through "
                   f"the model's prediction) inside [{b5[0]:.2f}, {b5[1]:.2f}] at "
                   f"{100 * f5:.0f} % (mean {nis.mean():.3g}, expected 5); about 95 % is what a "
                   f"well-tuned Q gives.", "note")


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

    model: object
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
                 results: list[dict[str, np.ndarray]]) -> None:
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
            report.add("matches-optimal", f"x̂ and P match the optimal multirate filter to "
                       f"{tol:g} σ on all {len(results)} voyages (the dropout voyage included).",
                       "note")
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
                where = _first_departure(dx, dP, tol, tol, t, [s for s, _ in STATES], labels,
                                         x, x_ref, sd)
                hint = " No catalogued mistake matches."
                if found and found[1] <= 10.0:
                    hint = (f" The nearest known mistake is {found[0][0]}, within "
                            f"{found[1]:.2g}× the tolerance; look there first.")
                report.add("filter-mismatch", f"Your x̂, P differ from the optimal multirate "
                           f"filter (by up to {dx.max():.3g} σ in x̂ and {dP.max():.3g} σσ in "
                           f"P).{hint} {where}.")
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
        msgs = {
            "zeroed-gain": f"Your update computes the full gain M Hᵀ (H M Hᵀ + V)⁻¹ as if every "
                           f"sensor had reported and zeroes the columns of the missing ones (the "
                           f"report's filter). That gain is near-optimal but not optimal: {cost}. "
                           f"Use only the rows that arrived: K = M H_aᵀ (H_a M H_aᵀ + V_aa)⁻¹.",
            "report-covariance": "Your P is the report's (I − K H) M, which is the covariance "
                                 "of the optimal gain only; with any other gain it is not the "
                                 "covariance of your error (and not symmetric). Use the Joseph "
                                 "form (I − K H) M (I − K H)ᵀ + K V Kᵀ.",
            "monorate-gain": f"At the GPS fixes your filter applies the gain of the monorate "
                             f"filter (all sensors every step), as the report's loop does, "
                             f"instead of its own gain from its own M: {cost}.",
            "no-input": "Your prediction leaves out the known input: x̄_(k+1) = Φ x̂_k + B u_k "
                        "(u[k] drives the step from t_k to t_(k+1)).",
        }
        for code in v.codes:
            report.add(code, msgs[code])

    def _consistency(self, report: Report, cases: ShipCases, x: np.ndarray,
                     P: np.ndarray) -> None:
        R = x.shape[0] - 1  # the regular voyages (the dropout one left out)
        e = cases.x_true[:R, 1:] - x[:R, 1:]
        try:
            nees = consistency.nees(e, P[:R, 1:]).mean(axis=0)
        except np.linalg.LinAlgError:
            report.add("p-not-positive-definite", "P is not positive definite at some step, so "
                       "NEES cannot be formed.", "warning")
            return
        b = consistency.chi2_bounds(9, R)
        f = consistency.fraction_inside(nees, b)
        report.details["ship"]["nees_fraction_inside_95"] = f
        report.add("nees", f"Information, not the verdict: over {R} voyages the average NEES "
                   f"(your x̂ and P against the truth) is inside its 95 % χ² bounds "
                   f"[{b[0]:.2f}, {b[1]:.2f}] at {100 * f:.0f} % of the steps (mean "
                   f"{nees.mean():.3g}, expected 9).", "note")


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
PROBLEMS: dict[str, Problem] = {}


def get(problem: str | Problem) -> Problem:
    """The problem named ``problem`` ("calibration", "coop", "ship"), or ``problem`` itself."""
    if isinstance(problem, Problem):
        return problem
    name = _v.choice("problem", problem, ("calibration", "coop", "ship"))
    if name not in PROBLEMS:
        PROBLEMS[name] = {"calibration": CalibrationProblem, "coop": CoopProblem,
                          "ship": ShipProblem}[name]()
    return PROBLEMS[name]


def submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
               **options: object) -> Report:
    """Check the student's file ``path`` for ``problem``; the options are those of
    :meth:`Problem.check` (n_runs, seed, timeout; the calibration problem takes every option of
    :func:`gpsaccel.check.whole_filter.submission`)."""
    return get(problem).check(path, **options)


def assert_submission(path: str | os.PathLike, *, problem: str | Problem = "calibration",
                      **options: object) -> Report:
    """:func:`submission` for a grader cell: raise AssertionError with the findings if it fails."""
    report = submission(path, problem=problem, **options)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
