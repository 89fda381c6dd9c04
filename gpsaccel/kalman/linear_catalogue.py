r"""The catalogue of mistakes every linear filter can make, written for a model's numbers.

:class:`LinearCatalogue` gives, for any :class:`~gpsaccel.kalman.linear_model.LinearModel`, the
entries (:class:`~gpsaccel.kalman.mistakes.Mistake`) the checker matches a student's filter
against: each a change of :class:`~gpsaccel.kalman.linear_model.LinearIngredients`, worded by the
generic table :data:`gpsaccel.kalman.linear_messages.MESSAGES` (an instructor rewords any entry).
The ideas every system shares (a sign of Φ, σ for σ², a prior off by a power of ten, Joseph's
sign, V left out of S, no process noise or one ∝ Δt, Γ's order, Φ and Q for the whole interval,
every other measurement skipped, z one epoch late, an information vector with V, a wrong x0) are
written once in :mod:`gpsaccel.kalman.entries`; this module adds the linear filter's own
(Φᵀ, Q without Γ, M0's order, a skipped first or last update, the schedule, H's state order).
The calibration system keeps its own physical wording on the same machinery, and borrows
:func:`structural_mistakes`, :func:`shared_mistakes`, :func:`output_mistakes` and
:func:`predict_before_first_update`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gpsaccel.kalman import entries
from gpsaccel.kalman.entries import phi_sign_variants, state_orders  # noqa: F401 - their home once
from gpsaccel.kalman.epochs import EpochFilter
from gpsaccel.kalman.linear_messages import MESSAGES
from gpsaccel.kalman.linear_model import LinearIngredients, LinearModel
from gpsaccel.kalman.mistakes import Mistake, with_changes

#: The generic catalogue's wording: the linear table (:mod:`gpsaccel.kalman.linear_messages`).
LINEAR_MESSAGES = MESSAGES


def structural_mistakes(Phi: np.ndarray, H: np.ndarray, states: Sequence[str], every: int,
                        text, step: str = "propagation step", dt: float = 1.0,
                        phi_signs: bool = True, orders: bool = True) -> list[Mistake]:
    """The entries every linear filter can get wrong in its structure: P never updated, an
    update at every step (with the last measurement, or the next), Φ's signs
    (:func:`gpsaccel.kalman.entries.phi_sign`, unless ``phi_signs`` is False), H for another state
    order (unless ``orders`` is False).  ``text(key, **fields)`` words them (a system's own
    wording or :data:`LINEAR_MESSAGES`); Φ and H are changed as ``Phi`` and ``H`` ingredients."""
    out = [Mistake("covariance-update-skipped", "P never updated",
                   text("covariance-update-skipped.never"), (("update_P", False),),
                   where="every measurement time")]
    if every > 1:
        for which in ("last", "next"):
            out.append(Mistake("update-every-step", f"updated at every {step} with the {which} "
                               "measurement", text(
                                   "update-every-step" + (".next" if which == "next" else ""),
                                   step=step, every=every, interval=every * dt),
                               (("update_every_step", which),), alone=True))
    if phi_signs:
        out += entries.phi_sign(_Numbers(Phi=Phi, states=states), text)
    H = np.asarray(H, dtype=float)
    for order in state_orders(H.shape[1]) if orders else ():
        used = H[:, list(order)]
        if np.array_equal(used, H):
            continue  # H does not see the difference
        names = ", ".join(states[i] for i in order)
        out.append(Mistake("state-order", f"H for [{names}]",
                           text("state-order", order=names, states=", ".join(states)),
                           (("H", used),)))
    return out


def transposed_mistakes(m: LinearModel, text) -> list[Mistake]:
    """Φᵀ for Φ (``phi-transposed``), and Q = W·I or W for Γ W Γᵀ (``q-without-gamma``)."""
    n, k = m.n, m.Gamma.shape[1]
    out: list[Mistake] = []
    if not entries.same(m.Phi, m.Phi.T):
        out.append(Mistake("phi-transposed", "Φᵀ", text("phi-transposed"), (("Phi", m.Phi.T),)))
    # Q = W put on the states as they are: W itself (k = n), W·I (k = 1), or W once per block
    # of k states (k divides n: a 2×2 W = σ²I₂ on [px, py, vx, vy] gives σ²I₄)
    W_state = np.kron(np.eye(n // k), m.W) if n % k == 0 else None
    if W_state is not None and not entries.same(m.Gamma @ m.W @ m.Gamma.T, W_state):
        blocks = [f"[{', '.join(m.states[i:i + k])}]" for i in range(0, n, k)]
        used = "W·I" if k == 1 else "W" if k == n else "W on " + " and on ".join(blocks)
        out.append(Mistake("q-without-gamma", f"Q = {used}",
                           text("q-without-gamma", used=f"Q = {used}", m=k),
                           (("Gamma", np.eye(n)), ("W", W_state))))
    return out


class _Numbers:
    """A model's numbers, by name (what a constructor of :mod:`gpsaccel.kalman.entries` reads)."""

    def __init__(self, **numbers: object) -> None:
        self.__dict__.update(numbers)


