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

Besides the report's, the slips every system shares (:mod:`gpsaccel.kalman.entries`, one
definition each: a sign of Φ, σ for σ² in V, W or M0, a prior off by a power of ten, Joseph's
sign, V left out of S, no process noise or Q·Δt, z one step late, x̂₀ = 0, every other GPS fix
skipped) and the ship's own: NaN rows used as measurements of 0 (``missing-as-zero``), u one step
off (``input-shift``), the outputs one row late (``epoch-shift``).  Each is a change of
:class:`Ingredients`.

:func:`run` runs any combination on an ensemble at once, through the one stepping loop of the
package (:func:`gpsaccel.kalman.update.step_schedule`, an epoch at every step) with the zeroed-gain
hook as its update (:class:`gpsaccel.ship.zeroed_gain.ZeroedGainUpdate`, which applies any of
these gains and carries the true covariance of the error alongside): the gains do not depend on
the data, so one covariance recursion serves every run and the means move as (R, 9) arrays.
What the hook cannot express is done around it, and said where: the input (``no-input``,
``input-shift``) in the prediction, which z the update sees (``missing-as-zero``,
``measurement-late``, every other GPS fix) before the loop, the rows returned
(``epoch-shift``) after it.  :func:`variants` lists every combination the checker matches
against (:func:`run` with none of them is the optimal filter, equal to
:func:`gpsaccel.kalman.multirate.run_multirate` to rounding).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from gpsaccel.kalman import entries
from gpsaccel.kalman.linear_messages import MESSAGES as LINEAR_MESSAGES
from gpsaccel.kalman.linear_model import LinearModel
from gpsaccel.kalman.mistakes import Mistake, apply
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import partial_update, step_schedule
from gpsaccel.ship.model import GPS_ROWS, STATES, ShipModel
from gpsaccel.ship.plan import driving_input
from gpsaccel.ship.zeroed_gain import ZeroedGainUpdate

#: The ship's wording, one table: code -> the filter entry's message (``{cost}``: the σ excess of
#: the student's filter's true covariance over the optimal, said in words by the checker);
#: ``update.<code>`` -> what the homework's one update is (the student reads it after the code's
#: wording), ``update.<code>.hint`` -> its hint (the instructor's: it states the optimal gain);
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
    "missing-as-zero": "Your filter uses the sensors that did not report (NaN in z) as "
                       "measurements of 0, so every step updates with all nine rows: leave the "
                       "rows that did not arrive out (H_a, V_aa, z_a).",
    "input-shift.early": "Your prediction from t_k to t_(k+1) uses u[k + 1], the next step's "
                         "input (the last row repeated at the end): u[k] drives the step from "
                         "t_k to t_(k+1).",
    "input-shift.late": "Your prediction from t_k to t_(k+1) uses u[k − 1], the step before's "
                        "(none at the first): u[k] drives the step from t_k to t_(k+1).",
    "epoch-shift": "Your outputs are one row late: row k holds x̂ and P of step k − 1 (row 0 "
                   "twice). Store x̂_k and P_k in row k, right after the update with z[k].",
    "fixes-skipped": "Your filter uses the GPS only at every other fix (the {which}): every "
                     "row where z is not NaN updates.",
    "measurement-late": "Your update at step k uses z[k − 1], the row before (nothing at k = "
                        "1): the residual takes the row of the step being updated, z[k].",
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
    "homework.update-mismatch": "Case “{where}”: {what} (by up to {dx:.3g} σ in x̂ and "
                                "{dP:.3g} σσ in P). Use only the rows r where z is not NaN, "
                                "their H_r, V_r and z_r, in the gain, the estimate and P.{none}",
    "homework.update-mismatch.both": "your x̂ and P differ from the update with the rows that "
                                     "arrived",
    "homework.update-mismatch.x_hat": "your x̂ differs from the update with the rows that "
                                      "arrived, your P does not",
    "homework.update-mismatch.P": "your P differs from the update with the rows that arrived, "
                                  "your x̂ does not",
    "homework.update-mismatch.none": " Nothing arrived here: the question says what the update "
                                     "returns then.",
    "homework.update-mismatch.formulas": "The optimal update: K_r = M H_rᵀ (H_r M H_rᵀ + "
                                         "V_r)⁻¹, x̂ = x̄ + K_r (z_r − H_r x̄), P in Joseph form; "
                                         "with nothing arrived x̂ = x̄ and P = M.",
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


