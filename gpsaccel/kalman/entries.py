r"""The known mistakes every system shares, one constructor per idea, written once.

A student makes the same slips whatever the system: σ where σ² belongs, one sign of Φ, Φ and Q
written for the whole measurement interval, a prior off by a power of ten, V left out of the
gain's S, Joseph's form with a sign wrong, no process noise (or one that grows like Δt), Γ's rows
in another order, z taken one epoch late, every other measurement skipped, an information vector
built with V, a wrong x0.  Each constructor here turns one idea into catalogue entries
(:class:`~gpsaccel.kalman.mistakes.Mistake`) for one model's numbers: its changes name the
ingredients every filter of the package understands under the same names (``Phi``, ``Gamma``,
``W``, ``Q``, ``V``, ``M0``, ``x0``, ``V_gain``, ``form``, ``updates``, ``z_shift``, ``z_weight``,
``x0_from_z``, ``steps``: :class:`~gpsaccel.kalman.linear_model.LinearIngredients` and the ship's
:class:`gpsaccel.ship.mistakes.Ingredients`), and its wording comes from the caller's
``text(key, **fields)`` (the generic table :data:`gpsaccel.kalman.linear_messages.MESSAGES`, or a
system's own over it).  So any linear model, the calibration problem, an instructor's own problem
and the ship get the same entry under the same code, each worded in its own states and names.

``m`` is the model's numbers: anything with ``Phi``, ``Gamma``, ``W``, ``H``, ``V``, ``M0``,
``x0``, ``every``, ``dt`` and ``states`` (:class:`~gpsaccel.kalman.linear_model.LinearModel`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from math import factorial
from typing import Any

import numpy as np

from gpsaccel.kalman.mistakes import Mistake
from gpsaccel.kalman.update import epoch_transition

Text = Callable[..., str]

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def subscript(name: str, i: int) -> str:
    """``V₂₂``: an element of a matrix, as the reports write it (1-based)."""
    return name + f"{i + 1}{i + 1}".translate(_SUB)


def measured(m: Any, i: int) -> str:
    """What measurement ``i`` of ``m`` is called: the name the problem gives it, else the state
    its row of H measures alone, else z with its 1-based number."""
    names = tuple(getattr(m, "measurements", ()) or ())
    if i < len(names) and names[i] != f"z{i + 1}":  # z1, z2 ...: LinearModel's unnamed default
        return names[i]
    row = np.asarray(m.H, dtype=float)[i]
    if np.count_nonzero(row) == 1:
        return str(m.states[int(np.flatnonzero(row)[0])])
    return f"z{i + 1}"


def holds(m: Any, name: str, i: int) -> str:
    """What the diagonal element ``i`` of covariance ``name`` (V, W or M0) holds, in the
    problem's own names: "the δv measurement's variance", "δp's prior variance"."""
    if name == "V":
        return f"the {measured(m, i)} measurement's variance"
    if name == "M0":
        return f"{m.states[i]}'s prior variance"
    n = np.asarray(getattr(m, name)).shape[0]
    return "the process noise's variance" if n == 1 else f"process noise {i + 1}'s variance"


