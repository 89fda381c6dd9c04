r"""Filters side by side, each measured against the exact answer; and the conditioning sweeps.

:func:`compare` runs any number of filters on one realization of the calibration problem (the
core's :func:`gpsaccel.kalman.compare.compare`, which takes any linear model, on a realization of
report 000 drawn with its truth): the built-in forms by name
(:data:`~gpsaccel.kalman.factory.FORMS`: ``standard``, ``joseph``, ``information``,
``filterpy-information``, ``square-root``) and any callables with the checkers'
signature ``kalman_filter(z) -> (x_hat, P)`` (``z`` the (n_gps, 2) measurements, ``x_hat``
(n_gps, 3) and ``P`` (n_gps, 3, 3) a posteriori at the GPS times).  A student's *file* becomes
such a callable with :func:`gpsaccel.check.student_filter`, which runs it in a process of its own;
``gpsaccel compare FORM|FILE ...`` does that for you.

None of them is the reference.  The reference is the same filter computed with 50 significant
digits (:mod:`gpsaccel.kalman.exact`), so every number in the table is that filter's own
rounding error, in units that read the same for every state:

* ``max|dx|/sigma``: max over time and state of |x̂ − x̂*| / σ*, σ* = √diag P* (* = exact);
* ``max|dP|``:       max over time and element of |P_ij − P*_ij| / √(P*_ii P*_jj);
* ``asym``:          max over time and element of |P_ij − P_ji| / √(P*_ii P*_jj);
* ``min eig``:       smallest eigenvalue, over time, of P_ij / √(P*_ii P*_jj); the exact row shows
  the true value, a negative one means the filter's P is no longer a covariance;
* ``ms/run``:        wall-clock time of one 30-s run (best of ``repeat``; a filter that reports
  its own time, as a student's file timed in its own process does, is trusted for it).

The row "exact, rounded to float64" is the floor: the exact answer stored in float64 is already
that far from itself (half an ulp of x̂ is ~10⁻¹⁴ σ here, x̂ being ~10² σ).

:func:`sweep` makes the problem worse conditioned step by step and runs the forms at each step:

* ``"prior"``: the filter's M0 from 1 to 10¹² times the report's (a vaguer and vaguer prior; the
  data are the report's, simulated with its M0, so only the filter's arithmetic changes);
* ``"gps"``: the GPS noise V from 1 down to 10⁻¹² times the report's (a better and better receiver;
  the data are simulated with that V).

Its x-axis is the update's condition number κ = max over epochs of λmax(M P⁻¹) = λmax(S V⁻¹)
(S = H M Hᵀ + V): by how much the update shrinks the variance in the worst direction.  It is the
2-norm condition number of P^-½ M P^-½ (its smallest eigenvalue is 1: the bias is not measured),
independent of units, and 6.3·10² on the report's numbers.  Rounding in P = (I − K H) M grows like
ε κ (ε = 2⁻⁵³); that is what the Joseph and square-root forms are for.
"""

from __future__ import annotations

import concurrent.futures as cf
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.simulation import TRUTHS, simulate
from gpsaccel.kalman import compare as _core
from gpsaccel.kalman.compare import (  # noqa: F401 - the calibration names of the core's table
    Comparison,
    ComparisonRow,
    FilterCallable,
    differences,
    form_filter,
    reference_filter,
    update_condition_number,
)
from gpsaccel.kalman.exact import DIGITS, Errors, ExactResult, exact_filter
from gpsaccel.kalman.factory import FORMS

#: The sweeps of :func:`sweep` and the scale factor of their last point.
SWEEPS = ("prior", "gps")

#: Sweep points: 10⁰ … 10¹² for the prior, 10⁰ … 10⁻¹² for the GPS noise, one per decade.
DEFAULT_FACTORS = {"prior": 10.0 ** np.arange(13), "gps": 10.0 ** -np.arange(13)}


def compare(*forms: str, model: CalibrationModel | None = None, seed: int = 0,
            truth: str = "error-model", filters: Mapping[str, FilterCallable] | None = None,
            repeat: int = 3, digits: int = DIGITS, exact: ExactResult | None = None
            ) -> Comparison:
    """Run the built-in ``forms`` and the callables ``filters`` on one realization, each against
    the exact answer (:func:`gpsaccel.kalman.compare.compare` on report 000's data).

    Parameters
    ----------
    forms : names of built-in forms (see :data:`~gpsaccel.kalman.factory.FORMS`); with neither
        ``forms`` nor ``filters``, every built-in form.
    model : the problem (report 000's defaults when None).
    seed : seed of the realization (``numpy.random.default_rng(seed)``), a non-negative integer;
        None is refused, since a comparison on a realization nobody can draw again is not
        reproducible.
    truth : ``"error-model"`` or ``"kinematic"``, see :func:`gpsaccel.simulate`.
    filters : name -> ``kalman_filter(z) -> (x_hat, P)``; :func:`gpsaccel.check.student_filter`
        makes one of a student's file.  A callable that raises gets a row saying what it raised; one
        that returns the wrong shapes is an error naming it.
    repeat : each filter is timed ``repeat`` times and the best time kept.
    digits : significant decimal digits of the exact answer.
    exact : the exact answer on this realization, if already computed
        (``exact_filter(model, simulate(model, default_rng(seed), truth).z)``): the 50-digit
        answer is the comparison's dearest part, and a lesson comparing several times on one
        realization needs it once.
    """
    model = CalibrationModel() if model is None else model
    seed = _v.integer("seed", seed, minimum=0)
    truth = _v.choice("truth", truth, TRUTHS)
    repeat = _v.integer("repeat", repeat, minimum=1)
    if not forms and not filters:
        forms = tuple(FORMS)
    _core.contestants(forms, filters, model)  # bad names refused before the simulation
    z = simulate(model, np.random.default_rng(seed), truth).z
    return _core.compare(model, *forms, z=z, seed=seed, truth=truth, filters=filters,
                         repeat=repeat, digits=digits, exact=exact)