def shared_mistakes(m: LinearModel, text, skip: tuple[str, ...] = ()
                    ) -> tuple[list[Mistake], list[Mistake]]:
    """The covariance and mean entries of :mod:`gpsaccel.kalman.entries` on a linear model's
    numbers (those whose code is in ``skip`` left out, for a system that words its own), worded
    by ``text``: what every linear problem gets, the calibration's and an instructor's alike."""
    cov: list[Mistake] = []
    for make in (entries.fix_interval, entries.process_noise, entries.gamma_order,
                 entries.residual_covariance, entries.joseph_sign, entries.prior_scale,
                 entries.fixes_skipped):
        cov += make(m, text)
    mean: list[Mistake] = []
    for make in (entries.measurement_late, entries.information_vector, entries.x0_wrong):
        mean += make(m, text)
    if m.n_epochs < 3:
        cov = [c for c in cov if c.code != "fixes-skipped"]
    return ([c for c in cov if c.code not in skip], [c for c in mean if c.code not in skip])


def output_mistakes(m: LinearModel, text) -> list[Mistake]:
    """The a priori returned, and a skipped first or last update (of x̂ and P, or of P only)."""
    t_last = float(m.t[-1])
    out = []
    for key, changes, variant, where in (
            ("returns-a-priori", (("output", "prior"),), "returns (x̄, M)", ""),
            ("first-update-skipped", (("skip_first", True),), "no update at t = 0", ""),
            ("first-update-skipped.covariance", (("skip_first", "covariance"),),
             "P not updated at t = 0", ""),
            ("last-update-missing.last", (("skip_last", True),), "no update at the last epoch",
             ""),
            ("covariance-update-skipped.last", (("skip_last", "covariance"),),
             "P not updated at the last epoch", f"the last epoch (t = {t_last:g} s)")):
        out.append(Mistake(key.split(".")[0], variant, text(key, t_last=t_last), changes,
                           where=where))
    return out


def predict_before_first_update(message: str) -> Mistake:
    """The entry ``predict-before-first-update`` (:attr:`LinearIngredients.predict_first`), the
    same for every linear system; ``message`` is the system's wording of it."""
    return Mistake("predict-before-first-update", "propagated before the update at t = 0",
                   message, (("predict_first", True),))


@dataclass(frozen=True, eq=False)
class LinearCatalogue:
    """The mistakes every linear filter can make, on ``model``'s numbers (:class:`Catalogue`).

    ``messages`` overrides :data:`LINEAR_MESSAGES` entry by entry (an instructor's wording).
    """

    model: LinearModel
    messages: dict[str, str] = field(default_factory=dict)

    def _text(self, key: str, **fields: object) -> str:
        return {**LINEAR_MESSAGES, **self.messages}[key].format(**fields)

    def build(self, mistakes: tuple[Mistake, ...] = ()) -> EpochFilter:
        g = LinearIngredients.correct(self.model)
        if mistakes:  # every entry's changes in turn, in one copy (a diagnosis builds ~1800)
            g = with_changes(g, tuple(c for m in mistakes for c in m.changes))
        return g.epoch_filter()

    def reference(self) -> EpochFilter:
        return self.build()

    def covariance_mistakes(self) -> tuple[Mistake, ...]:
        m = self.model
        out = transposed_mistakes(m, self._text)
        out += entries.std_as_variance(m, self._text)
        out += self._permuted_m0()
        out += output_mistakes(m, self._text)
        out.append(predict_before_first_update(self._text(
            "predict-before-first-update", measurement="measurement", every=m.every,
            step="propagation step")))
        for steps in sorted({m.every - 1, m.every + 1, 1} - {0, m.every}):
            out.append(Mistake("missing-propagation", f"{steps} step(s) between updates",
                               self._text("missing-propagation", steps=steps, every=m.every,
                                          dt=m.dt, interval=m.every * m.dt),
                               (("steps", steps),)))
        out += structural_mistakes(m.Phi, m.H, m.states, m.every, self._text, dt=m.dt)
        return tuple(out) + tuple(shared_mistakes(m, self._text)[0])

    def _permuted_m0(self) -> list[Mistake]:
        m, out = self.model, []
        d = np.diag(m.M0)
        for a, b in itertools.combinations(range(m.n), 2):
            if np.isclose(d[a], d[b]) or b != a + 1:
                continue  # neighbours only: a swapped pair of adjacent states
            used = d.copy()
            used[[a, b]] = d[[b, a]]
            out.append(Mistake("m0-order", f"M0 with {m.states[a]}, {m.states[b]} swapped",
                               self._text("m0-order", a=m.states[a], b=m.states[b],
                                          states=", ".join(m.states),
                                          right=", ".join(f"{v:g}" for v in d),
                                          used=", ".join(f"{v:g}" for v in used)),
                               (("M0", (a, a), float(d[b])), ("M0", (b, b), float(d[a])))))
        return out

    def mean_mistakes(self) -> tuple[Mistake, ...]:
        return (Mistake("mean-not-propagated", "x̄ₖ = x̂ₖ₋₁",
                        self._text("mean-not-propagated", every=self.model.every),
                        (("mean_propagated", False),)),) + tuple(
            shared_mistakes(self.model, self._text)[1])

    def catalogue(self) -> tuple[Mistake, ...]:
        return self.covariance_mistakes() + self.mean_mistakes()

    def codes(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(m.code for m in self.catalogue()))