def same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to 1e-9 relative, however small the numbers (no absolute floor: a model's Q may
    be 1e-12 throughout)."""
    return bool(np.allclose(a, b, rtol=1e-9, atol=0.0))


def _fmt(v: np.ndarray) -> str:
    return ", ".join(f"{float(a):g}" for a in np.ravel(v))


# ----------------------------------------------------------------------------------- Φ's signs
def _blocks(Phi: np.ndarray) -> int:
    """The size s of Φ's equal diagonal blocks (n = k·s, k ≥ 2, nothing outside the blocks), or
    0 when Φ is not block-diagonal so."""
    n = Phi.shape[0]
    for s in range(1, n // 2 + 1):
        if n % s:
            continue
        inside = np.kron(np.eye(n // s, dtype=bool), np.ones((s, s), dtype=bool))
        if not np.any(Phi[~inside]):
            return s
    return 0


def phi_sign_variants(Phi: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """(variant, Φ with signs flipped): each off-diagonal entry alone; every off-diagonal entry of
    a column that has several (one state entering the others with the wrong sign); for a Φ of
    equal diagonal blocks (the ship's three axes), one entry flipped in every block (a block
    written in a loop); and every coupling at once where no column variant covers it."""
    Phi = np.asarray(Phi, dtype=float)
    groups = _single_entries(Phi) + _column_entries(Phi) + _block_entries(Phi)
    off = _single_entries(Phi)
    if len(off) > 1 and all(np.count_nonzero(Phi[:, e[0][1]]) <= 2 for e in off):
        # every coupling flipped (e.g. −Δt in x and in y), unless a column variant covers it
        every = [e[0] for e in off]
        if every not in groups:
            groups.append(every)
    return [_flipped(Phi, entries) for entries in groups]


def _flipped(Phi: np.ndarray, entries: list[tuple[int, int]]) -> tuple[str, np.ndarray]:
    f = Phi.copy()
    for a, b in entries:
        f[a, b] = -Phi[a, b]
    return " and ".join(f"Φ{a + 1}{b + 1}".translate(_SUB) for a, b in entries), f


def _single_entries(Phi: np.ndarray) -> list[list[tuple[int, int]]]:
    n = Phi.shape[0]
    return [[(a, b)] for a, b in itertools.product(range(n), repeat=2)
            if a != b and Phi[a, b] != 0.0]


def _column_entries(Phi: np.ndarray) -> list[list[tuple[int, int]]]:
    n = Phi.shape[0]
    cols = [[(a, b) for a in range(n) if a != b and Phi[a, b] != 0.0] for b in range(n)]
    return [c for c in cols if len(c) > 1]


def _block_entries(Phi: np.ndarray) -> list[list[tuple[int, int]]]:
    n, s = Phi.shape[0], _blocks(Phi)
    if s < 2:
        return []
    same = ([(a + j, b + j) for j in range(0, n, s)]
            for a, b in itertools.product(range(s), repeat=2) if a != b)
    return [e for e in same if all(Phi[i] != 0.0 for i in e)]


def couplings(Phi: np.ndarray, flipped: np.ndarray, states) -> str:
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


def phi_sign(m: Any, text: Text, skip: tuple[str, ...] = ()) -> list[Mistake]:
    """``phi-sign``: Φ with the signs of :func:`phi_sign_variants` (those named in ``skip`` left
    to the caller, who words them its own way); the variant, which a student reads, says which
    state enters which, in the problem's names."""
    out = []
    for variant, flipped in phi_sign_variants(m.Phi):
        if variant in skip:
            continue
        n_flip = variant.count("Φ")
        entries = variant if n_flip == 1 else f"{n_flip} entries ({variant})"
        out.append(Mistake("phi-sign", f"{variant} sign flipped: how "
                           f"{couplings(m.Phi, flipped, m.states)}",
                           text("phi-sign", entries=entries), (("Phi", flipped),)))
    return out