# ------------------------------------------------------------------------------ the sweeps
@dataclass(frozen=True, eq=False)
class Sweep:
    """The forms at each point of a conditioning sweep.

    kind : ``"prior"`` (M0 × factor) or ``"gps"`` (V × factor).
    factors : (n_points,) scale factors.  kappa : (n_points,) the update's condition number κ.
    cond_P : (n_points,) max over epochs of cond(P) (exact P, 2-norm, SI units).
    floor : the exact answer rounded to float64, per point (the best a float64 filter can do).
    errors : form -> per point :class:`~gpsaccel.kalman.exact.Errors` (inf if it broke down).
    problems : form -> per point what it raised (None where it ran).
    """

    kind: str
    seed: int
    factors: np.ndarray
    kappa: np.ndarray
    cond_P: np.ndarray
    floor: tuple[Errors, ...]
    errors: dict[str, tuple[Errors, ...]] = field(default_factory=dict)
    problems: dict[str, tuple[str | None, ...]] = field(default_factory=dict)

    @property
    def label(self) -> str:
        return {"prior": "M0 × factor (vaguer prior)", "gps": "V × factor (better GPS)"}[self.kind]

    def dP(self, form: str) -> np.ndarray:
        """(n_points,) max |ΔP_ij| / √(P*_ii P*_jj) of ``form``."""
        return np.array([e.dP_rel for e in self.errors[form]])

    def dx(self, form: str) -> np.ndarray:
        """(n_points,) max |Δx̂| / σ* of ``form``."""
        return np.array([e.dx_sigma for e in self.errors[form]])

    def min_eig(self, form: str) -> np.ndarray:
        """(n_points,) smallest eigenvalue of ``form``'s P in units of the exact σ."""
        return np.array([e.min_eig for e in self.errors[form]])

    def __str__(self) -> str:
        forms = list(self.errors)
        w = {f: max(9, len(f) + 1) for f in forms}
        out = [f"conditioning sweep '{self.kind}': {self.label}, seed {self.seed}"]
        for title, get, floor in (
                ("max |dP_ij| / sqrt(P*_ii P*_jj)", self.dP, [e.dP_rel for e in self.floor]),
                ("max |dx| / sigma*", self.dx, [e.dx_sigma for e in self.floor])):
            head = f"{'factor':>8} {'kappa':>8} {'cond(P)':>8} {'floor':>8} " + " ".join(
                f"{f:>{w[f]}}" for f in forms)
            out += ["", title, head, "-" * len(head)]
            cols = {f: get(f) for f in forms}
            for i, fac in enumerate(self.factors):
                cells = []
                for f in forms:
                    mark = "!" if self.errors[f][i].min_eig < 0 else " "
                    cells.append(f"{cols[f][i]:>{w[f] - 1}.1e}{mark}")
                out.append(f"{fac:8.0e} {self.kappa[i]:8.1e} {self.cond_P[i]:8.1e} "
                           f"{floor[i]:8.1e} " + " ".join(cells))
        out.append("\n! = P not positive definite (its smallest eigenvalue < 0); floor = the exact "
                   "answer rounded to float64")
        return "\n".join(out)


def sweep_model(kind: str, factor: float, base: CalibrationModel | None = None
                ) -> tuple[CalibrationModel, CalibrationModel]:
    """(the filter's model, the model the data are simulated from) at one sweep point."""
    base = CalibrationModel() if base is None else base
    kind = _v.choice("kind", kind, SWEEPS)
    factor = _v.positive_float("factor", factor)
    if kind == "prior":
        return base.replace(M0=base.M0 * factor), base
    model = base.replace(V=base.V * factor)
    return model, model


def sweep(kind: str, factors: Sequence[float] | None = None, forms: Sequence[str] | None = None,
          seed: int = 0, truth: str = "error-model", digits: int = DIGITS,
          executor: object = None, progress: bool = False) -> Sweep:
    """Run ``forms`` (default: all built-in) against the exact answer at each sweep point.

    kind : ``"prior"`` (M0 × factor, data from the report's model) or ``"gps"`` (V × factor, data
        simulated with that V).  factors : default :data:`DEFAULT_FACTORS` ``[kind]``.
    seed : one seed for every point (the same noise draws, scaled).
    executor : where the points run (:func:`gpsaccel.executors.resolve_executor`: None in this
        process, ``"processes"``, an Executor, ...).  Each point is computed whole by one worker
        with the same code, so the numbers do not depend on it; only the wall time does (a
        point's CPU is mostly the forms' 6000 predictions, one by one, as the lesson measures
        their rounding; benchmarks/lessons.py times the lesson).
    progress : a tqdm.auto bar over the points (a lesson's long cell shows progress).
    """
    kind = _v.choice("kind", kind, SWEEPS)
    return sweeps((kind,), None if factors is None else {kind: factors}, forms, seed, truth,
                  digits, executor, progress)[0]


