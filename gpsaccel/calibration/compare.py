"""Put two (or more) filter implementations side by side on the same realization.

The reference is filterpy's ``KalmanFilter`` (covariance form, Joseph update) under the multirate
driver.  Every other filter is a callable with the checkers' signature
``kalman_filter(z) -> (x_hat, P)``: ``z`` the (n_gps, 2) measurements, ``x_hat`` (n_gps, 3) and
``P`` (n_gps, 3, 3) the a posteriori estimates and covariances at GPS times.  Differences are
normalised so that they read the same for every state:

* estimates:    max over time and state of |x̂ − x̂_ref| / σ_ref,   σ_ref = √diag P_ref (units of σ);
* covariances:  max over time and element of |P_ij − P_ref,ij| / √(P_ref,ii P_ref,jj).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.simulation import TRUTHS, simulate
from gpsaccel.kalman.consistency import sigma_distance
from gpsaccel.kalman.multirate import run_multirate

FilterCallable = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def reference_filter(model: CalibrationModel, method: str = "filterpy") -> FilterCallable:
    """The package's filter as a ``kalman_filter(z) -> (x_hat, P)`` callable."""

    def kalman_filter(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        result = run_multirate(model, z, method=method)
        return result.x_hat, result.P

    kalman_filter.__name__ = f"gpsaccel[{method}]"
    return kalman_filter


@dataclass(frozen=True)
class ComparisonRow:
    """One filter against the reference.  ``seconds`` is the best of ``repeat`` wall-clock runs."""

    name: str
    max_dx_sigma: float
    max_dP_rel: float
    seconds: float


@dataclass(frozen=True)
class Comparison:
    reference: str
    reference_seconds: float
    rows: tuple[ComparisonRow, ...]

    def __str__(self) -> str:
        head = f"{'filter':<30} {'max|dx|/sigma':>14} {'max|dP|/sqrt(PiiPjj)':>21} {'time (ms)':>10}"
        lines = [head, "-" * len(head),
                 f"{self.reference + ' (reference)':<30} {'0':>14} {'0':>21} "
                 f"{1e3 * self.reference_seconds:10.1f}"]
        for r in self.rows:
            lines.append(f"{r.name:<30} {r.max_dx_sigma:14.3e} {r.max_dP_rel:21.3e} "
                         f"{1e3 * r.seconds:10.1f}")
        return "\n".join(lines)


def differences(x_ref: np.ndarray, P_ref: np.ndarray, x_hat: np.ndarray,
                P: np.ndarray) -> tuple[float, float]:
    """(max |Δx̂|/σ, max |ΔP_ij|/√(P_ii P_jj)) of (x_hat, P) against the reference."""
    dx, dP = sigma_distance(x_hat, P, x_ref, P_ref)
    return float(dx.max()), float(dP.max())


def _timed(f: FilterCallable, z: np.ndarray, repeat: int) -> tuple[tuple, float]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f(z.copy())
        best = min(best, time.perf_counter() - t0)
    return out, best


def compare(model: CalibrationModel | None = None, seed: int = 0, truth: str = "error-model",
            filters: Mapping[str, FilterCallable] | None = None, repeat: int = 3) -> Comparison:
    """Run the reference and ``filters`` (default: the information form) on one realization.

    Parameters
    ----------
    model : the problem (report 000's defaults when None).
    seed : seed of the realization (``numpy.random.default_rng(seed)``).
    truth : ``"error-model"`` or ``"kinematic"``, see :func:`gpsaccel.simulate`.
    filters : name -> ``kalman_filter(z) -> (x_hat, P)``.
    repeat : each filter is timed ``repeat`` times and the best time kept.
    """
    model = CalibrationModel() if model is None else model
    truth = _v.choice("truth", truth, TRUTHS)
    repeat = _v.integer("repeat", repeat, minimum=1)
    if filters is None:
        filters = {"information form": reference_filter(model, "information")}
    z = simulate(model, np.random.default_rng(seed), truth).z
    (x_ref, P_ref), t_ref = _timed(reference_filter(model, "filterpy"), z, repeat)
    rows = []
    for name, f in filters.items():
        if not callable(f):
            raise ValueError(f"filters[{name!r}] must be callable as kalman_filter(z)")
        (x_hat, P), seconds = _timed(f, z, repeat)
        x_hat = _v.finite_array(f"{name}: x_hat", x_hat, x_ref.shape)
        P = _v.finite_array(f"{name}: P", P, P_ref.shape)
        rows.append(ComparisonRow(name, *differences(x_ref, P_ref, x_hat, P), seconds))
    return Comparison("filterpy (Joseph)", t_ref, tuple(rows))