# ------------------------------------------------------------------------------ variances
def std_as_variance(m: Any, text: Text, names: tuple[str, ...] = ("V", "W", "M0"),
                    whole: int = 4) -> list[Mistake]:
    """``std-as-variance``: σ for σ², or σ² squared again, in one diagonal element of each of
    ``names``, and in every element of one matrix at once (a matrix written with the σ's) where
    it has at least ``whole`` elements that show the slip: a linear diagnosis combines up to three
    entries, so a smaller matrix's whole slip is already a combination of its elements' (and a
    lesson counts those); the ship's matches its entries one at a time (``whole=2``).

    An element's variant, which the student reads, names it as the feedback does everywhere, in
    1-based course notation and the problem's own names, with the student's value ("V₂₂ =
    0.04, the δv measurement's variance"; a 1 × 1 matrix without indices, as the reports write
    W), never the value it should have."""
    out: list[Mistake] = []
    for name in names:
        mat = np.asarray(getattr(m, name), dtype=float)
        per_label: dict[str, list[tuple]] = {"sigma": [], "squared": []}
        for i in range(mat.shape[0]):
            right = float(mat[i, i])
            for value, label in ((np.sqrt(right), "sigma"), (right**2, "squared")):
                if np.isclose(value, right, rtol=1e-6):
                    continue  # σ = σ² (a variance of 1): this slip cannot be seen
                elem = name if mat.shape[0] == 1 else subscript(name, i)
                per_label[label].append((name, (i, i), float(value)))
                out.append(Mistake("std-as-variance", f"{elem} = {value:.4g}, "
                                   f"{holds(m, name, i)}",
                                   text("std-as-variance", elem=elem, value=float(value),
                                        right=right, label=text(f"std-as-variance.{label}"),
                                        sigma=float(np.sqrt(right))),
                                   ((name, (i, i), float(value)),)))
        for label, changes in per_label.items():
            if len(changes) >= max(whole, 2):
                what = "σ for σ²" if label == "sigma" else "σ² squared"
                values = ", ".join(f"{c[2]:.4g}" for c in changes)
                out.append(Mistake("std-as-variance", f"every element of {name}: {what} "
                                   f"({values})",
                                   text("std-as-variance.whole", name=name,
                                        label=text(f"std-as-variance.{label}")),
                                   tuple(changes), combined=2))
    return out


def prior_scale(m: Any, text: Text, powers: tuple[int, ...] = (-2, -1, 1, 2),
                name: str = "M0") -> list[Mistake]:
    """``prior-scale``: M0 off by a power of ten (every variance of the prior; ``name`` is what
    the system calls it)."""
    M0 = np.asarray(m.M0, dtype=float)
    return [Mistake("prior-scale", f"{name} × {10.0**p:g}", text("prior-scale", factor=10.0**p),
                    (("M0", M0 * 10.0**p),), combined=2) for p in powers]


# --------------------------------------------------------------------------- the update
def residual_covariance(m: Any, text: Text, name: str = "V") -> list[Mistake]:
    """``residual-covariance``: the gain's S = H M Hᵀ without V, or with the standard deviations
    √V (V diagonal); P's update keeps V (``name``: what the system calls V)."""
    V = np.asarray(m.V, dtype=float)
    out = [Mistake("residual-covariance", f"S = H M Hᵀ ({name} left out)",
                   text("residual-covariance.none"), (("V_gain", np.zeros_like(V)),),
                   combined=2)]
    if same(V, np.diag(np.diag(V))) and not same(np.sqrt(np.diag(V)), np.diag(V)):
        out.append(Mistake("residual-covariance", f"S = H M Hᵀ + √{name}",
                           text("residual-covariance.sqrt"),
                           (("V_gain", np.diag(np.sqrt(np.diag(V)))),), combined=2))
    return out


def joseph_sign(m: Any, text: Text, name: str = "V") -> list[Mistake]:
    """``joseph-sign``: Joseph's form with − K V Kᵀ, or with I + K H."""
    return [Mistake("joseph-sign", variant, text(f"joseph-sign.{form}"), (("form", form),),
                    combined=2)
            for form, variant in (("minus", f"(I − K H) M (I − K H)ᵀ − K {name} Kᵀ"),
                                  ("plus", f"(I + K H) M (I + K H)ᵀ + K {name} Kᵀ"))]


def fixes_skipped(m: Any, text: Text, which: dict[str, str] | None = None,
                  title: str = "updates at {which}") -> list[Mistake]:
    """``fixes-skipped``: updates only at every other epoch (the others only propagate):
    ``updates`` "even" keeps the 1st, 3rd, ... measurement, "odd" the 2nd, 4th, ...; ``which``
    names those kept for the system (epochs, or the ship's GPS fixes), ``title`` the entry."""
    which = which or {"even": "epochs 0, 2, 4, ...", "odd": "epochs 1, 3, 5, ..."}
    return [Mistake("fixes-skipped", title.format(which=w), text("fixes-skipped", which=w),
                    (("updates", key),), combined=2) for key, w in which.items()]


