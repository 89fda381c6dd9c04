r"""The catalogue of mistakes every linear filter can make, written for a model's numbers.

:class:`LinearCatalogue` gives, for any :class:`~gpsaccel.kalman.linear_model.LinearModel`, the
entries (:class:`~gpsaccel.kalman.mistakes.Mistake`) the checker matches a student's filter
against: each a change of :class:`~gpsaccel.kalman.linear_model.LinearIngredients`, worded by the
generic table :data:`gpsaccel.kalman.linear_messages.MESSAGES` (an instructor rewords any entry).
The calibration system keeps its own physical wording on the same machinery, and borrows
:func:`structural_mistakes`, :func:`state_orders` and :func:`predict_before_first_update`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gpsaccel.kalman.epochs import EpochFilter
from gpsaccel.kalman.linear_messages import MESSAGES
from gpsaccel.kalman.linear_model import LinearIngredients, LinearModel
from gpsaccel.kalman.mistakes import Mistake, with_changes

#: The generic catalogue's wording: the linear table (:mod:`gpsaccel.kalman.linear_messages`).
LINEAR_MESSAGES = MESSAGES

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def phi_sign_variants(Phi: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """(variant, Φ with signs flipped): each off-diagonal entry alone, and every off-diagonal
    entry of a column that has several (one state entering the others with the wrong sign)."""
    Phi = np.asarray(Phi, dtype=float)
    n = Phi.shape[0]
    out = []
    for a, b in itertools.product(range(n), repeat=2):
        if a != b and Phi[a, b] != 0.0:
            flipped = Phi.copy()
            flipped[a, b] = -Phi[a, b]
            out.append((f"Φ{a + 1}{b + 1}".translate(_SUB), flipped))
    for b in range(n):
        rows = [a for a in range(n) if a != b and Phi[a, b] != 0.0]
        if len(rows) > 1:
            flipped = Phi.copy()
            flipped[rows, b] = -Phi[rows, b]
            out.append((" and ".join(f"Φ{a + 1}{b + 1}".translate(_SUB) for a in rows), flipped))
    off = [(a, b) for a, b in itertools.product(range(n), repeat=2) if a != b and Phi[a, b] != 0]
    if len(off) > 1 and all(np.count_nonzero(Phi[:, b]) <= 2 for _, b in off):
        # every coupling flipped (e.g. −Δt in x and in y), unless a column variant covers it
        flipped = Phi.copy()
        for a, b in off:
            flipped[a, b] = -Phi[a, b]
        out.append((" and ".join(f"Φ{a + 1}{b + 1}".translate(_SUB) for a, b in off), flipped))
    return out


def _couplings(Phi: np.ndarray, flipped: np.ndarray, states: Sequence[str]) -> str:
    """Which state enters which through the flipped entries of Φ, in the states' names
    ("vx enters px", "b enters δp and δv")."""
    rows, cols = np.nonzero(np.asarray(flipped) != np.asarray(Phi, dtype=float))
    by_source: dict[int, list[int]] = {}
    for a, b in zip(rows.tolist(), cols.tolist(), strict=True):
        by_source.setdefault(b, []).append(a)
    said = []
    for b, into in by_source.items():
        names = [states[a] for a in into]
        said.append(f"{states[b]} enters " + (names[0] if len(names) == 1 else
                                               ", ".join(names[:-1]) + f" and {names[-1]}"))
    return "; ".join(said)


def state_orders(n: int) -> list[tuple[int, ...]]:
    """Other orders a student may write the state in: the interleaved and blocked orders of
    pairs ([x, vx, y, vy] ↔ [x, y, vx, vy]) for an even n ≥ 4, else neighbours swapped."""
    if n >= 4 and n % 2 == 0:
        k = n // 2
        blocked = tuple(range(0, n, 2)) + tuple(range(1, n, 2))
        interleaved = tuple(i for pair in zip(range(k), range(k, n), strict=True)
                            for i in pair)
        return [blocked, interleaved]
    return [tuple(list(range(a)) + [a + 1, a] + list(range(a + 2, n))) for a in range(n - 1)]


def structural_mistakes(Phi: np.ndarray, H: np.ndarray, states: Sequence[str], every: int,
                        text, step: str = "propagation step", dt: float = 1.0
                        ) -> list[Mistake]:
    """The entries every linear filter can get wrong in its structure: P never updated, an
    update at every step, Φ's signs, H for another state order.  ``text(key, **fields)`` words
    them (a system's own wording or :data:`LINEAR_MESSAGES`); Φ and H are changed as ``Phi``
    and ``H`` ingredients."""
    out = [Mistake("covariance-update-skipped", "P never updated",
                   text("covariance-update-skipped.never"), (("update_P", False),))]
    if every > 1:
        out.append(Mistake("update-every-step", f"updated at every {step}",
                           text("update-every-step", step=step, every=every,
                                interval=every * dt), (("update_every_step", True),),
                           alone=True))
    for variant, flipped in phi_sign_variants(Phi):
        n_flip = variant.count("Φ")
        entries = variant if n_flip == 1 else f"{n_flip} entries ({variant})"
        # the variant is what the student reads: which state enters which, in the problem's names
        out.append(Mistake("phi-sign", f"{variant} sign flipped: how {_couplings(Phi, flipped, states)}",
                           text("phi-sign", entries=entries), (("Phi", flipped),)))
    H = np.asarray(H, dtype=float)
    for order in state_orders(H.shape[1]):
        used = H[:, list(order)]
        if np.array_equal(used, H):
            continue  # H does not see the difference
        names = ", ".join(states[i] for i in order)
        out.append(Mistake("state-order", f"H for [{names}]",
                           text("state-order", order=names, states=", ".join(states)),
                           (("H", used),)))
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
        n, k = m.n, m.Gamma.shape[1]
        out: list[Mistake] = []
        if not np.allclose(m.Phi, m.Phi.T):
            out.append(Mistake("phi-transposed", "Φᵀ", self._text("phi-transposed"),
                               (("Phi", m.Phi.T),)))
        # Q = W put on the states as they are: W itself (k = n), W·I (k = 1), or W once per
        # block of k states (k divides n: a 2×2 W = σ²I₂ on [px, py, vx, vy] gives σ²I₄)
        W_state = np.kron(np.eye(n // k), m.W) if n % k == 0 else None
        if W_state is not None and not np.allclose(m.Gamma @ m.W @ m.Gamma.T, W_state):
            blocks = [f"[{', '.join(m.states[i:i + k])}]" for i in range(0, n, k)]
            used = "W·I" if k == 1 else "W" if k == n else "W on " + " and on ".join(blocks)
            out.append(Mistake("q-without-gamma", f"Q = {used}",
                               self._text("q-without-gamma", used=f"Q = {used}", m=k),
                               (("Gamma", np.eye(n)), ("W", W_state))))
        out += self._std_as_variance()
        out += self._permuted_m0()
        for key, changes, variant in (
                ("returns-a-priori", (("output", "prior"),), "returns (x̄, M)"),
                ("first-update-skipped", (("skip_first", True),), "no update at t = 0"),
                ("first-update-skipped.covariance", (("skip_first", "covariance"),),
                 "P not updated at t = 0"),
                ("last-update-missing.last", (("skip_last", True),), "no update at the last epoch"),
                ("covariance-update-skipped.last", (("skip_last", "covariance"),),
                 "P not updated at the last epoch")):
            out.append(Mistake(key.split(".")[0], variant,
                               self._text(key, t_last=float(m.t[-1])), changes))
        out.append(predict_before_first_update(self._text(
            "predict-before-first-update", measurement="measurement", every=m.every,
            step="propagation step")))
        for steps in sorted({m.every - 1, m.every + 1, 1} - {0, m.every}):
            out.append(Mistake("missing-propagation", f"{steps} step(s) between updates",
                               self._text("missing-propagation", steps=steps, every=m.every,
                                          dt=m.dt, interval=m.every * m.dt),
                               (("steps", steps),)))
        out += structural_mistakes(m.Phi, m.H, m.states, m.every, self._text, dt=m.dt)
        return tuple(out)

    def _std_as_variance(self) -> list[Mistake]:
        out: list[Mistake] = []
        sva = "a standard deviation used where a variance belongs"
        avs = "a variance squared again, as if it were a standard deviation"
        for name in ("V", "W", "M0"):
            mat = getattr(self.model, name)
            for i in range(mat.shape[0]):
                right = float(mat[i, i])
                for value, label in ((np.sqrt(right), sva), (right**2, avs)):
                    if np.isclose(value, right, rtol=1e-6):
                        continue  # σ = σ² (a variance of 1): this slip cannot be seen
                    elem = f"{name}[{i},{i}]"
                    out.append(Mistake("std-as-variance", f"{elem} = {value:.4g}",
                                       self._text("std-as-variance", elem=elem,
                                                  value=float(value), right=right, label=label,
                                                  sigma=float(np.sqrt(right))),
                                       ((name, (i, i), float(value)),)))
        return out

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
                        (("mean_propagated", False),)),)

    def catalogue(self) -> tuple[Mistake, ...]:
        return self.covariance_mistakes() + self.mean_mistakes()

    def codes(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(m.code for m in self.catalogue()))
