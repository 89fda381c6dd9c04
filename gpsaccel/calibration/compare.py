r"""Filters side by side, each measured against the exact answer; and the conditioning sweeps.

:func:`compare` runs any number of filters on one realization of the calibration problem: the
built-in forms by name (:data:`~gpsaccel.calibration.forms.FORMS`: ``standard``, ``joseph``,
``information``, ``filterpy-information``, ``square-root``) and any callables with the checkers'
signature ``kalman_filter(z) -> (x_hat, P)`` (``z`` the (n_gps, 2) measurements, ``x_hat``
(n_gps, 3) and ``P`` (n_gps, 3, 3) a posteriori at the GPS times).  A student's *file* becomes
such a callable with :func:`gpsaccel.check.student_filter`, which runs it in a process of its own;
``gpsaccel compare FORM|FILE ...`` does that for you.

None of them is the reference.  The reference is the same filter computed with 50 significant
digits (:mod:`gpsaccel.calibration.exact`), so every number in the table is that filter's own
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

import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.exact import DIGITS, Errors, ExactResult, errors, exact_filter
from gpsaccel.calibration.exact import min_eigenvalue_exact as _min_eig_exact
from gpsaccel.calibration.forms import FORMS, run_form
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.simulation import TRUTHS, simulate
from gpsaccel.kalman.consistency import sigma_distance
from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.kalman.update import NumericalWarning

FilterCallable = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]

#: The sweeps of :func:`sweep` and the scale factor of their last point.
SWEEPS = ("prior", "gps")

#: Sweep points: 10⁰ … 10¹² for the prior, 10⁰ … 10⁻¹² for the GPS noise, one per decade.
DEFAULT_FACTORS = {"prior": 10.0 ** np.arange(13), "gps": 10.0 ** -np.arange(13)}


def reference_filter(model: CalibrationModel, method: str = "filterpy") -> FilterCallable:
    """The package's filter (``run_multirate``) as a ``kalman_filter(z) -> (x_hat, P)`` callable."""

    def kalman_filter(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = run_multirate(model, z, method=method, check=False)  # measured here instead
        return result.x_hat, result.P

    kalman_filter.__name__ = f"gpsaccel[{method}]"
    return kalman_filter


def form_filter(name: str, model: CalibrationModel) -> FilterCallable:
    """Built-in form ``name`` as a ``kalman_filter(z) -> (x_hat, P)`` callable."""

    def kalman_filter(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        with warnings.catch_warnings():  # the table measures what the guard would warn about
            warnings.simplefilter("ignore", NumericalWarning)
            result = run_form(name, model, z)
        return result.x_hat, result.P

    kalman_filter.__name__ = name
    return kalman_filter


def differences(x_ref: np.ndarray, P_ref: np.ndarray, x_hat: np.ndarray,
                P: np.ndarray) -> tuple[float, float]:
    """(max |Δx̂|/σ, max |ΔP_ij|/√(P_ii P_jj)) of one float filter against another (σ from P_ref)."""
    dx, dP = sigma_distance(x_hat, P, x_ref, P_ref)
    return float(dx.max()), float(dP.max())


# ------------------------------------------------------------------------------ one comparison
@dataclass(frozen=True)
class ComparisonRow:
    """One filter against the exact answer.

    errors : its :class:`~gpsaccel.calibration.exact.Errors` (None if it gave nothing back).
    seconds : time of one run (s).  problem : what went wrong, if it raised (None otherwise).
    """

    name: str
    description: str
    errors: Errors | None
    seconds: float
    problem: str | None = None

    @property
    def max_dx_sigma(self) -> float:
        return np.nan if self.errors is None else self.errors.dx_sigma


@dataclass(frozen=True)
class Comparison:
    """:func:`compare`'s table; ``str()`` prints it."""

    seed: int
    truth: str
    digits: int
    exact_seconds: float
    exact_min_eig: float
    floor: Errors
    kappa: float
    cond_P: float
    rows: tuple[ComparisonRow, ...]

    def row(self, name: str) -> ComparisonRow:
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(f"no filter named {name!r}; the table has {[r.name for r in self.rows]}")

    def __str__(self) -> str:
        w = max(30, *(len(r.name) + 1 for r in self.rows))
        head = (f"{'filter':<{w}} {'max|dx|/sigma':>13} {'max|dP|':>9} {'asym':>9} "
                f"{'min eig':>9} {'ms/run':>8}")
        lines = [f"against the exact answer ({self.digits} digits), seed {self.seed}, truth "
                 f"{self.truth}; κ = {self.kappa:.2g}, cond(P) ≤ {self.cond_P:.2g}", head,
                 "-" * len(head),
                 f"{'exact (mpmath)':<{w}} {'0':>13} {'0':>9} {'0':>9} "
                 f"{self.exact_min_eig:9.4f} {1e3 * self.exact_seconds:8.1f}",
                 f"{'exact, rounded to float64':<{w}} {self.floor.dx_sigma:13.1e} "
                 f"{self.floor.dP_rel:9.1e} {self.floor.asymmetry:9.1e} {'':>9} {'':>8}"]
        for r in self.rows:
            if r.errors is None:
                first, *rest = (r.problem or "").splitlines() or [""]
                lines.append(f"{r.name:<{w}} failed: {first}")
                lines += [" " * (w + 1) + line for line in rest]
                continue
            e = r.errors
            lines.append(f"{r.name:<{w}} {e.dx_sigma:13.1e} {e.dP_rel:9.1e} {e.asymmetry:9.1e} "
                         f"{e.min_eig:9.4f} {1e3 * r.seconds:8.1f}")
        return "\n".join(lines)


def _floor(exact: ExactResult) -> Errors:
    """The errors of the exact answer rounded to float64: the best any float64 filter can do."""
    return errors(exact, exact.x_hat, exact.P)


def update_condition_number(model: CalibrationModel, exact: ExactResult) -> float:
    """κ = max over epochs of λmax(S V⁻¹) = λmax(M P⁻¹), S = H M Hᵀ + V (every component measured)."""
    H, V = np.asarray(model.H, dtype=float), np.asarray(model.V, dtype=float)
    S = H @ exact.M @ H.T + V
    return float(np.linalg.eigvals(S @ np.linalg.inv(V)).real.max())


def _numbers(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a float array of ``shape``; NaN and inf are kept (a filter that broke down
    is measured as infinitely wrong, not refused)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    return arr


def _run_one(name: str, f: FilterCallable, z: np.ndarray, exact: ExactResult, repeat: int,
             description: str) -> ComparisonRow:
    """Run ``f`` on ``z`` (best time of ``repeat``); a filter that raises is a row saying so."""
    best = np.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        try:
            out = f(z.copy())
        except Exception as exc:  # noqa: BLE001 - a form that breaks down is a result
            return ComparisonRow(name, description, None, np.nan,
                                 f"{type(exc).__name__}: {exc}".strip())
        best = min(best, time.perf_counter() - t0)
        reported = getattr(f, "seconds", None)  # a filter timed where it ran
        if reported is not None:
            best = float(reported)
            break
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise ValueError(f"{name}: kalman_filter(z) must return (x_hat, P), got "
                         f"{type(out).__name__}")
    x_hat, P = (_numbers(f"{name}: {what}", value, shape) for what, value, shape in
                (("x_hat", out[0], exact.x_hat.shape), ("P", out[1], exact.P.shape)))
    return ComparisonRow(name, description, errors(exact, x_hat, P), best)


def _contestants(forms: Sequence[str], filters: Mapping[str, FilterCallable] | None,
                 model: CalibrationModel) -> list[tuple[str, FilterCallable, str]]:
    out = []
    for name in forms:
        name = _v.choice("forms", name, FORMS)
        out.append((name, form_filter(name, model), FORMS[name][1]))
    for name, f in (filters or {}).items():
        if not callable(f):
            raise ValueError(f"filters[{name!r}] must be callable as kalman_filter(z)")
        out.append((str(name), f, getattr(f, "description", "kalman_filter(z)")))
    names = [n for n, _, _ in out]
    if len(set(names)) != len(names):
        raise ValueError(f"every filter needs its own name, got {names}")
    return out


def compare(*forms: str, model: CalibrationModel | None = None, seed: int = 0,
            truth: str = "error-model", filters: Mapping[str, FilterCallable] | None = None,
            repeat: int = 3, digits: int = DIGITS) -> Comparison:
    """Run the built-in ``forms`` and the callables ``filters`` on one realization, each against
    the exact answer.

    Parameters
    ----------
    forms : names of built-in forms (see :data:`~gpsaccel.calibration.forms.FORMS`); with neither
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
    """
    model = CalibrationModel() if model is None else model
    seed = _v.integer("seed", seed, minimum=0)
    truth = _v.choice("truth", truth, TRUTHS)
    repeat = _v.integer("repeat", repeat, minimum=1)
    if not forms and not filters:
        forms = tuple(FORMS)
    contestants = _contestants(forms, filters, model)
    z = simulate(model, np.random.default_rng(seed), truth).z
    exact = exact_filter(model, z, digits)
    rows = tuple(_run_one(name, f, z, exact, repeat, description)
                 for name, f, description in contestants)
    return Comparison(seed, truth, exact.digits, exact.seconds, _min_eig_exact(exact),
                      _floor(exact), update_condition_number(model, exact),
                      exact.condition_number(), rows)


# ------------------------------------------------------------------------------ the sweeps
@dataclass(frozen=True, eq=False)
class Sweep:
    """The forms at each point of a conditioning sweep.

    kind : ``"prior"`` (M0 × factor) or ``"gps"`` (V × factor).
    factors : (n_points,) scale factors.  kappa : (n_points,) the update's condition number κ.
    cond_P : (n_points,) max over epochs of cond(P) (exact P, 2-norm, SI units).
    floor : the exact answer rounded to float64, per point (the best a float64 filter can do).
    errors : form -> per point :class:`~gpsaccel.calibration.exact.Errors` (inf if it broke down).
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
          seed: int = 0, truth: str = "error-model", digits: int = DIGITS) -> Sweep:
    """Run ``forms`` (default: all built-in) against the exact answer at each sweep point.

    kind : ``"prior"`` (M0 × factor, data from the report's model) or ``"gps"`` (V × factor, data
        simulated with that V).  factors : default :data:`DEFAULT_FACTORS` ``[kind]``.
    seed : one seed for every point (the same noise draws, scaled).
    """
    kind = _v.choice("kind", kind, SWEEPS)
    seed = _v.integer("seed", seed, minimum=0)  # None would draw a sweep nobody can redraw
    truth = _v.choice("truth", truth, TRUTHS)
    factors = DEFAULT_FACTORS[kind] if factors is None else np.asarray(factors, dtype=float)
    forms = tuple(FORMS) if forms is None else tuple(_v.choice("forms", f, FORMS) for f in forms)
    kappa, cond_P, floor = [], [], []
    errs: dict[str, list[Errors]] = {f: [] for f in forms}
    problems: dict[str, list[str | None]] = {f: [] for f in forms}
    for factor in factors:
        model, data_model = sweep_model(kind, factor)
        z = simulate(data_model, np.random.default_rng(seed), truth).z
        exact = exact_filter(model, z, digits)
        kappa.append(update_condition_number(model, exact))
        cond_P.append(exact.condition_number())
        floor.append(_floor(exact))
        for name in forms:
            row = _run_one(name, form_filter(name, model), z, exact, 1, "")
            errs[name].append(row.errors or Errors(np.inf, np.inf, np.inf, -np.inf))
            problems[name].append(row.problem)
    return Sweep(kind, seed, np.asarray(factors), np.array(kappa), np.array(cond_P), tuple(floor),
                 {f: tuple(v) for f, v in errs.items()},
                 {f: tuple(v) for f, v in problems.items()})
