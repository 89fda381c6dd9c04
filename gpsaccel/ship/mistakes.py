r"""Known mistakes in a student's multirate ship filter (report 004), as runnable filters.

A student's ``multirate_filter(z, u)`` gets z (N, 9), row k the sensors at t_k = k·Ts with NaN
where a sensor did not report (row 0 all NaN), and the known input u (N − 1, 3); it returns x̂_k
and P_k at every step k = 0..N−1 (row 0: x0 and M0, nothing is measured there).  The optimal
filter updates with exactly the rows that arrived::

    x̄_{k+1} = Φ x̂_k + B u_k,   M_{k+1} = Φ P_k Φᵀ + Q
    a = the components measured at k+1,  K = M H_aᵀ (H_a M H_aᵀ + V_aa)⁻¹
    x̂ = x̄ + K (z_a − H_a x̄),   P = (I − K H_a) M (I − K H_a)ᵀ + K V_aa Kᵀ

The report's filter differs in up to three ways, and a student can forget the input:

``zeroed-gain``       the full 9-column gain M Hᵀ (H M Hᵀ + V)⁻¹ with the columns of the missing
                      sensors set to zero (:mod:`gpsaccel.ship.zeroed_gain`): near-optimal, not
                      optimal; its cost is the exact σ excess of its true covariance;
``report-covariance`` with that gain, P = (I − K H) M, which is not the covariance of a
                      suboptimal gain (and is not symmetric);
``monorate-gain``     at the GPS fixes (all nine components) the gain of the *monorate* filter
                      (every sensor every step) instead of the filter's own;
``no-input``          the prediction without B u_k.

:func:`run` runs any combination on an ensemble at once: the gains do not depend on the data,
so one covariance recursion serves every run and the means move as (R, 9) arrays.
:func:`variants` lists every combination the checker matches against (:func:`run` with none of
them is the optimal filter, equal to :func:`gpsaccel.kalman.multirate.run_multirate` to
rounding).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from gpsaccel.kalman.mistakes import Mistake, apply
from gpsaccel.kalman.update import joseph_update, partial_update
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.plan import driving_input

#: The ship's wording, one table: code -> the filter entry's message (``{cost}``: the σ excess of
#: the student's filter's true covariance over the optimal, said in words by the checker);
#: ``update.<code>`` -> what the homework's one update is, ``update.<code>.hint`` -> its hint;
#: ``homework.<code>`` -> the homework's findings (:mod:`gpsaccel.assignments.ship`).
MESSAGES: dict[str, str] = {
    "zeroed-gain": "Your update computes the full gain M Hᵀ (H M Hᵀ + V)⁻¹ as if every sensor had "
                   "reported and zeroes the columns of the missing ones (the report's filter). "
                   "That gain is near-optimal but not optimal: {cost}. Use only the rows that "
                   "arrived: K = M H_aᵀ (H_a M H_aᵀ + V_aa)⁻¹.",
    "report-covariance": "Your P is the report's (I − K H) M, which is the covariance of the "
                         "optimal gain only; with any other gain it is not the covariance of "
                         "your error (and not symmetric). Use the Joseph form (I − K H) M "
                         "(I − K H)ᵀ + K V Kᵀ.",
    "monorate-gain": "At the GPS fixes your filter applies the gain of the monorate filter (all "
                     "sensors every step), as the report's loop does, instead of its own gain "
                     "from its own M: {cost}.",
    "no-input": "Your prediction leaves out the known input: x̄_(k+1) = Φ x̂_k + B u_k (u[k] "
                "drives the step from t_k to t_(k+1)).",
    "update.zeroed-gain": "the full gain M Hᵀ (H M Hᵀ + V)⁻¹ with the columns of the missing "
                          "rows set to zero (report 004's BD(:,1,n) = 0)",
    "update.zeroed-gain.hint": "The kept columns of the full gain were computed as if the "
                               "missing rows would also correct the estimate, so they "
                               "under-weight what did arrive. Use only the rows r that arrived: "
                               "K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹.",
    "update.report-covariance": "report 004's zeroed gain with P = (I − K H) M",
    "update.report-covariance.hint": "Besides the zeroed gain (use K_r = M H_rᵀ (H_r M H_rᵀ + "
                                     "V_r)⁻¹ with the rows r that arrived), P = (I − K H) M "
                                     "holds only for the optimal gain: with any other it is not "
                                     "even symmetric. The Joseph form holds for every gain.",
    "update.missing-as-zero": "the missing rows used as measurements of 0",
    "update.missing-as-zero.hint": "A NaN means the row did not arrive: leave it out (H_r, V_r, "
                                   "z_r), do not replace it with 0.",
    # -------------------------------------- the homework's findings (assignments/ship.py)
    "homework.return-value": "update must return a pair (x_hat, P); it returned a {type}.",
    "homework.update-mistake": "Case “{where}”: your update is {what}. {hint}",
    "homework.update-mismatch": "Case “{where}”: x̂ differs from the update with the rows that "
                                "arrived by up to {dx:.3g} σ and P by up to {dP:.3g} σσ. Use the "
                                "rows r where z is not NaN: K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹, "
                                "x̂ = x̄ + K_r (z_r − H_r x̄), P in Joseph form.{none}",
    "homework.update-mismatch.none": " With nothing arrived, x̂ = x̄ and P = M.",
    "homework.ok.update": "The update matches the optimal one with the rows that arrived on {n} "
                          "cases (IMU-only, all rows, one row missing, none).",
    "homework.not-a-number": "{where} must be one number; got {value}.",
    "homework.not-a-number.finite": "{where} = {value}: it must be a finite number.",
    "homework.std-as-variance": "{where} is the variance P₁₁; the question asks for the standard "
                                "deviation σ = √P₁₁ (m).",
    "homework.claimed-not-actual": "sigma_zeroed is what the report's filter claims, from its "
                                   "P = (I − K H) M. That formula holds only for the optimal "
                                   "gain; the zeroed gain's actual error covariance is the "
                                   "Joseph form of the gains it applied (P_actual).",
    "homework.sigma-value.optimal": "sigma_zeroed is the optimal filter's σ; use the zeroed-gain "
                                    "filter's P_actual.",
    "homework.sigma-value.zeroed": "sigma_optimal is the zeroed-gain filter's σ; use the optimal "
                                   "filter's P.",
    "homework.sigma-value": "{where} = {value:.6g} m is not σ of the x position at the last step "
                            "(t = 100 s) for your ship (VARIANT); give at least 6 significant "
                            "digits (within {rtol:g} relative: the filters differ in the 4th).",
    "homework.ok.cost": "σ_x(100 s) of both filters is right; compare them: the zeroed gain's "
                        "actual σ is larger than the optimal one, and larger than it claims.",
}


@dataclass(frozen=True)
class Ingredients:
    """What a student chooses writing the ship's update or filter; every switch off is the
    optimal one.  zeroed: the full gain with the missing columns zeroed; report_covariance:
    P = (I − K H) M; monorate_gain: the monorate filter's gain at the GPS fixes; no_input: the
    prediction without B u; missing_as_zero: NaN rows used as measurements of 0."""

    zeroed: bool = False
    report_covariance: bool = False
    monorate_gain: bool = False
    no_input: bool = False
    missing_as_zero: bool = False


#: (code, the switches it sets, the filters it applies to): the catalogue's entries in order.
#: ``report-covariance`` of the filter sets only its own switch: :func:`variants` pairs it with
#: ``zeroed-gain`` (with the optimal gain (I − KH) M is the Joseph form, no mistake).
_ENTRIES: tuple[tuple[str, tuple[tuple, ...], str], ...] = (
    ("zeroed-gain", (("zeroed", True),), "filter"),
    ("report-covariance", (("report_covariance", True),), "filter"),
    ("monorate-gain", (("monorate_gain", True),), "filter"),
    ("no-input", (("no_input", True),), "filter"),
    ("zeroed-gain", (("zeroed", True),), "update"),
    ("report-covariance", (("zeroed", True), ("report_covariance", True)), "update"),
    ("missing-as-zero", (("missing_as_zero", True),), "update"),
)


def catalogue(kind: str = "filter") -> tuple[Mistake, ...]:
    """The ship's catalogue: entries of the core's one type (:class:`gpsaccel.kalman.mistakes
    .Mistake`), each a change of :class:`Ingredients`, for ``kind`` "filter" (the checker's
    ``multirate_filter``, message templates with ``{cost}``) or "update" (the homework's one
    update, :func:`update`: what it is and the hint; ``missing-as-zero`` is the homework's own,
    the checker's filter gets NaN rows, whose zero-filled use it names as a mismatch)."""
    out = []
    for code, changes, k in _ENTRIES:
        if k != kind:
            continue
        key = code if k == "filter" else f"update.{code}"
        out.append(Mistake(code, code if k == "filter" else MESSAGES[key], MESSAGES[key],
                           changes, hint=MESSAGES.get(f"{key}.hint", ""), kinds=(k,),
                           homework=k == "update"))
    return tuple(out)


CODES = tuple(m.code for m in catalogue("filter"))

#: The homework's question 1 (one update, :func:`update`): the mistakes it names, in the order
#: tried.
UPDATE_CODES = tuple(m.code for m in catalogue("update"))


def update_catalogue() -> tuple[Mistake, ...]:
    """The homework's one-update mistakes: :func:`catalogue` ``("update")``."""
    return catalogue("update")


def update(x_bar: np.ndarray, M: np.ndarray, z: np.ndarray, H: np.ndarray, V: np.ndarray,
           mistakes: tuple[Mistake, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """(x̂, P): one update with the rows of z that are finite (NaN = did not arrive), the
    optimal one (:func:`gpsaccel.kalman.update.partial_update`) or the one making ``mistakes``."""
    g = apply(Ingredients(), mistakes)
    if g.missing_as_zero:
        z = np.nan_to_num(z, nan=0.0)
    rows = np.flatnonzero(np.isfinite(z))
    if rows.size == 0 and not g.zeroed:
        return x_bar.copy(), M.copy()
    x, P, _ = partial_update(x_bar, M, z, H, V, rows, zeroed=g.zeroed,
                             short_form=g.report_covariance)
    return x, P


@dataclass(frozen=True)
class Variant:
    """One filter the checker matches against: a combination of the catalogue's entries."""

    mistakes: tuple[Mistake, ...] = ()

    @property
    def codes(self) -> tuple[str, ...]:
        return tuple(m.code for m in self.mistakes)

    @property
    def ingredients(self) -> Ingredients:
        return apply(Ingredients(), self.mistakes)

    def __str__(self) -> str:
        return " + ".join(self.codes) or "optimal"


def variants() -> tuple[Variant, ...]:
    """The optimal filter first, then every valid combination of the catalogue's mistakes.

    ``report-covariance`` needs ``zeroed-gain`` (with the optimal gain (I − KH) M equals the Joseph
    form, so it is not a mistake there).
    """
    entries = catalogue("filter")
    out = [Variant(())]
    for on in itertools.product((False, True), repeat=len(entries)):
        zeroed, report = on[0], on[1]
        if report and not zeroed or not any(on):
            continue
        out.append(Variant(tuple(m for m, o in zip(entries, on, strict=True) if o)))
    return tuple(out)


@dataclass
class Output:
    """What a filter of the catalogue returns on an ensemble.

    x_hat : (R, N, n) a posteriori means (row 0 the prior x0).  P : (N, n, n) the covariance the
    filter carries and returns.  P_true : (N, n, n) the true covariance of its error (Joseph form
    of the gains it applied).  K : (N, n, 9) the gains (zero at k = 0).
    """

    x_hat: np.ndarray
    P: np.ndarray
    P_true: np.ndarray
    K: np.ndarray


def availability(z: np.ndarray) -> np.ndarray:
    """(N, 9) bool: the components measured at each step, from one run's z (finite = measured)."""
    return np.isfinite(np.asarray(z, dtype=float))


def run(model: ShipModel, z: np.ndarray, u: np.ndarray | None = None,
        variant: Variant = Variant(()), mono_K: np.ndarray | None = None) -> Output:
    """Run ``variant`` on z (R, N, 9) (every run with the same NaN pattern) and input u (N−1, 3).

    ``u`` defaults to the model's driving input; ``mono_K`` (N, n, 9), the monorate filter's gains,
    is computed when the variant needs it and it is not given.
    """
    z = np.asarray(z, dtype=float)
    if z.ndim == 2:
        z = z[None]
    R, N, p = z.shape
    avail = availability(z[0])
    if (availability(z) != avail).any():
        raise ValueError("z: every run must have the same NaN pattern (the same schedule)")
    u = driving_input(model) if u is None else np.asarray(u, dtype=float)
    Phi, Q, H, V, B = model.Phi, model.Q, model.H, model.V, model.B
    n = Phi.shape[0]
    g = variant.ingredients
    if g.monorate_gain and mono_K is None:
        mono_K = monorate_gains(model)
    x = np.broadcast_to(model.x0, (R, n)).copy()
    C = model.M0.copy()
    Ct = C.copy()
    x_hat = np.empty((R, N, n))
    P = np.empty((N, n, n))
    P_true = np.empty((N, n, n))
    K_all = np.zeros((N, n, p))
    x_hat[:, 0], P[0], P_true[0] = x, C, Ct
    for k in range(N - 1):
        j = k + 1
        x = x @ Phi.T + (0.0 if g.no_input else B @ u[k])
        C = Phi @ C @ Phi.T + Q
        Ct = Phi @ Ct @ Phi.T + Q
        rows = np.flatnonzero(avail[j])
        K = np.zeros((n, p))
        if rows.size:
            given = mono_K[j] if mono_K is not None and g.monorate_gain and \
                rows.size == p else None
            x, C, K = partial_update(x, C, z[:, j], H, V, rows, given, g.zeroed,
                                     g.report_covariance)
            Ct = joseph_update(Ct, K, H, V)                 # the true covariance of any gain
        K_all[j] = K
        x_hat[:, j], P[j], P_true[j] = x, C, Ct
    return Output(x_hat, P, P_true, K_all)


def monorate_gains(model: ShipModel) -> np.ndarray:
    """(N, n, 9) the gains of the monorate filter (every component at every step k ≥ 1)."""
    N = model.n_samples
    z = np.zeros((1, N, 9))
    z[:, 0] = np.nan
    return run(model, z, np.zeros((N - 1, 3)), Variant(())).K


def schedule_z(model: ShipModel, z_all: np.ndarray) -> np.ndarray:
    """The report's multirate layout: z_all (..., N, 9) with NaN where the multirate schedule
    (GPS at ``gps_rate_hz``, IMU at ``imu_rate_hz``, nothing at k = 0) delivers nothing."""
    k = np.arange(model.n_samples)[:, None]
    avail = (k % model.periods(multirate=True) == 0) & (k >= 1)
    out = np.array(z_all, dtype=float, copy=True)
    out[..., ~avail] = np.nan
    return out


def sigma_excess(P_true: np.ndarray, P_opt: np.ndarray) -> np.ndarray:
    """(N, n) √diag P_true / √diag P_opt − 1: the exact loss in σ of each state (≥ 0)."""
    return np.sqrt(np.diagonal(P_true, axis1=-2, axis2=-1)
                   / np.diagonal(P_opt, axis1=-2, axis2=-1)) - 1