# ------------------------------------------------------------------------------ the noise
def _unipotent_log(Phi: np.ndarray) -> np.ndarray | None:
    """A·Δt = log Φ when Φ − I is nilpotent (a kinematic model: the series ends), else None."""
    n = Phi.shape[0]
    N = Phi - np.eye(n)
    if not np.allclose(np.linalg.matrix_power(N, n), 0.0, atol=1e-14):
        return None
    out, Nk = np.zeros_like(N), np.eye(n)
    for k in range(1, n + 1):
        Nk = Nk @ N
        out += (-1) ** (k + 1) * Nk / k
    return out


def continuous_q(Phi: np.ndarray, Gamma: np.ndarray, W: np.ndarray, dt: float
                 ) -> np.ndarray | None:
    """Q of a continuous white noise of spectral density W that enters as Γ's zero-order hold
    does: ∫₀^Δt e^{Aτ} G W Gᵀ e^{Aᵀτ} dτ with e^{AΔt} = Φ and ∫₀^Δt e^{Aτ} dτ G = Γ (what
    filterpy's ``Q_continuous_white_noise`` gives a kinematic model; it grows like Δt where the
    model's Γ W Γᵀ grows like Δt²).  None unless Φ − I is nilpotent and Γ is such a hold."""
    Adt = _unipotent_log(np.asarray(Phi, dtype=float))
    if Adt is None:
        return None
    n = Phi.shape[0]
    A = Adt / dt
    powers = [np.linalg.matrix_power(A, k) for k in range(n)]
    hold = sum(powers[k] * dt ** (k + 1) / factorial(k + 1) for k in range(n))
    G = np.linalg.lstsq(hold, Gamma, rcond=None)[0]
    if not np.allclose(hold @ G, Gamma, rtol=1e-9, atol=1e-15):
        return None
    GWG = G @ W @ G.T
    Q = np.zeros((n, n))
    for j, k in itertools.product(range(n), repeat=2):   # ∫ τ^(j+k)/(j! k!) A^j GWGᵀ A^kᵀ dτ
        Q += (powers[j] @ GWG @ powers[k].T * dt ** (j + k + 1)
              / (factorial(j) * factorial(k) * (j + k + 1)))
    return (Q + Q.T) / 2


def process_noise(m: Any, text: Text, dt_scaled: bool = True) -> list[Mistake]:
    """``process-noise``: no Q, the Q of a continuous white noise (∝ Δt, :func:`continuous_q`), or
    Γ W Γᵀ scaled by Δt."""
    Q = m.Gamma @ m.W @ m.Gamma.T
    out = [Mistake("process-noise", "Q = 0", text("process-noise.zero"),
                   (("Q", np.zeros_like(Q)),), combined=2)]
    Qc = continuous_q(m.Phi, m.Gamma, m.W, m.dt)
    if Qc is not None and not same(Qc, Q):
        out.append(Mistake("process-noise", "Q of a continuous white noise (∝ Δt)",
                           text("process-noise.continuous"), (("Q", Qc),), combined=2))
    if dt_scaled and m.dt != 1.0:
        out.append(Mistake("process-noise", "Q = Γ W Γᵀ · Δt", text("process-noise.dt",
                                                                     dt=m.dt),
                           (("Q", Q * m.dt),), combined=2))
    return out


