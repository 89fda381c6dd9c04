r"""Report 002's problem: the student's ``ekf(y, Q, R)`` and/or ``lkf(y, Q, R) -> (x_hat, P)``
against the reference EKF and LKF on simulated truth runs and the course log
(:class:`CoopProblem`; the filters and the catalogue of mistakes are
:mod:`gpsaccel.coop.mistakes`').
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.problem import Argument, Function, Problem
from gpsaccel.check.problems.compare import (
    distances,
    first_departure,
    nan_finding,
    nearest_within,
)
from gpsaccel.check.report import Report
from gpsaccel.check.wording import STUDENT
from gpsaccel.kalman import consistency
from gpsaccel.problems import PROBLEM_TITLES
from gpsaccel.sandbox import Call, Output


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
    title = PROBLEM_TITLES["coop"]
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

    def prepare(self) -> None:
        """The model's nominal trajectory (x* from x0 under u0, solve_ivp: the LKF's and some
        catalogue entries' linearization point), integrated once per process
        (:meth:`gpsaccel.coop.model.CoopModel.nominal` keeps it): the model's, no data, no
        filter run.  Every filter run on the cases is an answer, computed after the box."""
        self.model.nominal()

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

    def _reference(self, cases: CoopCases, kind: str, mistakes: tuple = (),
                   steps: int | None = None):
        """The reference (no mistakes) or a catalogue filter on the cases; cached, since every
        check of a class runs on the same cases.  ``steps``: its first rows only (not kept)."""
        from gpsaccel.coop import mistakes as cm
        from gpsaccel.coop.filters import run_batch

        if steps is not None:
            return run_batch(kind, self.model, cases.y, self.Q(kind), self.model.Rtrue,
                             ingredients=cm.ingredients(mistakes), steps=steps)
        key = (id(cases), kind, mistakes)
        if key not in self._cache:
            if len(self._cache) > 64:
                self._cache.clear()
            out = cm.run(self.model, cases.y, self.Q(kind), self.model.Rtrue, kind, mistakes)
            self._cache[key] = (out, cases)  # cases kept alive so its id stays unique
        return self._cache[key][0]

    def evaluate(self, report: Report, cases: CoopCases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        # a filter that runs away (1e108, 1e308) is judged as any other: its distances overflow
        # to inf (far), never a warning or an error of the checker
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            self._evaluate(report, cases, function, results, returned)

    def _evaluate(self, report: Report, cases: CoopCases, function: Function,
                  results: list[dict[str, np.ndarray]], returned: dict) -> None:
        from gpsaccel.coop import mistakes as cm
        from gpsaccel.coop.model import STATES

        kind, fname = function.name, function.name
        t = self.model.t
        x = np.stack([r["x_hat"] for r in results])
        P = np.stack([r["P"] for r in results])
        if nan_finding(report, fname, "x_hat", x, t, list(cases.labels)) or \
                nan_finding(report, fname, "P", P, t, list(cases.labels)):
            return
        ref = self._reference(cases, kind)
        tol_x, tol_P = self.TOL[kind]
        dx, dP, sd = distances(x, P, ref.x_hat, ref.P, cm.wrapped_difference)
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
            where = first_departure(dx, dP, tol_x, tol_P, t, states, list(cases.labels),
                                     x, ref.x_hat, sd)
            self._match_catalogue(report, cases, kind, x, P, ref, (dx, dP), where)
        self._consistency(report, cases, kind, x, P)

    def _match_catalogue(self, report: Report, cases: CoopCases, kind: str, x: np.ndarray,
                         P: np.ndarray, ref, dist: tuple[np.ndarray, np.ndarray],
                         where: tuple[str, str]) -> None:
        """A failing filter against each catalogue entry: its code, or a mismatch with the
        nearest entry as a hint when it is within 10× the tolerance.  ``where``: the first
        departure, the student's account and the instructor's (:func:`first_departure`)."""
        from gpsaccel.coop import mistakes as cm

        fname = kind
        tol_x, tol_P = self.TOL[kind]
        cands = [m for m in cm.catalogue(self.model, kind)
                 if m.code not in ("no-state-wrap", "p-not-symmetric") and m.checker]

        def run(m, steps: int | None) -> tuple[np.ndarray, np.ndarray]:
            try:
                o = self._reference(cases, kind, (m,), steps)
            except np.linalg.LinAlgError:  # its S turns singular: it matches nothing
                k = cases.y.shape[1] if steps is None else steps
                return (np.full((cases.y.shape[0], k, 6), np.nan),
                        np.full((cases.y.shape[0], k, 6, 6), np.nan))
            return o.x_hat, o.P

        found = nearest_within(cands, run, x, P, ref.P, tol_x, tol_P, cm.wrapped_difference,
                               x_ref=ref.x_hat)
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



def _register() -> None:
    from gpsaccel import registry

    registry.add_problem("coop", CoopProblem, system="coop", title=CoopProblem.title,
                         replace=True)


_register()