@dataclass(frozen=True, eq=False)
class Ingredients:
    """What a student chooses writing the ship's update or filter; every switch off (and every
    matrix None: the ship's own) is the optimal one.

    zeroed : the full gain with the missing columns zeroed; report_covariance : P = (I − K H) M;
    monorate_gain : the monorate filter's gain at the GPS fixes; no_input : the prediction without
    B u; missing_as_zero : NaN rows used as measurements of 0.
    Phi, W, Q, V, M0, x0 : the filter's own model (None: the ship's, :meth:`correct` fills them
    in; Q, when given, instead of Γ W Γᵀ); V_gain, form : the gain's V and the covariance update
    (:class:`~gpsaccel.ship.zeroed_gain.ZeroedGainUpdate`); z_shift : "first", the update at
    step k takes z[k − 1]; updates : "even" or "odd", the GPS only at every other fix (the 2nd,
    4th, ... left out, or the 1st, 3rd, ...); u_shift : "early" u[k + 1] or "late" u[k − 1]
    drives the step from t_k; output_shift : the rows returned one late.
    """

    zeroed: bool = False
    report_covariance: bool = False
    monorate_gain: bool = False
    no_input: bool = False
    missing_as_zero: bool = False
    Phi: np.ndarray | None = None
    W: np.ndarray | None = None
    Q: np.ndarray | None = None
    V: np.ndarray | None = None
    M0: np.ndarray | None = None
    x0: np.ndarray | None = None
    V_gain: np.ndarray | None = None
    form: str | None = None
    z_shift: str | None = None
    updates: str | None = None
    u_shift: str | None = None
    output_shift: bool = False

    @classmethod
    def correct(cls, model: ShipModel) -> Ingredients:
        """The optimal filter's, with ``model``'s matrices filled in (so that a change of one
        element has a matrix to change)."""
        return cls(Phi=model.Phi, W=model.W, V=model.V, M0=model.M0, x0=model.x0)


#: The ingredients that change only the gains a filter applies, never how its mean moves: with
#: only these, the true covariance of its error is the Joseph recursion of its gains (the cost
#: said exactly); with any other, the cost is said from its estimates.
GAIN_ONLY = frozenset({"zeroed", "report_covariance", "monorate_gain", "W", "Q", "V", "M0",
                       "V_gain", "form", "updates"})

#: (code, the switches it sets, the filters it applies to): the report's entries in order.
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


def _numbers(model: ShipModel) -> LinearModel:
    """The ship's matrices by the names :mod:`gpsaccel.kalman.entries` reads (an epoch every
    step)."""
    return LinearModel(model.Phi, model.Gamma, model.W, model.H, model.V, model.M0, model.x0,
                       1, model.n_samples, model.dt, tuple(s for s, _ in STATES))


def _text(key: str, **fields: object) -> str:
    return {**LINEAR_MESSAGES, **MESSAGES}[key].format(**fields)


def shared_catalogue(model: ShipModel | None = None) -> tuple[Mistake, ...]:
    """The checker's entries beyond the report's: the ideas every system shares
    (:mod:`gpsaccel.kalman.entries`) on the ship's numbers, and the ship's own."""
    m = _numbers(ShipModel() if model is None else model)
    out = entries.phi_sign(m, _text)
    out += entries.std_as_variance(m, _text, whole=2)
    out += entries.prior_scale(m, _text) + entries.joseph_sign(m, _text)
    out += entries.residual_covariance(m, _text) + entries.process_noise(m, _text)
    out += entries.x0_wrong(m, _text, from_z=False) + entries.measurement_late(
        m, _text, wrap=False, first="z[k − 1] for z[k] (nothing at k = 1)")
    out += entries.fixes_skipped(m, _text, {"even": "the 1st, 3rd, ... fix",
                                            "odd": "the 2nd, 4th, ... fix"}, "the GPS at {which}")
    out += [Mistake("missing-as-zero", "NaN rows used as 0", MESSAGES["missing-as-zero"],
                    (("missing_as_zero", True),)),
            Mistake("epoch-shift", "outputs one row late", MESSAGES["epoch-shift"],
                    (("output_shift", True),))]
    out += [Mistake("input-shift", f"u[k {sign} 1] for u[k]", MESSAGES[f"input-shift.{key}"],
                    (("u_shift", key),)) for key, sign in (("early", "+"), ("late", "−"))]
    return tuple(replace(e, kinds=("filter",)) for e in out)


