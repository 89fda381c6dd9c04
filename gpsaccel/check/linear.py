r"""The checker of a linear filter, for any linear model: compare with the one optimal answer, then
diagnose against a catalogue of mistakes.

A student's ``kalman_filter(z) -> (x_hat, P)`` is run (in the sandbox, by :meth:`Problem.check`)
on realizations simulated from a seed; with every student process gone the optimal filter runs on
the same z, and the two are compared in units of the optimal σ = √diag P_ref::

    d_P = max |P_ij − P_ref,ij| / (σ_i σ_j)     d_x = max |x̂_i − x̂_ref,i| / σ_i

It passes when both are within ``tol`` (1e-6) on every run.  A failing filter is diagnosed in
this order (each would otherwise read as a wrong V or M0):

1. mistakes in what is returned (:meth:`LinearProblem.output_mistake`): ``aliased-output``,
   ``state-between-calls``, ``low-precision`` (float32), ``p-scaled``, ``epoch-shift``, and a
   skipped update at the first row that departs — x̂ = x̄ and P = M there (``update-skipped``,
   ``last-update-missing`` at the last epoch), P = M only (``covariance-update-skipped``) or
   x̂ = x̄ only (``mean-update-skipped``);
2. the catalogue (:class:`gpsaccel.kalman.mistakes.Catalogue`, matched by
   :mod:`gpsaccel.check.linear_diagnosis`): P does not depend on the data, so P is matched first
   against every covariance mistake and every combination of up to three that touch different
   ingredients, then x̂ against the matched entry with the mean mistakes;
3. otherwise the first departure is located (t = 0: the update; later: the propagation), with
   the nearest catalogue entry as a hint when it is within :data:`HINT_FACTOR` × tol.

Then consistency over the runs with the student's own P (mean error and average NEES, each a
Bonferroni family at ``alpha``) is reported as information: it never decides ``passed``
(:mod:`gpsaccel.check.linear_consistency`).

:class:`LinearProblem` holds this for any :class:`~gpsaccel.kalman.linear_model.LinearModel`
(``check.Problem.linear(...)``, the generic catalogue); the calibration problem
(:mod:`gpsaccel.check.problems.calibration`) is the same class with report 000's simulation, catalogue
and wording.
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from gpsaccel import _validation as _v
from gpsaccel._feedback import describe_miss
from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.linear_consistency import RUNAWAY, consistency
from gpsaccel.check.linear_diagnosis import (  # noqa: F401 - the diagnosis's names, re-exported
    TOLERANCE,
    Answer,
    CandidateFilters,
    Candidates,
    Cases,
    Diagnosis,
    answer,
    candidate_filters,
    candidates,
    diagnose,
)
from gpsaccel.check.problem import Argument, Function, Problem
from gpsaccel.check.report import Report, used
from gpsaccel.kalman.consistency import covariance_distance, sigma_distance
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_messages import MESSAGES
from gpsaccel.kalman.linear_model import LinearModel
from gpsaccel.kalman.mistakes import Catalogue, Mistake
from gpsaccel.sandbox import Call, Output

#: The nearest catalogued mistake is shown as a hint only within this factor of the tolerance.
HINT_FACTOR = 10.0

#: Covariance entries a diagnosis combines at most (report 003's filter makes three at once).
COMBINED = 3

#: Largest distances (σσ in P, σ in x̂) at which a float32 filter counts as "right but low
#: precision" (measured on report 000's 6000 steps: 8e-5 σσ in P, 0.035 σ in x̂).
LOW_PRECISION = (1e-3, 0.1)

#: code -> template of the diagnosis's findings: the generic linear problem's one table of
#: wording (:mod:`gpsaccel.kalman.linear_messages`; a problem overrides entries in ``messages``).
FINDINGS = MESSAGES


def _float32_exact(a: np.ndarray) -> bool:
    """Every value of ``a`` is a float32 number (what a float32 computation returns)."""
    return bool(np.all(a.astype(np.float32).astype(np.float64) == a))


def _covariances(P: np.ndarray) -> bool:
    """Whether every matrix of P (..., n, n) is finite with a positive diagonal and a Cholesky
    factor (a covariance)."""
    if not np.isfinite(P).all() or (np.diagonal(P, axis1=-2, axis2=-1) <= 0).any():
        return False
    try:
        np.linalg.cholesky((P + np.swapaxes(P, -1, -2)) / 2)
    except np.linalg.LinAlgError:
        return False
    return True


class LinearProblem(Problem):
    """``kalman_filter(z) -> (x_hat, P)`` for a linear model, checked as the module docstring says.

    Subclasses (or :meth:`Problem.linear`) give :meth:`catalogue`, :meth:`simulate`, the epoch
    times :attr:`t`, the state names :attr:`states`, :attr:`every` and :attr:`n_steps`.
    """

    function_name = "kalman_filter"
    default_runs = 10
    tolerance = "1e-6 σ in x̂ and P (units of the optimal σ)"
    #: what one propagation step is called in messages
    step = "propagation step"
    t: np.ndarray
    states: tuple[str, ...]
    every: int = 1
    n_steps: int = 0

    def __init__(self, alpha: float = 0.01, tol: float = TOLERANCE) -> None:
        self.alpha = _v.probability("alpha", alpha)
        self.tol = _v.positive_float("tol", tol)
        self._candidates: dict[int, tuple[list[tuple[Mistake, ...]], np.ndarray]] = {}
        self._built: dict[int, CandidateFilters] = {}

    # ------------------------------------------------------------------------- the hooks
    def catalogue(self) -> Catalogue:
        raise NotImplementedError

    def simulate(self, n_runs: int, seed: int) -> Cases:
        raise NotImplementedError

    def answer(self, cases: Cases) -> Answer:
        """The optimal answer on the cases (computed only once no student process is alive)."""
        return answer(self.catalogue().build(), cases.z)

    def candidates(self, max_combined: int = 3) -> tuple[list[tuple[Mistake, ...]], np.ndarray]:
        if max_combined not in self._candidates:
            self._candidates[max_combined] = candidates(self.catalogue(), max_combined)
        return self._candidates[max_combined]

    def candidate_filters(self, max_combined: int = COMBINED) -> CandidateFilters:
        """The catalogue's candidate filters, built (never run) once for this problem: what
        every file's diagnosis shares (:class:`~gpsaccel.check.linear_diagnosis
        .CandidateFilters`), kept across :meth:`forget` since it holds no answer."""
        if max_combined not in self._built:
            self._built[max_combined] = candidate_filters(self.catalogue(), max_combined)
        return self._built[max_combined]

    def prepare(self) -> None:
        self.candidate_filters(COMBINED)

    def forget(self) -> None:
        self._candidates.clear()

    def codes(self) -> tuple[str, ...]:
        cat = self.catalogue()
        return tuple(dict.fromkeys(m.code for m in cat.covariance_mistakes()
                                   + cat.mean_mistakes()))

    def text(self, key: str, **fields: object) -> str:
        return {**FINDINGS, **self.messages}[key].format(**fields)

    def add(self, report: Report, code: str, severity: str = "error", *,
            expected: dict | None = None, **fields: object) -> None:
        """A finding worded by the template of ``code``: every field here is the student's
        (their output's distances, times, rows) or the check's; ``expected`` (the optimal
        filter's numbers) goes to the instructor only."""
        template = {**FINDINGS, **self.messages}[code]
        report.add(code, severity=severity, text=template, observed=used(template, fields),
                   expected=expected, where=str(fields.get("where", "")))

    # -------------------------------------------------------------------- the contract
    def contract(self, n_meas: int, meaning: str = "") -> tuple[Function, ...]:
        """The one function ``kalman_filter(z) -> (x_hat, P)`` for this problem's sizes."""
        k, n = len(self.t), len(self.states)
        return (Function(self.function_name, (Argument("z", (k, n_meas), meaning or
                                                        "the measurements, row i at t_i"),),
                         (Output("x_hat", (k, n)), Output("P", (k, n, n))),
                         "the a posteriori x̂ and P at every measurement time"),)

    def cases(self, n_runs: int, seed: int) -> Cases:
        return self.simulate(n_runs, seed)

    def calls(self, cases: Cases, function: Function) -> list[Call]:
        return [Call(function.name, (cases.z[r],), function.outputs)
                for r in range(cases.z.shape[0])]

    def labels(self, cases: Cases) -> list[str]:
        return [f"run {r}" for r in range(cases.z.shape[0])]

    def message_fields(self, cases: Cases) -> dict[str, object]:
        t = self.t
        return {"every": self.every,
                "rows": f"one row per measurement time t = {t[0]:g}, {t[1]:g}, ..., {t[-1]:g} s",
                "work": f"{self.n_steps} {self.step}s per run should take well under a second"}

    # ---------------------------------------------------------------------- the verdict
    def evaluate(self, report: Report, cases: Cases, function: Function,
                 results: list[dict[str, np.ndarray]], returned: dict) -> None:
        # a filter that runs away returns 1e108 or 1e308, its own result: judged as any other,
        # its distances overflowing to inf (far), never a warning or an error of the checker
        with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
            self._evaluate(report, cases, results, returned)

    def _evaluate(self, report: Report, cases: Cases, results: list[dict[str, np.ndarray]],
                  returned: dict) -> None:
        x = np.stack([r["x_hat"] for r in results])
        P = np.stack([r["P"] for r in results])
        if not self._finite(report, x, P):
            return
        ans = self.answer(cases)  # the box is empty: now the answer may exist
        P_ok, x_ok = self._comparison(report, ans, x, P)
        if P_ok and x_ok:
            self.add(report, "matches-optimal", "note", tol=self.tol, n_runs=x.shape[0])
        elif not self.output_mistake(report, cases, ans, x, P, returned):
            self._diagnosis(report, cases, ans, x, P)
        if "low-precision" not in report.codes:  # float32's P is not symmetric to 1e-9
            self._consistency(report, cases, ans, x, P)

    def _where(self, idx: tuple, kind: str) -> str:
        if kind == "x":
            r, i, s = idx
            return f"run {r}, t = {self.t[i]:g} s, {self.states[s]}"
        i, a, b = idx[-3:]
        return f"t = {self.t[i]:g} s, element P{a + 1}{b + 1}"

    def _finite(self, report: Report, x: np.ndarray, P: np.ndarray) -> bool:
        """NaN/inf in what came back; True when everything is finite."""
        for name, arr in (("x_hat", x), ("P", P)):
            bad = ~np.isfinite(arr)
            if bad.any():
                runs = np.flatnonzero(bad.reshape(bad.shape[0], -1).any(axis=1))
                first = np.argwhere(bad[runs[0]])[0]
                before = np.abs(arr[runs[0], :first[0]])
                top = float(before.max()) if before.size else 0.0
                cause = self.text("nan-output.runaway" if top > RUNAWAY else "nan-output.causes",
                                  top=top)
                self.add(report, "nan-output", name=name,
                         what="NaN" if np.isnan(arr).any() else "inf", bad_runs=runs.size,
                         n_runs=arr.shape[0], run=int(runs[0]), t=float(self.t[first[0]]),
                         row=int(first[0]), cause=cause)
                return False
        return True

    def _comparison(self, report: Report, ans: Answer, x: np.ndarray, P: np.ndarray
                    ) -> tuple[bool, bool]:
        tol = self.tol
        dx, dP = sigma_distance(x, P, ans.x_ref, ans.P_ref, ans.sd)
        iP = np.unravel_index(int(np.argmax(dP)), dP.shape)
        ix = np.unravel_index(int(np.argmax(dx)), dx.shape)
        spread = covariance_distance(P, P[:1], ans.sd).max()
        report.details.update({
            "max_dP_sigma": float(dP.max()), "max_dP_where": self._where(iP, "P"),
            "max_dx_sigma": float(dx.max()), "max_dx_where": self._where(ix, "x"),
            "P_spread_over_runs_sigma": float(spread), "tolerance_sigma": tol,
        })
        report.tables.append(
            f"against the optimal filter on {x.shape[0]} runs (units of the optimal σ, "
            f"tolerance {tol:g}):\n"
            f"  max |ΔP|/(σσ) = {dP.max():.3g}  at {self._where(iP, 'P')}\n"
            f"  max |Δx̂|/σ   = {dx.max():.3g}  at {self._where(ix, 'x')}")
        if spread > tol:
            self.add(report, "p-depends-on-data", "warning", spread=float(spread))
        return bool(dP.max() <= tol), bool(dx.max() <= tol)

    # --------------------------------------------------------- mistakes in what is returned
    def output_mistake(self, report: Report, cases: Cases, ans: Answer, x: np.ndarray,
                       P: np.ndarray, returned: dict) -> bool:
        """Mistakes in what is returned or how calls share state, recognised before the
        catalogue (module docstring, step 1); True when one was reported."""
        sd = ans.sd
        dP = covariance_distance(P, ans.P_ref[None], sd)                   # (N, k, n, n)
        dx = np.abs(x - ans.x_ref) / sd                                     # (N, k, n)
        checks = (self._aliased, self._between_calls, self._low_precision, self._scaled,
                  self._shifted)
        return self._first_of(report, checks, cases, ans, x, P, dx, dP, returned)

    def _first_of(self, report: Report, checks, cases, ans, x, P, dx, dP, returned) -> bool:
        """Report the first of ``checks`` that recognises the output; True when one did."""
        for check in checks:
            found = check(cases, ans, x, P, dx, dP, returned)
            if found is not None:
                code, fields = found
                self.add(report, code, expected=fields.pop("expected", None), tol=self.tol,
                         t_last=float(self.t[-1]), **fields)
                if code == "state-between-calls":
                    report.findings = [f for f in report.findings
                                       if f.code != "p-depends-on-data"]
                    report.details["first_wrong_run"] = fields["run"]
                return True
        return False

    def _aliased(self, cases, ans, x, P, dx, dP, returned):
        # every row identical and equal to the last optimal one: one array object stored at
        # every time (a constant output that is not the last estimate is some other mistake)
        if x.shape[1] > 2 and np.all(P == P[:, -1:]) and np.all(x == x[:, -1:]) and \
                dP[:, -1].max() <= self.tol and dx[:, -1].max() <= self.tol:
            return "aliased-output", {}
        return None

    def _between_calls(self, cases, ans, x, P, dx, dP, returned):
        per_run = np.maximum(dP.max(axis=(1, 2, 3)), dx.max(axis=(1, 2)))
        if per_run[0] <= self.tol and (per_run > self.tol).any():
            r = int(np.argmax(per_run > self.tol))
            return "state-between-calls", {
                "what": "P" if dP[r].max() > self.tol else "x̂", "run": r, "by": per_run[r],
                "n_bad": int((per_run > self.tol).sum()), "n_runs": len(per_run)}
        return None

    def _low_precision(self, cases, ans, x, P, dx, dP, returned):
        dtypes = {(returned.get(k) or {}).get("dtype") for k in ("x_hat", "P")}
        if dP.max() <= LOW_PRECISION[0] and dx.max() <= LOW_PRECISION[1] and (
                "float32" in dtypes or (_float32_exact(x) and _float32_exact(P))):
            return "low-precision", {"dP": dP.max(), "dx": dx.max(), "n_steps": self.n_steps}
        return None

    def _scaled(self, cases, ans, x, P, dx, dP, returned):
        diag_ref = np.diagonal(ans.P_ref, axis1=-2, axis2=-1)
        c = float(np.median(np.diagonal(P, axis1=-2, axis2=-1) / diag_ref))
        if abs(c - 1) > 1e-3 and covariance_distance(P, c * ans.P_ref[None], ans.sd).max() \
                <= self.tol * max(c, 1.0):
            x_note = ("Your x̂ is right, so only the returned P is scaled." if dx.max() <= self.tol
                      else f"Your x̂ differs too (by up to {dx.max():.3g} σ): the scaled P also "
                           f"feeds your gain.")
            sym = " — P + Pᵀ without the /2 when symmetrising" if abs(c - 2) < 1e-6 else ""
            return "p-scaled", {"expected": {"factor": c}, "x_note": x_note, "sym": sym}
        return None

    def _shifted(self, cases, ans, x, P, dx, dP, returned):
        """x̂ and P (or one of them, the other right) stored one epoch off."""
        P_right, x_right = dP.max() <= self.tol, dx.max() <= self.tol
        for shift, late in ((1, "late"), (-1, "early")):
            where = self.text(f"epoch-shift.{late}")
            a = slice(1, None) if shift == 1 else slice(None, -1)
            b = slice(None, -1) if shift == 1 else slice(1, None)
            P_moved = covariance_distance(P[:, a], ans.P_ref[None, b], ans.sd[b]).max() <= self.tol
            x_moved = (np.abs(x[:, a] - ans.x_ref[:, b]) / ans.sd[b]).max() <= self.tol
            if P_moved and x_moved:
                what, other = "x̂ and P are", ""
            elif P_moved and x_right:
                what, other = "P is", self.text("epoch-shift.other", right="x̂")
            elif x_moved and P_right:
                what, other = "x̂ is", self.text("epoch-shift.other", right="P")
            else:
                continue
            return "epoch-shift", {"where": where, "end": "first" if shift == 1 else "last",
                                   "what": what, "other": other}
        return None

    def _skipped_update(self, cases, ans, x, P, dx, dP, returned):
        """The first row that departs holds the a priori x̄ and/or M of the optimal filter."""
        tol = self.tol
        bad = (dP.max(axis=(0, 2, 3)) > tol) | (dx.max(axis=(0, 2)) > tol)
        k = int(np.argmax(bad))
        if k == 0:
            return None  # the first epoch: the catalogue's first-update-skipped
        flt = self.catalogue().build()
        _, M_ref, _ = flt.gains
        x_bar = replace(flt, output="prior").apply(cases.z)[0]
        sd = ans.sd[k:k + 1]
        P_prior = covariance_distance(P[:, k:k + 1], M_ref[None, k:k + 1], sd).max() <= tol
        x_prior = (np.abs(x[:, k] - x_bar[:, k]) / ans.sd[k]).max() <= tol
        P_post = dP[:, k].max() <= tol
        x_post = dx[:, k].max() <= tol
        last = k == len(self.t) - 1
        fields = {"t": self.t[k], "row": k, "t_prev": self.t[k - 1]}
        if P_prior and x_prior:
            return ("last-update-missing" if last else "update-skipped"), fields
        if P_prior and x_post:
            return "covariance-update-skipped", fields
        if x_prior and P_post:
            return "mean-update-skipped", fields
        return None

    # -------------------------------------------------------------------- the catalogue
    def _diagnosis(self, report: Report, cases: Cases, ans: Answer, x: np.ndarray,
                   P: np.ndarray) -> None:
        tol, t = self.tol, self.t
        # only what the match reads (linear_diagnosis): the candidates' covariances are
        # computed again after every box, none is kept while a student's code runs; their
        # filters, built and never run, are the class's (candidate_filters)
        pool = Candidates(self.catalogue(), COMBINED, self.candidate_filters(COMBINED))
        diag = diagnose(P, x, cases.z, ans.sd, self.catalogue(), pool.combos, pool, tol)
        names = lambda ms: ", ".join(str(m) for m in ms)  # noqa: E731
        if diag.covariance is not None and diag.mean is not None:
            found = diag.covariance + diag.mean
            report.details["matched"] = [{"code": m.code, "variant": m.variant} for m in found]
            for m in found:
                mistake_finding(report, m, where=m.where, student=self.student)
            report.tables.append(f"catalogue: on every run your (x̂, P) match, to {tol:g} σ, "
                                 f"the filter that makes\n" + "\n".join(f"  {m}" for m in found))
            return
        if self._first_of(report, (self._skipped_update,), cases, ans, x, P,
                          np.abs(x - ans.x_ref) / ans.sd,
                          covariance_distance(P, ans.P_ref[None], ans.sd), {}):
            return  # one update missing at a row (after the catalogue: fixes-skipped is one)
        if diag.covariance is not None:  # P recognised, x̂ not
            for m in diag.covariance:
                mistake_finding(report, m, where=m.where, student=self.student)
            report.details["matched"] = [{"code": m.code, "variant": m.variant}
                                         for m in diag.covariance]
            flt = self.catalogue().build(diag.covariance)
            if not _covariances(flt.P_out):
                # that filter's P is no covariance (Joseph's form with a minus): its gains, and so
                # x̂, depend on rounding, and x̂ cannot be compared; P says what is wrong
                report.details["x_not_compared"] = "the matched filter's P is not a covariance"
                return
            xm = flt.apply(cases.z)[0]
            dx = np.abs(x - xm) / ans.sd
            i = np.unravel_index(int(np.argmax(dx)), dx.shape)
            lead = self.text("gain-or-residual.optimal" if not diag.covariance else
                             "gain-or-residual.matched", names=names(diag.covariance))
            self.add(report, "gain-or-residual", lead=lead, dx=float(dx.max()),
                     where=self._where(i, "x"), step=self.step)
            return
        dP = covariance_distance(P, ans.P_ref[None], ans.sd).max(axis=(0, 2, 3))
        first = int(np.argmax(dP > tol))
        where = self.text("p-mismatch.first" if first == 0 else "p-mismatch.later", t=t[first])
        near = diag.nearest and diag.nearest_distance <= HINT_FACTOR * tol
        hint = self.text("hint.near" if near else "hint.none", names=names(diag.nearest or ()),
                         d=diag.nearest_distance, ratio=diag.nearest_distance / tol)
        worst = covariance_distance(P[:, first:first + 1], ans.P_ref[None, first:first + 1],
                                    ans.sd[first:first + 1])[:, 0]
        r, a, b = np.unravel_index(int(np.argmax(worst)), worst.shape)
        # where and how, never the optimal filter's value (the answer itself)
        miss = describe_miss(float(P[r, first, a, b]), float(ans.P_ref[first, a, b]), typed=False)
        depart = f" Your output first departs at t = {t[first]:g} s: P{a + 1}{b + 1} {miss}."
        self.add(report, "p-mismatch", d=float(dP.max()), hint=hint, where=where, depart=depart,
                 matrices=self.text("p-mismatch.matrices"),
                 expected={f"P{a + 1}{b + 1} at t = {t[first]:g} s": float(
                     ans.P_ref[first, a, b])})
        report.details["matched"] = []

    # ------------------------------------------------------------------ the information
    def _consistency(self, report: Report, cases: Cases, ans: Answer, x: np.ndarray,
                     P: np.ndarray) -> None:
        """Consistency over the runs with the student's own P
        (:func:`gpsaccel.check.linear_consistency.consistency`), in this problem's wording."""
        consistency(report, cases, ans, x, P, t=self.t, states=self.states, alpha=self.alpha,
                    text=self.text)


# ================================================================== any model, by an instructor
class ModelProblem(LinearProblem):
    """A :class:`LinearProblem` for a :class:`~gpsaccel.kalman.linear_model.LinearModel` with the
    generic catalogue (:class:`~gpsaccel.kalman.linear_catalogue.LinearCatalogue`); see
    :meth:`Problem.linear`."""

    def __init__(self, name: str, model: LinearModel, title: str = "",
                 messages: dict[str, str] | None = None, z_meaning: str = "",
                 default_runs: int = 10, alpha: float = 0.01, tol: float = TOLERANCE) -> None:
        super().__init__(alpha=alpha, tol=tol)
        if not isinstance(model, LinearModel):
            raise ValueError(f"model must be a gpsaccel.kalman.linear_model.LinearModel, got "
                             f"{type(model).__name__}")
        if not isinstance(name, str) or not name.replace("-", "").isalnum():
            raise ValueError(f"name must be letters, digits and dashes, got {name!r}")
        self.name = name
        self.model = model
        self.title = title or f"{name}: a linear filter ({model.n} states)"
        self.messages = dict(messages or {})
        self.t, self.states = model.t, model.states
        self.every, self.n_steps = model.every, model.n_steps
        self.default_runs = _v.integer("default_runs", default_runs, minimum=2)
        self.functions = self.contract(model.H.shape[0], z_meaning)
        self._catalogue = LinearCatalogue(model, self.messages)
        self._simulated = lru_cache(maxsize=4)(self._simulate)

    def catalogue(self) -> LinearCatalogue:
        return self._catalogue

    def _simulate(self, n_runs: int, seed: int) -> Cases:
        z, x = self.model.simulate(np.random.default_rng(seed), n_runs)
        return Cases(seed, z, x)

    def simulate(self, n_runs: int, seed: int) -> Cases:
        return self._simulated(n_runs, seed)


def linear(name: str, *, Phi: ArrayLike, Gamma: ArrayLike, W: ArrayLike, H: ArrayLike,
           V: ArrayLike, M0: ArrayLike, x0: ArrayLike, every: int, n_epochs: int, dt: float = 1.0,
           states: tuple[str, ...] = (), measurements: tuple[str, ...] = (), title: str = "",
           messages: dict[str, str] | None = None, register: bool = True,
           **options: object) -> ModelProblem:
    """A homework problem for any linear model: ``kalman_filter(z) -> (x_hat, P)`` on the model
    x_{j+1} = Φ x_j + Γ w_j (w ~ N(0, W)), z_i = H x_{i·every} + v_i (v ~ N(0, V)),
    x_0 ~ N(x0, M0), with measurements at the epochs i = 0 .. n_epochs − 1 (every ``every``
    propagation steps of ``dt`` s).  It is checked as :mod:`gpsaccel.check.linear` says, against
    the generic catalogue of linear-filter mistakes (``messages`` rewords any entry, code ->
    template).  ``register`` makes ``check.submission(path, problem=name)`` and ``gpsaccel check
    --problem name`` find it.  ``options``: ``z_meaning``, ``default_runs``, ``alpha``, ``tol``.
    """
    model = LinearModel(Phi, Gamma, W, H, V, M0, x0,  # type: ignore[arg-type]  # checked there
                        every, n_epochs, dt, states, measurements)
    problem = ModelProblem(name, model, title, messages, **options)  # type: ignore[arg-type]
    if register:
        from gpsaccel import registry

        registry.add_problem(problem.name, lambda: problem, system=problem.name,
                             title=problem.title, replace=True)
    return problem
