r"""Known mistakes as parameterised filters, run vectorised across realizations and candidates.

Every filter a student writes for the report-000 problem — right or wrong — is, at the GPS times,
a linear recursion of the same shape::

    x̄_0 = x0,                      M_0 = M0
    x̄_i = A x̂_{i−1},               M_i = F P_{i−1} Fᵀ + Q_e          (i ≥ 1)
    K_i = M_i Hᵀ (H M_i Hᵀ + V)⁻¹
    P_i = (I − K_i H) M_i (I − K_i H)ᵀ + K_i V K_iᵀ                   (Joseph form)
    x̂_i = x̄_i + K_i (z_i − H x̄_i)

For the optimal filter ``A = F = Φⁿ`` with n = gps_every = 40 and ``Q_e = Σ_{j<n} Φʲ ΓWΓᵀ Φʲᵀ``
(exactly what 40 one-step predictions do).  A mistake changes one ingredient of this recursion:
the report's model (Φ(Δt), Γ(Δt), W, H, V, M0, x0) is a
:class:`~gpsaccel.kalman.linear_model.LinearModel` (:func:`linear_model`), and a filter for it is
that model's :class:`~gpsaccel.kalman.linear_model.LinearIngredients` (:func:`ingredients`), the
recursion itself :class:`~gpsaccel.kalman.epochs.EpochFilter` and
:func:`~gpsaccel.kalman.epochs.batch_gains` of :mod:`gpsaccel.kalman.epochs`.  ``phi-sign`` flips
the sign of Φ₁₃, ``process-noise-interval`` builds Φ and Γ with the GPS interval and steps once,
``m0-order`` swaps M0's first two diagonal elements, ``mean-not-propagated`` sets ``A = I``, and
so on (:func:`covariance_mistakes`, :func:`mean_mistakes`).  The ideas every system shares
(:mod:`gpsaccel.kalman.entries`: Joseph's sign, V left out of S, a prior off by a power of ten, no
process noise or one ∝ Δt, Γ's order, every other fix skipped, z one epoch late, an information
vector with V, x0 from the first fix, the other single signs of Φ) are the generic catalogue's,
worded by report 000's table where it has its own text.

The gains K_i and covariances M_i, P_i do not depend on the data, so :func:`batch_gains` computes
them once — for many candidate filters at once, as stacked arrays — and :meth:`EpochFilter.apply`
runs the mean recursion for all realizations at once: z of shape (n_runs, n_gps, 2) gives x̂ of
shape (n_runs, n_gps, 3).

Two stages, because P does not depend on the data: the covariance mistakes decide P (and the
gains); the mean mistakes change only x̂ and combine with any covariance entry, so a student who
makes one of each is still recognised.  Covariance mistakes that touch different ingredients
combine too (report 003's filter makes three at once: process-noise-interval and two
std-as-variance), see :func:`combinations`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cache, cached_property

import numpy as np

from gpsaccel.calibration.model import STATE_NAMES, CalibrationModel, gamma, phi
from gpsaccel.kalman import entries
from gpsaccel.kalman.epochs import EpochFilter, batch_gains  # noqa: F401 - re-exported
from gpsaccel.kalman.linear_catalogue import (
    LINEAR_MESSAGES,
    predict_before_first_update,
    shared_mistakes,
    state_orders,
    structural_mistakes,
    transposed_mistakes,
)
from gpsaccel.kalman.linear_model import LinearIngredients, LinearModel
from gpsaccel.kalman.mistakes import Mistake, combinations, with_changes  # noqa: F401


@dataclass(frozen=True, eq=False)
class Ingredients:
    """Report 000's filter in its own terms (the report's Δt of Φ and Γ, the signs of Φ₁₃ and
    Φ₂₃, a scalar W), for the lessons and a student's experiments (lesson 06's exercise builds the
    report's filters from it); :meth:`epoch_filter` assembles it into the core's
    :class:`~gpsaccel.kalman.linear_model.LinearIngredients`.  The catalogue's entries change
    those generic ingredients directly (:func:`ingredients`), so that the ideas every system
    shares are written once (:mod:`gpsaccel.kalman.entries`).

    phi_dt, sign13 : Φ = Φ(phi_dt) with Φ₁₃ = sign13·phi_dt²/2.
    gamma_dt, W : one-step process noise Q = Γ(gamma_dt) W Γ(gamma_dt)ᵀ.
    steps : one-step predictions between GPS updates (40; 1 when stepping over the GPS interval).
    H, V, M0, x0 : measurement matrix, GPS noise, prior covariance and mean.
    sign23 : Φ₂₃ = sign23·phi_dt.
    mean_propagated : False is the mean-not-propagated mistake (x̄_k = x̂_{k−1}).
    output, skip_first : see :class:`EpochFilter`; predict_first, update_P, update_every_step :
    see :class:`~gpsaccel.kalman.epochs.LinearIngredients`.
    """

    phi_dt: float
    sign13: float
    gamma_dt: float
    W: float
    steps: int
    H: np.ndarray
    V: np.ndarray
    M0: np.ndarray
    x0: np.ndarray
    n_gps: int
    mean_propagated: bool = True
    output: str = "posterior"
    skip_first: bool | str = False
    predict_first: bool = False
    sign23: float = -1.0
    update_P: bool = True
    update_every_step: bool = False

    @classmethod
    def correct(cls, model: CalibrationModel) -> Ingredients:
        return cls(model.dt, -1.0, model.dt, float(model.W[0, 0]), model.gps_every, model.H,
                   model.V, model.M0, model.x0, model.n_gps)

    def epoch_filter(self) -> EpochFilter:
        """The generic ingredients (:class:`gpsaccel.kalman.epochs.LinearIngredients`) of
        Φ(phi_dt) with its Φ₁₃ sign, Γ(gamma_dt) and W: the one epoch recursion of the core."""
        return LinearIngredients(phi(self.phi_dt, self.sign13, self.sign23),
                                 gamma(self.gamma_dt), np.array([[self.W]]), self.steps, self.H,
                                 self.V, self.M0, self.x0, self.n_gps, self.mean_propagated,
                                 self.output, self.skip_first, predict_first=self.predict_first,
                                 update_P=self.update_P,
                                 update_every_step=self.update_every_step).epoch_filter()

    def with_changes(self, changes: tuple[tuple, ...]) -> Ingredients:
        """Apply ``(field, value)`` or ``(field, (row, col), value)`` changes (see :class:`Mistake`)."""
        return with_changes(self, changes)


_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


#: Report 000's wording, one table: code (or code.part) -> template.  Its catalogue's entries (the
#: fields are the model's numbers, :func:`_fields`, and each entry's own) and its checker's findings
#: where they say more than the generic text (:class:`gpsaccel.check.problems.calibration
#: .CalibrationProblem` reads this table over :data:`gpsaccel.kalman.linear_messages.MESSAGES`
#: and the sandbox's :data:`gpsaccel.check.findings.MESSAGES`).
MESSAGES: dict[str, str] = {
    # ------------------------------------------------------------ the catalogue's entries
    "phi-sign.13": "Φ₁₃ has the wrong sign: the bias enters position as −Δt²/2 = {half_dt2:.4g}, "
                "and your filter uses +Δt²/2. Likely cause: the accelerometer reads a + b, so the "
                "integrated accelerometer runs ahead by the bias and δp = p − p_c loses b·Δt²/2 "
                "per step (report 001 prints the + sign).",
    "process-noise-interval": "The process noise between GPS fixes is Γ W Γᵀ built with the GPS "
                              "interval T = {T:g} s. Stepping once over T with Φ(T) is exact for "
                              "the mean, but the noise of {n} accelerometer samples adds up as "
                              "Σ_(j<{n}) Φʲ Γ W Γᵀ Φʲᵀ (velocity variance {n}·Δt²·W = "
                              "{var_n:.3g} (m/s)², not T²·W = {var_T:.3g}). Likely cause: Φ and "
                              "Γ written for the GPS step, as report 003 does; sum Q over the "
                              "{n} steps.",
    "m0-order": "M0 has position and velocity swapped: the state is [δp, δv, b], so M0 = "
                "diag({m_p:g} m², {m_v:g} (m/s)², {m_b:g} (m/s²)²); your filter starts with "
                "diag({m_v:g}, {m_p:g}, {m_b:g}) (as report 001 writes it).",
    "first-update-skipped": "Your filter does not use the GPS fix at t = 0: its first estimate "
                            "is the prior (x̂₀ = x̄₀, P₀ = M0) and its first update is at the "
                            "second GPS time. The GPS reports at t = 0 too; update with z₀ "
                            "before the first propagation.",
    "first-update-skipped.covariance": "Your P at t = 0 is the prior M0: the covariance update "
                                       "with the GPS fix at t = 0 is missing, though your x̂ at "
                                       "t = 0 did use z₀ (the mean was updated, P was not), and "
                                       "every later gain follows from that P. Update P at t = 0 "
                                       "too, before the first propagation.",
    "returns-a-priori": "Your filter returns the a priori estimate and covariance (x̄, M: before "
                        "the update) at each GPS time; the checker expects the a posteriori ones "
                        "(x̂, P: after the update with z at that time). Likely cause: the values "
                        "are stored before update().",
    "w-value": "W = {V22:g} is the GPS velocity-noise variance (0.04 m/s)²; the accelerometer "
               "noise variance is W = {W:g} (m/s²)² (report 001 writes 0.0016).",
    "missing-propagation": "Your filter propagates {steps_text} between GPS updates; there are "
                           "{n} (GPS {gps_hz:g} Hz, accelerometer {accel_hz:g} Hz). Likely "
                           "cause: {cause}.",
    "missing-propagation.fewer": "a loop such as range(1, {n}), or the first prediction placed "
                                 "before the loop",
    "missing-propagation.more": "an extra predict() at the update step",
    "missing-propagation.once": "one prediction with the {accel_hz:g} Hz Φ per GPS interval",
    "missing-propagation.tenth": "the GPS interval taken as {tenth:g} s (report 001 writes "
                                 "0.02 s for its 0.2 s)",
    "std-as-variance": "{elem} = {value:.4g} in your filter; it should be {right:.4g}: {label}. "
                       "A covariance holds variances σ² (here σ = {sigma:.4g}, σ² = {right:.4g}); "
                       "report 003 mixes them up the same way.",
    "std-as-variance.sigma": "a standard deviation used where a variance belongs",
    "std-as-variance.squared": "a variance squared again, as if it were a standard deviation",
    "covariance-update-skipped.never": "Your P is never updated: at every GPS time it is the a "
                                       "priori M, though your x̂ is updated with the gain "
                                       "K = M Hᵀ (H M Hᵀ + V)⁻¹ (so its σ only grows). The "
                                       "update of P is missing after each GPS update: "
                                       "P = (I − K H) M (I − K H)ᵀ + K V Kᵀ.",
    "update-every-step": "Your filter updates at every accelerometer step ({n} per GPS "
                         "interval), reusing the last GPS fix between fixes; the GPS reports at "
                         "{gps_hz:g} Hz, so only the steps with a new fix update (the others "
                         "only propagate).",
    "phi-sign.both": "Φ₁₃ and Φ₂₃ both have the wrong sign: the bias enters as if the "
                     "accelerometer read a − b. It reads a + b, so the integrated solution runs "
                     "ahead by the bias: −Δt²/2 in position and −Δt in velocity.",
    "state-order": "Your H is written for the state order [{order}]; the state is [δp, δv, b] "
                   "(Φ, M0 and your outputs follow it), so your H takes the GPS position for "
                   "{wrong}. Write H's columns in the state's order.",
    "mean-not-propagated": "Your covariance is propagated between GPS fixes but your estimate "
                           "is not: the residual uses x̂ₖ₋₁ where it should use x̄ₖ = Φ^{n} x̂ₖ₋₁ "
                           "(Φ applied at each of the {n} accelerometer steps). Likely cause: "
                           "x_bar = Phi @ x_hat is missing from the propagation loop, or its "
                           "result is not kept.",
    "x0-total-state": "Your error-state estimate starts at the total-state means [p̄0, v̄0, 0] = "
                      "[{p0:g}, {v0:g}, 0], as report 000's code does. The state is the error "
                      "[δp, δv, b] of the accelerometer-integrated solution, which itself starts "
                      "at (p̄0, v̄0), so the prior mean of the error is x̄₀ = [0, 0, 0].",
    # ----------------------------------------------------------- the checker's findings
    "no-function": "Your file does not define a function kalman_filter(z){found}. Functions it "
                   "defines: {callables}. Name your filter kalman_filter, taking z and returning "
                   "(x_hat, P).",
    "memory-limit": "Your code ran out of memory: a check may use {mib:g} MiB of address space, "
                    "and your file asked for more (after {done} of {n_calls} runs){tb} A filter "
                    "for {n_gps} GPS times needs a few kilobytes: look for an array sized by the "
                    "accelerometer steps squared, or a list that grows in a loop that never "
                    "ends.",
    "exception": "kalman_filter(z) raised an exception on {label}; the traceback ends "
                 "with:\n{traceback}",
    "epoch-shift.late": "one GPS time late: row k holds the estimate of time k − 1",
    "epoch-shift.early": "one GPS time early: row k holds the estimate of time k + 1",
    "p-mismatch.later": "P at t = 0 is right (so M0, H, V and the update are), but P differs "
                        "from t = {t:g} s on: the propagation between GPS fixes is wrong (Φ, "
                        "Q = Γ W Γᵀ, or the number of steps).",
    "p-mismatch.matrices": "Check your matrices with gpsaccel.check.model_matrices(Phi=..., "
                           "Gamma=..., H=..., V=..., W=..., M0=...).",
    "aliased-output": "Every row of your x_hat and P holds the same values, those of the last "
                      "GPS time (t = {t_last:g} s): each row is the same array object, changed "
                      "in place at every step (e.g. x += K @ r or P[:] = ..., then appended to a "
                      "list). Store a copy: x_hat[k] = x (into a preallocated array) or "
                      "xs.append(x.copy()).",
    "last-update-missing": "Your filter is right except at the last GPS time (t = {t:g} s), "
                           "where x̂ and P are the a priori x̄ and M: the update with the last "
                           "fix z[{row}] is missing (a loop such as range(n - 1), or the update "
                           "placed before the propagation).",
}


def _fields(model: CalibrationModel) -> dict[str, float]:
    """The model's numbers the messages quote."""
    dt, n, T, W = model.dt, model.gps_every, model.gps_interval, float(model.W[0, 0])
    m_p, m_v, m_b = (float(m) for m in np.diag(model.M0))
    return {"dt": dt, "n": n, "T": T, "W": W, "half_dt2": -dt**2 / 2, "var_n": n * dt**2 * W,
            "var_T": T**2 * W, "V11": float(model.V[0, 0]), "V22": float(model.V[1, 1]),
            "m_p": m_p, "m_v": m_v, "m_b": m_b, "gps_hz": 1 / T, "accel_hz": 1 / dt,
            "tenth": n // 10 * dt}


def linear_model(model: CalibrationModel) -> LinearModel:
    """Report 000's model as the core's :class:`~gpsaccel.kalman.linear_model.LinearModel`: Φ(Δt),
    Γ(Δt), W, H, V, M0, x0 at the accelerometer's step, a GPS fix every ``gps_every`` steps."""
    return LinearModel(phi(model.dt), gamma(model.dt), model.W, model.H, model.V, model.M0,
                       model.x0, model.gps_every, model.n_gps, model.dt, STATE_NAMES,
                       ("δp", "δv"))


def ingredients(model: CalibrationModel) -> LinearIngredients:
    """The optimal filter's ingredients (a mistake changes some of them)."""
    return LinearIngredients.correct(linear_model(model))


def _text(model: CalibrationModel):
    """``text(key, **fields)``: report 000's wording over the generic table, with its numbers."""
    f = _fields(model)
    table = {**LINEAR_MESSAGES, **MESSAGES}
    return lambda key, **fields: table[key].format(**{**f, **fields})


def covariance_mistakes(model: CalibrationModel | None = None) -> tuple[Mistake, ...]:
    """Mistakes that change P (and, through the gains and Φ, x̂) on ``model``'s numbers."""
    model = CalibrationModel() if model is None else model
    f = _fields(model)
    lm, text = linear_model(model), _text(model)
    out = (_model_mistakes(model, f) + _propagation_mistakes(model, f)
           + tuple(entries.std_as_variance(lm, text)))
    out += tuple(transposed_mistakes(lm, text))  # (the last epoch's: what is returned says it)
    return out + tuple(shared_mistakes(lm, text, skip=("process-noise-interval",))[0])


def _model_mistakes(model: CalibrationModel, f: dict[str, float]) -> tuple[Mistake, ...]:
    """One entry each: a sign, the interval, the prior's order, the schedule, the output, W."""
    lm, text = linear_model(model), _text(model)
    T, m_p, m_v = f["T"], f["m_p"], f["m_v"]
    entries_: tuple[tuple[str, str, tuple[tuple, ...]], ...] = (
        # the variant is what the student reads of a phi-sign: report 000's own names
        ("phi-sign.13", "Φ₁₃ = +Δt²/2: the bias enters δp as if the accelerometer read a − b",
         (("Phi", phi(model.dt, +1.0)),)),
        ("m0-order", "M0 with δp and δv swapped", (("M0", (0, 0), m_v), ("M0", (1, 1), m_p))),
        ("first-update-skipped", "no update at t = 0", (("skip_first", True),)),
        ("first-update-skipped.covariance", "P not updated at t = 0",
         (("skip_first", "covariance"),)),
        ("returns-a-priori", "returns (x̄, M)", (("output", "prior"),)),
        ("w-value", "W = V₂₂", (("W", np.array([[f["V22"]]])),)),
    )
    out = [Mistake(key.split(".")[0], variant, text(key), changes)
           for key, variant, changes in entries_]
    out[1:1] = entries.fix_interval(lm, text, variant=f"Φ, Γ built with T = {T:g} s, one step "
                                                      f"per GPS interval")
    out.insert(5, predict_before_first_update(LINEAR_MESSAGES["predict-before-first-update"]
                                              .format(measurement="GPS fix", every=f["n"],
                                                      step="accelerometer step")))
    return tuple(out) + _structural_mistakes(model, f)


def _structural_mistakes(model: CalibrationModel, f: dict[str, float]) -> tuple[Mistake, ...]:
    """The generic catalogue's structural entries (:func:`gpsaccel.kalman.linear_catalogue
    .structural_mistakes`: P never updated, an update at every step, Φ's other signs) on this
    model, in its wording; both bias entries of Φ and H for another state order in report 000's
    words."""
    lm, text = linear_model(model), _text(model)
    both = "Φ₁₃ and Φ₂₃"
    out = structural_mistakes(lm.Phi, lm.H, STATE_NAMES, model.gps_every, text,
                              step="accelerometer step", dt=model.dt, phi_signs=False,
                              orders=False)
    out.append(Mistake("phi-sign", "Φ₁₃ = +Δt²/2 and Φ₂₃ = +Δt: the bias enters δp and δv as if "
                       "the accelerometer read a − b", MESSAGES["phi-sign.both"],
                       (("Phi", phi(model.dt, +1.0, +1.0)),)))
    out += entries.phi_sign(lm, text, skip=("Φ₁₃", both))
    names = STATE_NAMES
    H = np.asarray(model.H, dtype=float)
    for order in state_orders(3):
        used = H[:, list(order)]
        if np.array_equal(used, H):
            continue
        wrong = names[int(np.argmax(used[0]))]
        out.append(Mistake("state-order", f"H for [{', '.join(names[i] for i in order)}]",
                           MESSAGES["state-order"].format(
                               order=", ".join(names[i] for i in order), wrong=wrong),
                           (("H", used),)))
    return tuple(out)


def _propagation_mistakes(model: CalibrationModel, f: dict[str, float]) -> tuple[Mistake, ...]:
    """The wrong number of accelerometer steps between GPS updates, each with its likely cause."""
    n = model.gps_every
    out = []
    for steps, cause in ((n - 1, "fewer"), (n + 1, "more"), (1, "once"), (n // 10, "tenth")):
        if steps < 1 or steps == n:
            continue
        text = MESSAGES["missing-propagation"].format(
            steps_text=_plural(steps, "accelerometer step"),
            cause=MESSAGES[f"missing-propagation.{cause}"].format(**f), **f)
        out.append(Mistake("missing-propagation", f"{_plural(steps, 'step')} between updates",
                           text, (("steps", steps),)))
    return tuple(out)


def mean_mistakes(model: CalibrationModel | None = None) -> tuple[Mistake, ...]:
    """Mistakes that change only how the estimate is carried (P is untouched)."""
    model = CalibrationModel() if model is None else model
    n = model.gps_every
    x0_total = np.array([model.p0_mean, model.v0_mean, 0.0])
    return (
        Mistake("mean-not-propagated", "x̄ₖ = x̂ₖ₋₁", MESSAGES["mean-not-propagated"].format(n=n),
                (("mean_propagated", False),)),
        Mistake("x0-total-state", f"x̄₀ = [{x0_total[0]:g}, {x0_total[1]:g}, 0]",
                MESSAGES["x0-total-state"].format(p0=x0_total[0], v0=x0_total[1]),
                (("x0", x0_total),)),
    ) + tuple(shared_mistakes(linear_model(model), _text(model))[1])


def build(model: CalibrationModel, mistakes: tuple[Mistake, ...] = ()) -> EpochFilter:
    """The epoch filter that makes ``mistakes`` (none: the optimal filter)."""
    g = ingredients(model)
    if mistakes:  # every entry's changes in turn, in one copy (a diagnosis builds thousands)
        g = with_changes(g, tuple(c for m in mistakes for c in m.changes))
    return g.epoch_filter()


def reference(model: CalibrationModel | None = None) -> EpochFilter:
    """The optimal filter at GPS epochs (A = F = Φ⁴⁰, Q_e the 40-step sum)."""
    return build(CalibrationModel() if model is None else model)


def catalogue(model: CalibrationModel | None = None) -> tuple[Mistake, ...]:
    """Every mistake, covariance mistakes first, each array it changes read-only: the default
    model's entries made once per process (:func:`default_catalogue`), a given model's anew (a
    CalibrationModel's arrays are its caller's to change, and a cache by model would keep every
    model a loop makes)."""
    return _of(model).catalogue()


def codes(model: CalibrationModel | None = None) -> tuple[str, ...]:
    """Every code of the catalogue, in catalogue order (:func:`catalogue`)."""
    return _of(model).codes()


def mutant(code: str, model: CalibrationModel | None = None, variant: str | None = None
           ) -> EpochFilter:
    """The filter that makes mistake ``code`` (its first variant unless ``variant`` is named)."""
    model = CalibrationModel() if model is None else model
    for m in catalogue(model):
        if m.code == code and (variant is None or m.variant == variant):
            return build(model, (m,))
    raise ValueError(f"code must be one of {', '.join(codes(model))} (with a known variant); "
                     f"got {code!r}" + ("" if variant is None else f", variant {variant!r}"))


@dataclass(frozen=True, eq=False)
class CalibrationCatalogue:
    """This catalogue in the interface every linear diagnosis reads
    (:class:`gpsaccel.kalman.epochs.Catalogue`), on ``model``'s numbers.  Its mistakes are made
    once per object (the model's numbers and wording, no data): a checker shares one object
    between the files of a class, so every array an entry changes is a read-only copy (a filter
    that writes into an ingredient in place raises instead of changing every later filter)."""

    model: CalibrationModel

    def covariance_mistakes(self) -> tuple[Mistake, ...]:
        return self._covariance

    def mean_mistakes(self) -> tuple[Mistake, ...]:
        return self._mean

    @cached_property
    def _covariance(self) -> tuple[Mistake, ...]:
        return _read_only(covariance_mistakes(self.model))

    @cached_property
    def _mean(self) -> tuple[Mistake, ...]:
        return _read_only(mean_mistakes(self.model))

    def build(self, mistakes: tuple[Mistake, ...] = ()) -> EpochFilter:
        g = self._ingredients
        if mistakes:  # every entry's changes in turn, in one copy (a diagnosis builds thousands)
            g = with_changes(g, tuple(c for m in mistakes for c in m.changes))
        return g.epoch_filter()

    @cached_property
    def _ingredients(self) -> LinearIngredients:
        return ingredients(self.model)

    def reference(self) -> EpochFilter:
        return reference(self.model)

    def catalogue(self) -> tuple[Mistake, ...]:
        return self._covariance + self._mean

    def codes(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(m.code for m in self.catalogue()))


def _read_only(mistakes: tuple[Mistake, ...]) -> tuple[Mistake, ...]:
    """The entries with every array they change replaced by a read-only copy of it."""
    def frozen(value: object) -> object:
        if not isinstance(value, np.ndarray):
            return value
        value = np.array(value)
        value.setflags(write=False)
        return value

    return tuple(replace(m, changes=tuple((*c[:-1], frozen(c[-1])) for c in m.changes))
                 for m in mistakes)


@cache
def default_catalogue() -> CalibrationCatalogue:
    """Report 000's catalogue on the default :class:`CalibrationModel`, one per process: its
    entries are the model's numbers and wording (no data), so every caller shares them
    (:func:`catalogue`, :func:`codes`, the checker's calibration problem)."""
    return CalibrationCatalogue(CalibrationModel())


def _of(model: CalibrationModel | None) -> CalibrationCatalogue:
    return default_catalogue() if model is None else CalibrationCatalogue(model)
