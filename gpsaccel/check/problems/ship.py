r"""Report 004's problem: the student's ``multirate_filter(z, u) -> (x_hat, P)`` against the
optimal multirate filter on simulated voyages, one of them with sensor dropouts
(:class:`ShipProblem`; the filter's variants and the catalogue of mistakes are
:mod:`gpsaccel.ship.mistakes`').
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

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
    title = PROBLEM_TITLES["ship"]
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
        _mono.cache_clear()  # the monorate filter's gains: a filter's result, though on no data

    def run_variant(self, cases: ShipCases, variant, steps: int | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x̂ (R+1, N, 9), P (R+1, N, 9, 9), P_true) of a catalogue variant on the cases;
        ``steps``: its first rows only (not kept)."""
        return _ship_variant(cases, variant, steps)

    def evaluate(self, report: Report, cases: ShipCases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        # a filter that runs away (1e108, 1e308) is judged as any other: its distances overflow
        # to inf (far), never a warning or an error of the checker
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            self._evaluate(report, cases, function, results, returned)

    def _evaluate(self, report: Report, cases: ShipCases, function: Function,
                  results: list[dict[str, np.ndarray]], returned: dict) -> None:
        from gpsaccel.ship import mistakes as sm
        from gpsaccel.ship.model import STATES

        fname = function.name
        t = self.model.t
        x = np.stack([r["x_hat"] for r in results])
        P = np.stack([r["P"] for r in results])
        labels = list(cases.labels)
        if nan_finding(report, fname, "x_hat", x, t, labels) or \
                nan_finding(report, fname, "P", P, t, labels):
            return
        variants = sm.variants()
        x_ref, P_ref, _ = self.run_variant(cases, variants[0])
        tol = self.TOL
        dx, dP, sd = distances(x, P, x_ref, P_ref)
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
            def run(v, steps: int | None) -> tuple[np.ndarray, np.ndarray]:
                return self.run_variant(cases, v, steps)[:2]

            found = nearest_within(variants[1:], run, x, P, P_ref, tol, tol, x_ref=x_ref)
            if found and found[1] <= 1.0:
                v = found[0]
                self._variant_findings(report, v, self.run_variant(cases, v)[2], P_ref, dx)
            else:
                where, full = first_departure(dx, dP, tol, tol, t, [s for s, _ in STATES],
                                               labels, x, x_ref, sd)
                hint = " No catalogued mistake matches."
                if found and found[1] <= 10.0:
                    hint = (f" The nearest known mistake is {found[0]}, within "
                            f"{found[1]:.2g}× the tolerance; look there first.")
                report.add("filter-mismatch", f"Your x̂, P differ from the optimal multirate "
                           f"filter (by up to {dx.max():.3g} σ in x̂ and {dP.max():.3g} σσ in "
                           f"P).{hint} {full}.", text="Your x̂, P differ from the optimal "
                           "multirate filter (by up to {dx:.3g} σ in x̂ and {dP:.3g} σσ in P)."
                           "{hint} {where}.", where=where, observed={
                               "dx": float(dx.max()), "dP": float(dP.max()), "hint": hint})
        self._consistency(report, cases, x, P)

    def _variant_findings(self, report: Report, v, P_true: np.ndarray, P_ref: np.ndarray,
                          dx: np.ndarray) -> None:
        """The matched variant's entries as findings, each with what it costs the student's own
        filter: the exact σ excess of its error's covariance when it changes only the gains,
        else how far its estimates are from the optimal filter's (a wrong mean is no variance)."""
        from gpsaccel.ship import mistakes as sm
        from gpsaccel.ship.model import STATES

        report.details["ship"]["matched"] = list(v.codes)
        if v.gain_only:
            ex = sm.sigma_excess(P_true, P_ref)[:, 1:]  # (R+1, N−1, 9)
            worst = np.unravel_index(int(np.argmax(ex)), ex.shape)
            cost = (f"its true error σ exceeds the optimal by up to {100 * ex.max():.3g} % "
                    f"({STATES[worst[2]][0]} at t = {self.model.t[worst[1] + 1]:g} s), "
                    f"{100 * ex.mean():.2g} % on average")
        else:
            worst = np.unravel_index(int(np.argmax(dx)), dx.shape)
            cost = (f"its x̂ is up to {dx.max():.3g} σ from the optimal estimate "
                    f"({STATES[worst[2]][0]} at t = {self.model.t[worst[1]]:g} s), "
                    f"{dx.mean():.2g} σ on average over the voyages")
        for m in v.mistakes:  # the cost is the student's own filter's (its true error)
            message = (m.message.format(cost=cost) if "{cost}" in m.message
                       else f"{m.message} Cost: {cost}.")
            matches = (" Your output matches a filter that makes this mistake ({variant})."
                       if m.variant != m.code else "")
            report.add(m.code, message, text=STUDENT[m.code] + matches + " Cost: {cost}.",
                       observed={"cost": cost, "variant": m.variant})

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


def _ship_variant(cases: ShipCases, variant, steps: int | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The variant on the regular voyages (one covariance for all) and on the dropout voyage;
    cached whole, computed on the first ``steps`` rows only when ``steps`` is given (each row
    the same number: :func:`gpsaccel.ship.mistakes.run` is a causal loop)."""
    if steps is not None:
        return _run_ship_variant(cases, variant, cases.z[:, :steps])
    key = (id(cases), variant)
    if key not in _VARIANT_CACHE:
        if len(_VARIANT_CACHE) > 64:
            _VARIANT_CACHE.clear()
        # cases kept alive so its id stays unique
        _VARIANT_CACHE[key] = (*_run_ship_variant(cases, variant, cases.z), cases)
    return _VARIANT_CACHE[key][:3]


def _run_ship_variant(cases: ShipCases, variant, z: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from gpsaccel.ship import mistakes as sm

    mono = _mono(cases.model) if variant.ingredients.monorate_gain else None
    R = z.shape[0] - 1
    try:
        a = sm.run(cases.model, z[:R], cases.u, variant, mono)
        b = sm.run(cases.model, z[R:], cases.u, variant, mono)
    except np.linalg.LinAlgError:  # a mistaken filter whose S is singular: it matches nothing
        nan = np.full((R + 1,) + z.shape[1:2] + (9, 9), np.nan)
        return np.full(z.shape, np.nan), nan, nan
    x = np.concatenate([a.x_hat, b.x_hat])
    P = np.concatenate([np.broadcast_to(a.P, (R,) + a.P.shape), b.P[None]])
    Pt = np.concatenate([np.broadcast_to(a.P_true, (R,) + a.P.shape), b.P_true[None]])
    return x, P, Pt


@lru_cache(maxsize=2)
def _mono(model) -> np.ndarray:
    from gpsaccel.ship.mistakes import monorate_gains

    return monorate_gains(model)



def _register() -> None:
    from gpsaccel import registry

    registry.add_problem("ship", ShipProblem, system="ship", title=ShipProblem.title,
                         replace=True)


_register()