def sweeps(kinds: Sequence[str] = SWEEPS, factors: Mapping[str, Sequence[float]] | None = None,
           forms: Sequence[str] | None = None, seed: int = 0, truth: str = "error-model",
           digits: int = DIGITS, executor: object = None, progress: bool = False
           ) -> tuple[Sweep, ...]:
    """:func:`sweep` of each of ``kinds``, their points on one executor at once, each distinct
    problem computed once: factor 1 is the report's own problem in every sweep (same filter model,
    same data), so a lesson running both sweeps would compute it twice.  ``factors``: kind ->
    factors (default :data:`DEFAULT_FACTORS`); the other arguments as :func:`sweep`'s.  The
    numbers are those of :func:`sweep` for each kind, bit for bit (a point is computed whole by
    one worker, whichever sweep asked for it)."""
    from gpsaccel.executors import resolve_executor

    kinds = tuple(_v.choice("kind", k, SWEEPS) for k in kinds)
    seed = _v.integer("seed", seed, minimum=0)  # None would draw a sweep nobody can redraw
    truth = _v.choice("truth", truth, TRUTHS)
    points = {k: DEFAULT_FACTORS[k] if factors is None or k not in factors
              else np.asarray(factors[k], dtype=float) for k in kinds}
    forms = tuple(FORMS) if forms is None else tuple(_v.choice("forms", f, FORMS) for f in forms)
    keys = {k: [_point_key(k, f) for f in points[k]] for k in kinds}  # refuses a bad factor here
    todo = list(dict.fromkeys(key for k in kinds for key in keys[k]))  # distinct, in order
    resolved = resolve_executor(executor)  # ValueError naming ``executor`` for anything else
    desc = f"sweep '{kinds[0]}'" if len(kinds) == 1 else "sweeps " + ", ".join(kinds)
    with resolved as ex, _progress_bar(progress, len(todo), desc) as bar:
        futures = {key: ex.submit(_sweep_point, *key, forms, seed, truth, digits) for key in todo}
        for future in cf.as_completed(futures.values()):
            future.result()  # a worker's exception surfaces here, at once
            bar.update(1)
    return tuple(_assemble(k, seed, points[k], [futures[key].result() for key in keys[k]], forms)
                 for k in kinds)


def _point_key(kind: str, factor: float) -> tuple[str, float]:
    """What :func:`_sweep_point` computes for (kind, factor): factor 1 is the report's problem
    whatever the kind (:func:`sweep_model` leaves the model as it is)."""
    sweep_model(kind, factor)  # a bad factor is refused here, before any worker starts
    return ("prior", 1.0) if float(factor) == 1.0 else (kind, float(factor))


def _assemble(kind: str, seed: int, points: np.ndarray, results: list[_Point],
              forms: tuple[str, ...]) -> Sweep:
    errs = {name: tuple(r.errors[name] for r in results) for name in forms}
    problems = {name: tuple(r.problems[name] for r in results) for name in forms}
    return Sweep(kind, seed, points, np.array([r.kappa for r in results]),
                 np.array([r.cond_P for r in results]), tuple(r.floor for r in results),
                 errs, problems)


@dataclass(frozen=True)
class _Point:
    """One sweep point's results (what a worker sends back)."""

    kappa: float
    cond_P: float
    floor: Errors
    errors: dict[str, Errors]
    problems: dict[str, str | None]


def _sweep_point(kind: str, factor: float, forms: tuple[str, ...], seed: int, truth: str,
                 digits: int) -> _Point:
    """The exact answer and every form at one sweep point.  Module-level and picklable: this is
    what an executor runs."""
    model, data_model = sweep_model(kind, factor)
    z = simulate(data_model, np.random.default_rng(seed), truth).z
    exact = exact_filter(model, z, digits)
    errs: dict[str, Errors] = {}
    problems: dict[str, str | None] = {}
    for name in forms:
        row = _core.run_one(name, form_filter(name, model), z, exact, 1, "")
        errs[name] = row.errors or Errors(np.inf, np.inf, np.inf, -np.inf)
        problems[name] = row.problem
    return _Point(update_condition_number(model, exact), exact.condition_number(),
                  _core.floor(exact), errs, problems)


def _progress_bar(progress: bool, total: int, desc: str):
    """tqdm.auto's bar (the notebook bar in a Jupyter kernel; nothing on a pipe or a log)."""
    from tqdm.auto import tqdm

    quiet = not progress or sys.stderr is None
    return tqdm(total=total, desc=desc, unit="point", disable=True if quiet else None,
                leave=False)