def catalogue(kind: str = "filter") -> tuple[Mistake, ...]:
    """The ship's catalogue: entries of the core's one type (:class:`gpsaccel.kalman.mistakes
    .Mistake`), each a change of :class:`Ingredients`, for ``kind`` "filter" (the checker's
    ``multirate_filter``: the report's entries, message templates with ``{cost}``, then
    :func:`shared_catalogue`) or "update" (the homework's one update, :func:`update`: what it is
    and the hint)."""
    out = []
    for code, changes, k in _ENTRIES:
        if k != kind:
            continue
        key = code if k == "filter" else f"update.{code}"
        out.append(Mistake(code, code if k == "filter" else MESSAGES[key], MESSAGES[key],
                           changes, hint=MESSAGES.get(f"{key}.hint", ""), kinds=(k,),
                           homework=k == "update"))
    return tuple(out) + (_shared() if kind == "filter" else ())


@lru_cache(maxsize=1)
def _shared() -> tuple[Mistake, ...]:
    return shared_catalogue(_default_model())


@lru_cache(maxsize=1)
def _default_model() -> ShipModel:
    return ShipModel()


#: The report's four codes (the homework's question 3 and :func:`variants`' combinations).
REPORT_CODES = ("zeroed-gain", "report-covariance", "monorate-gain", "no-input")

#: Every code of the checker's catalogue, in order.
CODES = tuple(dict.fromkeys(m.code for m in catalogue("filter")))

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
        """The ingredients on the ship's default model (:meth:`on` another)."""
        return self.on(_default_model())

    def on(self, model: ShipModel) -> Ingredients:
        return apply(Ingredients.correct(model), self.mistakes)

    @property
    def gain_only(self) -> bool:
        """Whether it changes only the gains (:data:`GAIN_ONLY`): its P_true is then the true
        covariance of its error."""
        return all(m.fields <= GAIN_ONLY for m in self.mistakes)

    def __str__(self) -> str:
        return " + ".join(str(m) if m.variant != m.code else m.code
                          for m in self.mistakes) or "optimal"


def variants() -> tuple[Variant, ...]:
    """The optimal filter first, then every valid combination of the report's four entries, then
    each other entry of the catalogue alone.

    ``report-covariance`` needs ``zeroed-gain`` (with the optimal gain (I − KH) M equals the Joseph
    form, so it is not a mistake there).
    """
    report = catalogue("filter")[:len(REPORT_CODES)]
    out = [Variant(())]
    for on in itertools.product((False, True), repeat=len(report)):
        zeroed, cov = on[0], on[1]
        if cov and not zeroed or not any(on):
            continue
        out.append(Variant(tuple(m for m, o in zip(report, on, strict=True) if o)))
    return tuple(out) + tuple(Variant((m,)) for m in _shared())


@dataclass
class Output:
    """What a filter of the catalogue returns on an ensemble.

    x_hat : (R, N, n) a posteriori means (row 0 the prior x0).  P : (N, n, n) the covariance the
    filter carries and returns.  P_true : (N, n, n) the true covariance of its error (Joseph form
    of the gains it applied; the error's covariance only when the mistakes change nothing but
    the gains, :attr:`Variant.gain_only`).  K : (N, n, 9) the gains (zero at k = 0).
    """

    x_hat: np.ndarray
    P: np.ndarray
    P_true: np.ndarray
    K: np.ndarray


def availability(z: np.ndarray) -> np.ndarray:
    """(N, 9) bool: the components measured at each step, from one run's z (finite = measured)."""
    return np.isfinite(np.asarray(z, dtype=float))


