r"""Filters side by side, each measured against the exact answer, for any linear model.

:func:`compare` runs any number of filters on one set of measurements of a linear model: the
built-in forms by name (:data:`~gpsaccel.kalman.factory.FORMS`: ``standard``, ``joseph``,
``information``, ``filterpy-information``, ``square-root``) and any callables with the checkers'
signature ``kalman_filter(z) -> (x_hat, P)`` (``z`` the (n_epochs, p) measurements, ``x_hat``
(n_epochs, n) and ``P`` (n_epochs, n, n) a posteriori at the epochs).  The model is any the forms
and the exact filter take (the driver's
:class:`~gpsaccel.kalman.multirate.LinearGaussianModel`, with Γ and W): an instructor's
:class:`~gpsaccel.kalman.epochs.LinearModel` (the tracker: its own realization is drawn from
``seed``), or report 000's ``CalibrationModel`` (:func:`gpsaccel.calibration.compare.compare`
draws its realization with the report's truth and calls this).

None of them is the reference.  The reference is the same filter computed with 50 significant
digits (:mod:`gpsaccel.kalman.exact`), so every number in the table is that filter's own rounding
error, in units that read the same for every state:

* ``max|dx|/sigma``: max over time and state of |x̂ − x̂*| / σ*, σ* = √diag P* (* = exact);
* ``max|dP|``:       max over time and element of |P_ij − P*_ij| / √(P*_ii P*_jj);
* ``asym``:          max over time and element of |P_ij − P_ji| / √(P*_ii P*_jj);
* ``min eig``:       smallest eigenvalue, over time, of P_ij / √(P*_ii P*_jj); the exact row shows
  the true value, a negative one means the filter's P is no longer a covariance;
* ``ms/run``:        wall-clock time of one run (best of ``repeat``; a filter that reports its own
  time, as a student's file timed in its own process does, is trusted for it).

The row "exact, rounded to float64" is the floor: the exact answer stored in float64 is already
that far from itself.  κ = max over epochs of λmax(S V⁻¹) = λmax(M P⁻¹) (S = H M Hᵀ + V) is the
update's condition number: rounding in P = (I − K H) M grows like ε κ (ε = 2⁻⁵³).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.consistency import sigma_distance
from gpsaccel.kalman.exact import DIGITS, Errors, ExactResult, errors, exact_filter
from gpsaccel.kalman.exact import min_eigenvalue_exact as _min_eig_exact
from gpsaccel.kalman.factory import FORMS, make_form
from gpsaccel.kalman.multirate import (
    LinearGaussianModel,
    check_inputs,
    optimal_update,
    run_multirate,
)
from gpsaccel.kalman.update import step_schedule

FilterCallable = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def reference_filter(model: LinearGaussianModel, method: str = "filterpy") -> FilterCallable:
    """The package's filter (``run_multirate``) as a ``kalman_filter(z) -> (x_hat, P)`` callable."""

    def kalman_filter(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = run_multirate(model, z, method=method, check=False)  # measured here instead
        return result.x_hat, result.P

    kalman_filter.__name__ = f"gpsaccel[{method}]"
    return kalman_filter


def form_filter(name: str, model: LinearGaussianModel) -> FilterCallable:
    """Built-in form ``name`` as a ``kalman_filter(z) -> (x_hat, P)`` callable: the x̂ and P of
    :func:`~gpsaccel.kalman.multirate.run_form`, bit for bit (:func:`epoch_estimates`)."""

    def kalman_filter(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return epoch_estimates(make_form(name, model), model, z)

    kalman_filter.__name__ = name
    return kalman_filter


def epoch_estimates(kf: Any, model: LinearGaussianModel, z: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(x̂, P) at the epochs of filter object ``kf`` (at (x0, M0)) run on ``z`` under the multirate
    driver's schedule: the same predictions and :func:`~gpsaccel.kalman.multirate.optimal_update`
    calls as :func:`~gpsaccel.kalman.multirate.run_multirate`, so the same numbers to the bit, but
    nothing else.  A comparison needs only these: recording the fast grid (which makes the
    information and square-root forms form P at each of the 6000 steps) and the covariance guard
    (whose warning the table would silence; it measures the same thing) were a third of a sweep's
    time."""
    inputs = check_inputs(model, z, None, None)
    schedule, H, V, z = inputs.schedule, inputs.H, inputs.V, inputs.z
    used = schedule.mask & np.isfinite(z)
    n = H.shape[1]
    x_hat, P = np.empty((schedule.n_epochs, n)), np.empty((schedule.n_epochs, n, n))

    def update_at(i: int) -> None:
        optimal_update(kf, i, z[i], np.flatnonzero(used[i]), H, V)
        x_hat[i], P[i] = kf.x[:, 0], kf.P

    step_schedule(schedule, lambda k: kf.predict(), update_at)
    return x_hat, P


def differences(x_ref: np.ndarray, P_ref: np.ndarray, x_hat: np.ndarray,
                P: np.ndarray) -> tuple[float, float]:
    """(max |Δx̂|/σ, max |ΔP_ij|/√(P_ii P_jj)) of one float filter against another (σ from P_ref)."""
    dx, dP = sigma_distance(x_hat, P, x_ref, P_ref)
    return float(dx.max()), float(dP.max())


# ------------------------------------------------------------------------------ one comparison
@dataclass(frozen=True)
class ComparisonRow:
    """One filter against the exact answer.

    errors : its :class:`~gpsaccel.kalman.exact.Errors` (None if it gave nothing back).
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


def floor(exact: ExactResult) -> Errors:
    """The errors of the exact answer rounded to float64: the best any float64 filter can do."""
    return errors(exact, exact.x_hat, exact.P)


def update_condition_number(model: LinearGaussianModel, exact: ExactResult) -> float:
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


def run_one(name: str, f: FilterCallable, z: np.ndarray, exact: ExactResult, repeat: int,
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


def contestants(forms: Sequence[str], filters: Mapping[str, FilterCallable] | None,
                 model: LinearGaussianModel) -> list[tuple[str, FilterCallable, str]]:
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


def compare(model: LinearGaussianModel, *forms: str, z: np.ndarray | None = None, seed: int = 0,
            truth: str = "", filters: Mapping[str, FilterCallable] | None = None,
            repeat: int = 3, digits: int = DIGITS, exact: ExactResult | None = None
            ) -> Comparison:
    """Run the built-in ``forms`` and the callables ``filters`` on one set of measurements of
    ``model``, each against the exact answer.

    Parameters
    ----------
    model : the linear model (:class:`~gpsaccel.kalman.multirate.LinearGaussianModel`, e.g. a
        :class:`~gpsaccel.kalman.epochs.LinearModel`).
    forms : names of built-in forms (:data:`~gpsaccel.kalman.factory.FORMS`); with neither
        ``forms`` nor ``filters``, every built-in form.
    z : the measurements (n_epochs, p), NaN = not measured; None draws one realization from the
        model's own ``simulate(rng, 1)`` with ``numpy.random.default_rng(seed)`` (a
        :class:`~gpsaccel.kalman.epochs.LinearModel` has it).
    seed : that seed (a non-negative integer; printed in the table either way).
    truth : what the measurements were simulated from, for the table's title.
    filters : name -> ``kalman_filter(z) -> (x_hat, P)``; a callable that raises gets a row saying
        what it raised; one that returns the wrong shapes is an error naming it.
    repeat : each filter is timed ``repeat`` times and the best time kept.
    digits : significant decimal digits of the exact answer.
    exact : the exact answer of ``model`` on these ``z`` with ``digits`` digits, if already
        computed (``exact_filter(model, z, digits)``; a lesson that compares several times on one
        realization computes it once).  Only its shape and digits are checked.
    """
    seed = _v.integer("seed", seed, minimum=0)
    repeat = _v.integer("repeat", repeat, minimum=1)
    if not forms and not filters:
        forms = tuple(FORMS)
    entries = contestants(forms, filters, model)
    if z is None:
        simulate = getattr(model, "simulate", None)
        if not callable(simulate):
            raise ValueError(f"z must be given: a {type(model).__name__} has no simulate(rng, "
                             f"n_runs) to draw it from")
        z = simulate(np.random.default_rng(seed), 1)[0][0]
        truth = truth or "the model"
    z = np.asarray(z, dtype=float)
    if exact is None:
        exact = exact_filter(model, z, digits)
    elif exact.digits != digits or exact.x_hat.shape[0] != z.shape[0]:
        raise ValueError(f"exact is a {exact.digits}-digit answer on {exact.x_hat.shape[0]} epochs; "
                         f"these z have {z.shape[0]} epochs and digits = {digits}")
    rows = tuple(run_one(name, f, z, exact, repeat, description)
                 for name, f, description in entries)
    return Comparison(seed, truth, exact.digits, exact.seconds, _min_eig_exact(exact),
                      floor(exact), update_condition_number(model, exact),
                      exact.condition_number(), rows)