def fix_interval(m: Any, text: Text, variant: str = "", **fields: object) -> list[Mistake]:
    """``process-noise-interval``: one step per measurement interval T with Φ and Γ written for T
    (Φ_T = Φⁿ, exact for the mean; Γ_T = Σ_(j<n) Φʲ Γ, the input held over T), so Q =
    Γ_T W Γ_Tᵀ instead of the n steps' Σ Φʲ Γ W Γᵀ Φʲᵀ.  None for a model updated every step."""
    n = int(m.every)
    if n < 2:
        return []
    Phi = np.asarray(m.Phi, dtype=float)
    F = epoch_transition(Phi, np.zeros_like(Phi), n)[0]
    G = sum(np.linalg.matrix_power(Phi, j) @ m.Gamma for j in range(n))
    T = n * m.dt
    return [Mistake("process-noise-interval", variant or f"Φ, Γ written for T = {T:g} s, one "
                    f"step per interval", text("process-noise-interval", interval=T, every=n,
                                               dt=m.dt, **fields),
                    (("Phi", F), ("Gamma", G), ("steps", 1)))]


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


def gamma_order(m: Any, text: Text) -> list[Mistake]:
    """``gamma-order``: Γ's rows in another state order (:func:`state_orders`), or Γᵀ for a
    square Γ."""
    G = np.asarray(m.Gamma, dtype=float)
    Q = G @ m.W @ G.T
    out, seen = [], [Q]
    for order in state_orders(G.shape[0]):
        used = G[list(order)]
        if any(same(used @ m.W @ used.T, q) for q in seen):
            continue  # the noise does not see the difference
        seen.append(used @ m.W @ used.T)
        names = ", ".join(m.states[i] for i in order)
        out.append(Mistake("gamma-order", f"Γ's rows for [{names}]", text(
            "gamma-order", order=names, states=", ".join(m.states)), (("Gamma", used),),
            combined=2))
    if G.shape[0] == G.shape[1] and not same(G.T @ m.W @ G, Q):
        out.append(Mistake("gamma-order", "Γᵀ", text("gamma-order.transposed"),
                           (("Gamma", G.T),), combined=2))
    return out


# ----------------------------------------------------------------------------- the mean
def measurement_late(m: Any, text: Text, wrap: bool = True,
                     first: str = "z[k − 1] for z[k] (z[0] at the first)") -> list[Mistake]:
    """``measurement-late``: each epoch updated with the previous epoch's z (the first with z₀,
    or with z[−1], Python's last row; ``first`` names the first variant)."""
    out = [Mistake("measurement-late", first,
                   text("measurement-late", first=text("measurement-late.first")),
                   (("z_shift", "first"),))]
    if wrap:
        out.append(Mistake("measurement-late", "z[k − 1] for z[k] (z[−1] at the first)",
                           text("measurement-late", first=text("measurement-late.wrap")),
                           (("z_shift", "wrap"),)))
    return out


def information_vector(m: Any, text: Text) -> list[Mistake]:
    """``information-vector``: y = M⁻¹ x̄ + Hᵀ V z (V for V⁻¹) with the right Y: x̂ = x̄ + K (V² z −
    H x̄) (:class:`gpsaccel.kalman.epochs.EpochFilter`'s ``z_weight``)."""
    V = np.asarray(m.V, dtype=float)
    if same(V @ V, np.eye(V.shape[0])):
        return []  # V = V⁻¹: the slip cannot be seen
    return [Mistake("information-vector", "y = M⁻¹ x̄ + Hᵀ V z", text("information-vector"),
                    (("z_weight", V @ V),))]


def x0_wrong(m: Any, text: Text, from_z: bool = True) -> list[Mistake]:
    """``x0-wrong``: the prior mean started at 0 (where x0 ≠ 0) or at the first measurement."""
    x0 = np.asarray(m.x0, dtype=float)
    fields = {"x0": _fmt(x0), "states": ", ".join(m.states)}
    out = []
    if np.any(x0 != 0.0):
        out.append(Mistake("x0-wrong", "x̄₀ = 0", text("x0-wrong.zero", **fields),
                           (("x0", np.zeros_like(x0)),)))
    if from_z:
        out.append(Mistake("x0-wrong", "x̄₀ from z₀ (H⁺ z₀)", text("x0-wrong.first", **fields),
                           (("x0_from_z", True),)))
    return out