def _used_z(z: np.ndarray, g: Ingredients) -> np.ndarray:
    """The z (R, N, 9) the filter's update sees: NaN as 0, one row late, or every other GPS
    fix left out.  (Not the hook's to say: it is handed the rows of z that arrived.)"""
    if g.missing_as_zero:
        z = np.nan_to_num(z, nan=0.0)
        z[:, 0] = np.nan  # row 0 is x0 and M0: nothing updates there
    if g.z_shift:
        z = np.concatenate([np.full_like(z[:, :1], np.nan), z[:, :-1]], axis=1)
    if g.updates:
        z = z.copy()
        for r in range(z.shape[0]):  # the fixes counted as they arrive, run by run
            fixes = np.flatnonzero(np.isfinite(z[r, :, GPS_ROWS[0]]))
            drop = fixes[1::2] if g.updates == "even" else fixes[0::2]
            z[r][np.ix_(drop, np.array(GPS_ROWS))] = np.nan
    return z


def _used_u(u: np.ndarray, g: Ingredients) -> np.ndarray:
    """The input that drives each step: u, one step early (the last row repeated) or late."""
    if g.u_shift == "early":
        return np.concatenate([u[1:], u[-1:]])
    if g.u_shift == "late":
        return np.concatenate([np.zeros_like(u[:1]), u[:-1]])
    return u


def run(model: ShipModel, z: np.ndarray, u: np.ndarray | None = None,
        variant: Variant = Variant(()), mono_K: np.ndarray | None = None) -> Output:
    """Run ``variant`` on z (R, N, 9) (every run with the same NaN pattern) and input u (N−1, 3).

    ``u`` defaults to the model's driving input; ``mono_K`` (N, n, 9), the monorate filter's gains,
    is computed when the variant needs it and it is not given.  The loop is
    :func:`~gpsaccel.kalman.update.step_schedule` over an epoch at every step k ≥ 1 (what
    arrived there, possibly nothing), its update :class:`~gpsaccel.ship.zeroed_gain
    .ZeroedGainUpdate` (module docstring).
    """
    g = variant.on(model)
    z = _used_z(np.asarray(z, dtype=float).reshape((-1,) + np.shape(z)[-2:]), g)
    R, N, p = z.shape
    avail = availability(z[0])
    if (availability(z) != avail).any():
        raise ValueError("z: every run must have the same NaN pattern (the same schedule)")
    u = _used_u(driving_input(model) if u is None else np.asarray(u, dtype=float), g)
    Phi = model.Phi if g.Phi is None else g.Phi            # (correct() fills them in)
    V = model.V if g.V is None else g.V
    W = model.W if g.W is None else g.W
    Q = g.Q if g.Q is not None else model.Q if W is model.W else model.Gamma @ W @ model.Gamma.T
    H, B = model.H, model.B
    n = Phi.shape[0]
    if g.monorate_gain and mono_K is None:
        mono_K = monorate_gains(model)
    schedule = Schedule(N - 1, np.arange(1, N), avail[1:])
    hook = ZeroedGainUpdate(model.Phi, model.Q, model.M0, schedule.steps,
                            "report" if g.report_covariance else "joseph",
                            mono_K[schedule.steps] if mono_K is not None and g.monorate_gain
                            else None,
                            zeroed=g.zeroed, V_gain=g.V_gain, form=g.form, V_true=model.V)
    state = {"x": np.broadcast_to(model.x0 if g.x0 is None else g.x0, (R, n)).copy(),
             "C": np.array(model.M0 if g.M0 is None else g.M0, dtype=float)}
    x_hat, P = np.empty((R, N, n)), np.empty((N, n, n))
    K_all = np.zeros((N, n, p))
    x_hat[:, 0], P[0] = state["x"], state["C"]

    def predict(k: int) -> None:                  # the input is the prediction's, not the hook's
        state["x"] = state["x"] @ Phi.T + (0.0 if g.no_input else B @ u[k])
        state["C"] = Phi @ state["C"] @ Phi.T + Q

    def update(i: int) -> None:
        j = int(schedule.steps[i])
        state["x"], state["C"], K_all[j] = hook.update(
            state["x"], state["C"], i, z[:, j], np.flatnonzero(schedule.mask[i]), H, V)
        x_hat[:, j], P[j] = state["x"], state["C"]

    step_schedule(schedule, predict, update)
    P_true = np.concatenate([model.M0[None], hook.P_actual])
    if g.output_shift:                            # the rows returned, after the loop
        x_hat[:, 1:], P[1:], P_true[1:] = x_hat[:, :-1].copy(), P[:-1].copy(), P_true[:-1].copy()
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
