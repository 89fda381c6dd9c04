r"""A linear filter at its measurement epochs, the mistakes a student makes writing one, and any linear
model's catalogue of them.

Every filter a student writes for a linear problem whose measurements arrive every ``every``-th
propagation step — right or wrong — is, at the measurement epochs, a recursion of one shape::

    x̄_0 = x0,                      M_0 = M0
    x̄_i = A x̂_{i−1},               M_i = F P_{i−1} Fᵀ + Q_e          (i ≥ 1)
    K_i = M_i Hᵀ (H M_i Hᵀ + V)⁻¹
    P_i = (I − K_i H) M_i (I − K_i H)ᵀ + K_i V K_iᵀ                   (Joseph form)
    x̂_i = x̄_i + K_i (z_i − H x̄_i)

The optimal filter has ``A = F = Φⁿ`` (n = every) and ``Q_e = Σ_{j<n} Φʲ ΓWΓᵀ Φʲᵀ``
(:func:`gpsaccel.kalman.update.epoch_transition`, exactly what n one-step predictions do).  A
mistake (:class:`Mistake`) changes one ingredient of it; the gains and covariances do not depend
on the data, so :func:`batch_gains` computes them once for many candidate filters at once and
:meth:`EpochFilter.apply` runs the mean for every realization at once.

:class:`LinearModel` is any such model (Φ, Γ, W, H, V, M0, x0 and the schedule ``every``,
``n_epochs``); :func:`linear_catalogue` is the catalogue of mistakes every linear filter can make,
written for that model's numbers (the calibration system keeps its own physical wording on the
same machinery).  Nothing here knows a system.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING, Protocol

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import epoch_transition, gain, joseph_update

if TYPE_CHECKING:  # filterpy pulls in scipy.stats (0.6 CPU s): imported where a filter is made
    from filterpy.kalman import KalmanFilter


# ------------------------------------------------------------------------------ the epoch filter
@dataclass(frozen=True, eq=False)
class EpochFilter:
    """A linear filter written at the measurement epochs (module docstring for the recursion).

    A : (n, n) mean transition from one epoch to the next (x̄_i = A x̂_{i−1}).
    F, Qe : (n, n) covariance transition and process noise between epochs (M_i = F P Fᵀ + Qe).
    H (p, n), V (p, p), x0 (n,), M0 (n, n): measurement model and prior at the first epoch.
    n_gps : number of epochs.
    output : ``"posterior"`` returns (x̂, P); ``"prior"`` returns (x̄, M) (returns-a-priori).
    skip_first, skip_last : True skips the update at the first (last) epoch; ``"covariance"``
        updates the mean there but leaves P = M (so every later gain follows the skipped P).
    update_P : False never updates P (P_i = M_i at every epoch; the gains K_i = M_i Hᵀ S⁻¹ still
        update the mean): covariance-update-skipped everywhere.
    fast : None, or (Φ, Q, n) of one propagation step when the filter updates at *every* step
        (n per epoch interval) with the last measurement it has, z_{i−1}, until z_i arrives
        (update-every-step); A, F, Qe are then unused between epochs.
    """

    A: np.ndarray
    F: np.ndarray
    Qe: np.ndarray
    H: np.ndarray
    V: np.ndarray
    x0: np.ndarray
    M0: np.ndarray
    n_gps: int
    output: str = "posterior"
    skip_first: bool | str = False
    skip_last: bool | str = False
    update_P: bool = True
    fast: tuple | None = None

    @cached_property
    def gains(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K, M, P): gains (n_gps, n, p), a priori and a posteriori covariances (n_gps, n, n)."""
        K, M, P = batch_gains([self])
        return K[0], M[0], P[0]

    @cached_property
    def fast_gains(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(K, M, P, K_between) of a filter that updates at every step (``fast``): the epochs'
        K, M, P as :attr:`gains`, and K_between (n_gps, n − 1, n, p) the gains of the updates
        between epoch i − 1 and epoch i (row 0 unused)."""
        assert self.fast is not None, "fast_gains is for a filter that updates at every step"
        Phi, Q, steps = self.fast
        n_gps, (p, n) = self.n_gps, self.H.shape
        K, M, P = np.zeros((n_gps, n, p)), np.empty((n_gps, n, n)), np.empty((n_gps, n, n))
        Kb = np.zeros((n_gps, max(steps - 1, 0), n, p))
        C = self.M0
        for i in range(n_gps):
            for s in range(steps if i else 0):
                C = Phi @ C @ Phi.T + Q                          # one step: M = Φ P Φᵀ + Q
                if s < steps - 1:                                # an update with z_{i−1}
                    Kb[i, s] = gain(C, self.H, self.V)[0]
                    C = joseph_update(C, Kb[i, s], self.H, self.V)
            M[i] = C
            K[i] = gain(C, self.H, self.V)[0]
            C = joseph_update(C, K[i], self.H, self.V)
            P[i] = (C + C.T) / 2
            C = P[i]
        return K, M, P, Kb

    @property
    def P_out(self) -> np.ndarray:
        """The covariance this filter returns: P, or M with ``output="prior"``."""
        _, M, P = self.gains
        return M if self.output == "prior" else P

    def apply(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Run on z (n_runs, n_gps, p) → (x (n_runs, n_gps, n), P (n_gps, n, n)), as returned.

        With ``output="posterior"`` these are x̂ and P; with ``"prior"`` x̄ and M.
        """
        z = np.asarray(z, dtype=float)
        K, M, P = self.gains
        n_runs, n = z.shape[0], self.A.shape[0]
        x_bar = np.empty((n_runs, self.n_gps, n))
        x_hat = np.empty_like(x_bar)
        xb = np.broadcast_to(np.asarray(self.x0, dtype=float), (n_runs, n))
        Kb = self.fast_gains[3] if self.fast is not None else None
        for i in range(self.n_gps):
            if i and Kb is not None:
                xb = self._between(x_hat[:, i - 1], z[:, i - 1], Kb[i])
            elif i:
                xb = x_hat[:, i - 1] @ self.A.T
            x_bar[:, i] = xb
            r = z[:, i] - xb @ self.H.T                       # r_i = z_i − H x̄_i
            x_hat[:, i] = xb + r @ K[i].T                     # x̂_i = x̄_i + K_i r_i
        if self.output == "prior":
            return x_bar, M
        return x_hat, P

    def _between(self, x: np.ndarray, z: np.ndarray, Kb: np.ndarray) -> np.ndarray:
        """x̄_i of a filter that updates at every step with z_{i−1} (``fast``), from x̂_{i−1}."""
        assert self.fast is not None
        Phi = self.fast[0]
        for K in Kb:
            x = x @ Phi.T
            x = x + (z - x @ self.H.T) @ K.T
        return x @ Phi.T


def batch_gains(filters: Sequence[EpochFilter]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gains and covariances of many filters at once: K (C, n_gps, n, p), M and P (C, n_gps, n, n).

    All filters must share n_gps and the state/measurement sizes.  The Joseph update
    (:func:`gpsaccel.kalman.update.joseph_update`) keeps P symmetric and positive definite even
    for badly scaled mistakes.
    """
    n_gps = filters[0].n_gps
    skip = {(i, kind): np.array([_skips(f, i, n_gps, kind) for f in filters])
            for i in {0, n_gps - 1} for kind in ("P", "x")}
    hold = np.array([not f.update_P for f in filters])
    F, Qe, H, V, M0 = (np.stack([getattr(f, a) for f in filters])
                       for a in ("F", "Qe", "H", "V", "M0"))
    K, M, P, _ = gain_recursion(F, Qe, H, V, M0, n_gps, skip=skip,
                                hold=hold if hold.any() else None)
    for c, f in enumerate(filters):
        if f.fast is not None:                        # updates between the epochs: its own loop
            K[c], M[c], P[c] = f.fast_gains[:3]
    return K, M, P


def gain_recursion(F: np.ndarray, Qe: np.ndarray, H: np.ndarray, V: np.ndarray, M0: np.ndarray,
                   n_gps: int, inverse: bool = False, symmetrise: bool = True,
                   skip: dict | None = None, hold: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(K, M, P, S) of the epoch recursion (module docstring) for n_gps epochs: the one loop.

    The matrices may carry leading axes (a stack of filters, ``batch_gains``), or none (one
    filter, the calibration ensemble's plan).  ``inverse``: S⁻¹ formed as filterpy does
    (:func:`gpsaccel.kalman.update.gain`).  ``symmetrise``: P ← (P + Pᵀ)/2 after each update.
    ``skip``: {(epoch, "P" or "x"): (C,) bool} the filters that skip that update at that epoch.
    ``hold``: (C,) bool, the filters whose P is never updated (P_i = M_i at every epoch).
    """
    lead, (n, p) = F.shape[:-2], (F.shape[-1], H.shape[-2])
    K = np.zeros(lead + (n_gps, n, p))
    M = np.empty(lead + (n_gps, n, n))
    P = np.empty(lead + (n_gps, n, n))
    S = np.empty(lead + (n_gps, p, p))
    Ft = np.swapaxes(F, -1, -2)
    skip = skip or {}
    for i in range(n_gps):
        Mi = M0 if i == 0 else F @ P[..., i - 1, :, :] @ Ft + Qe    # M_i = F P_{i−1} Fᵀ + Q_e
        M[..., i, :, :] = Mi
        Ki, S[..., i, :, :] = gain(Mi, H, V, inverse=inverse)    # K_i = M Hᵀ (H M Hᵀ + V)⁻¹
        Kp = Ki
        if (i, "P") in skip:
            Kp = np.where(skip[i, "P"][:, None, None], 0.0, Ki)   # P_i = M_i
            Ki = np.where(skip[i, "x"][:, None, None], 0.0, Ki)   # and x̂_i = x̄_i
        if hold is not None:
            Kp = np.where(hold[:, None, None], 0.0, Kp)          # P never updated
        Pi = joseph_update(Mi, Kp, H, V)
        K[..., i, :, :] = Ki
        P[..., i, :, :] = (Pi + np.swapaxes(Pi, -1, -2)) / 2 if symmetrise else Pi
    return K, M, P, S


def _skips(f: EpochFilter, i: int, n_gps: int, kind: str) -> bool:
    """Whether filter ``f`` skips the covariance ("P") or the mean ("x") update at epoch i."""
    how = (f.skip_first if i == 0 else False) or (f.skip_last if i == n_gps - 1 else False)
    return bool(how) if kind == "P" else how is True


# ------------------------------------------------------------------------------ the mistakes
@dataclass(frozen=True)
class Mistake:
    """One entry of a catalogue.

    code : the stable code students and instructors see (``"phi-sign"``).
    variant : which form of the mistake (``"V[2,2] = 0.04"``); a code can have several.
    message : what is wrong, what it should be and the likely cause, for the student.
    changes : the ingredients it changes, ``(field, value)`` or ``(field, (row, col), value)``.
    hint : where to look, said only when the evidence is this mistake (may be empty).
    alone : True for an entry matched only on its own, never combined with others (its filter
        has its own loop: update-every-step).

    Every system's catalogue (calibration, ship, coop, any linear model) is a tuple of these:
    the checker, the lessons and the homework read the same entries.
    """

    code: str
    variant: str
    message: str
    changes: tuple[tuple, ...]
    hint: str = ""
    alone: bool = False

    @property
    def touches(self) -> frozenset:
        """The ingredients (and elements) it changes; mistakes that share one do not combine."""
        return frozenset(c[0] if len(c) == 2 else (c[0], c[1]) for c in self.changes)

    def __str__(self) -> str:
        return f"{self.code} ({self.variant})"


def combinations(mistakes: Sequence[Mistake], size: int) -> Iterator[tuple[Mistake, ...]]:
    """All ``size``-tuples of ``mistakes`` that touch disjoint ingredients (so they can co-occur)."""
    for combo in itertools.combinations(mistakes, size):
        if size > 1 and any(m.alone for m in combo):
            continue
        touched = [m.touches for m in combo]
        if all(a.isdisjoint(b) for a, b in itertools.combinations(touched, 2)):
            yield combo


def with_changes(ingredients, changes: tuple[tuple, ...]):
    """A copy of the dataclass ``ingredients`` with ``(field, value)`` or ``(field, (row, col),
    value)`` changes applied (see :class:`Mistake`)."""
    kw: dict[str, object] = {}
    for change in changes:
        if len(change) == 2:
            kw[change[0]] = change[1]
        else:
            name, idx, value = change
            arr = np.array(kw.get(name, getattr(ingredients, name)), dtype=float)
            arr[idx] = value
            kw[name] = arr
    return replace(ingredients, **kw)


class Catalogue(Protocol):
    """What the diagnosis of a linear filter needs from a system's catalogue of mistakes."""

    def covariance_mistakes(self) -> tuple[Mistake, ...]:
        """Mistakes that change P (and, through the gains, x̂)."""
        ...

    def mean_mistakes(self) -> tuple[Mistake, ...]:
        """Mistakes that change only x̂."""
        ...

    def build(self, mistakes: tuple[Mistake, ...] = ()) -> EpochFilter:
        """The epoch filter that makes ``mistakes`` (none: the optimal filter)."""
        ...


# ------------------------------------------------------------------------------ any linear model
def _matrix(name: str, value: object, rows: int | None = None, cols: int | None = None
            ) -> np.ndarray:
    arr = np.atleast_2d(_v.finite_array(name, value))
    if arr.ndim != 2 or (rows is not None and arr.shape[0] != rows) or \
            (cols is not None and arr.shape[1] != cols):
        want = f"({'n' if rows is None else rows}, {'m' if cols is None else cols})"
        raise ValueError(f"{name} must be a matrix of shape {want}, got {arr.shape}")
    return arr


@dataclass(frozen=True, eq=False)
class LinearModel:
    """A linear-Gaussian system and its measurement schedule, in course notation.

    x_{j+1} = Φ x_j + Γ w_j, w_j ~ N(0, W) at every propagation step j (of ``dt`` s);
    z_i = H x_{i·every} + v_i, v_i ~ N(0, V) at the epochs i = 0 .. n_epochs − 1;
    x_0 ~ N(x0, M0).  ``states`` and ``measurements`` name the components (for messages).
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    W: np.ndarray
    H: np.ndarray
    V: np.ndarray
    M0: np.ndarray
    x0: np.ndarray
    every: int
    n_epochs: int
    dt: float = 1.0
    states: tuple[str, ...] = ()
    measurements: tuple[str, ...] = ()
    rtol: float = field(default=1e-10, repr=False)

    def __post_init__(self) -> None:
        Phi = _matrix("Phi", self.Phi)
        n = Phi.shape[0]
        if Phi.shape != (n, n):
            raise ValueError(f"Phi must be square, got shape {Phi.shape}")
        Gamma = _matrix("Gamma", self.Gamma, rows=n)
        W = _v.spd_matrix("W", self.W, Gamma.shape[1])
        H = _matrix("H", self.H, cols=n)
        V = _v.spd_matrix("V", self.V, H.shape[0])
        M0 = _v.spd_matrix("M0", self.M0, n)
        x0 = _v.finite_array("x0", self.x0, (n,))
        every = _v.integer("every", self.every, minimum=1)
        n_epochs = _v.integer("n_epochs", self.n_epochs, minimum=2)
        dt = _v.positive_float("dt", self.dt)
        states = tuple(self.states) or tuple(f"x{i + 1}" for i in range(n))
        meas = tuple(self.measurements) or tuple(f"z{i + 1}" for i in range(H.shape[0]))
        if len(states) != n or len(meas) != H.shape[0]:
            raise ValueError(f"states must name the {n} states and measurements the "
                             f"{H.shape[0]} measurements, got {states} and {meas}")
        for name, value in (("Phi", Phi), ("Gamma", Gamma), ("W", W), ("H", H), ("V", V),
                            ("M0", M0), ("x0", x0), ("every", every), ("n_epochs", n_epochs),
                            ("dt", dt), ("states", states), ("measurements", meas)):
            if isinstance(value, np.ndarray):  # the model's own read-only copy: a filter that
                value = np.array(value)        # updates in place (filterpy's square root did,
                value.setflags(write=False)    # on x0) raises instead of changing the problem
            object.__setattr__(self, name, value)

    @property
    def n(self) -> int:
        return int(self.Phi.shape[0])

    @property
    def dim_x(self) -> int:
        return self.n

    @property
    def dim_z(self) -> int:
        return int(self.H.shape[0])

    @property
    def Q(self) -> np.ndarray:
        """The process noise of one step, Q = Γ W Γᵀ (filterpy's ``Q``)."""
        return self.Gamma @ self.W @ self.Gamma.T

    def schedule(self) -> Schedule:
        """Every component at every ``every``-th step 0, every, ..., n_steps: what the
        multirate driver (:func:`gpsaccel.kalman.multirate.run_multirate`), the filter forms
        (:mod:`gpsaccel.kalman.forms`) and the exact filter (:mod:`gpsaccel.kalman.exact`) run."""
        return Schedule.from_periods(self.n_steps, [self.every] * self.dim_z)

    def kalman_filter(self) -> KalmanFilter:
        """A filterpy ``KalmanFilter`` for one step: F = Φ, Q = Γ W Γᵀ, H, R = V, x = x0, P = M0."""
        from gpsaccel.kalman.factory import kalman_filter  # filterpy: only when called

        return kalman_filter(self)

    @property
    def t(self) -> np.ndarray:
        """The epoch times, s (epoch i at step i·every)."""
        return np.arange(self.n_epochs) * self.every * self.dt

    @property
    def n_steps(self) -> int:
        """Propagation steps from the first epoch to the last."""
        return (self.n_epochs - 1) * self.every

    def simulate(self, rng: np.random.Generator, n_runs: int) -> tuple[np.ndarray, np.ndarray]:
        """``n_runs`` realizations: z (n_runs, n_epochs, p) and the true x (n_runs, n_epochs, n)
        at the epochs, drawn from ``rng`` (a ``numpy.random.Generator``)."""
        n_runs = _v.integer("n_runs", n_runs, minimum=1)
        n, m, p = self.n, self.Gamma.shape[1], self.H.shape[0]
        x = self.x0 + rng.standard_normal((n_runs, n)) @ np.linalg.cholesky(self.M0).T
        w = rng.standard_normal((self.n_steps, n_runs, m)) @ np.linalg.cholesky(self.W).T
        v = rng.standard_normal((n_runs, self.n_epochs, p)) @ np.linalg.cholesky(self.V).T
        xs = np.empty((n_runs, self.n_epochs, n))
        xs[:, 0] = x
        for j in range(self.n_steps):
            x = x @ self.Phi.T + w[j] @ self.Gamma.T          # x_{j+1} = Φ x_j + Γ w_j
            if (j + 1) % self.every == 0:
                xs[:, (j + 1) // self.every] = x
        return xs @ self.H.T + v, xs


@dataclass(frozen=True, eq=False)
class LinearIngredients:
    """What a student chooses writing a filter for a :class:`LinearModel`.

    Phi, Gamma, W : one-step Φ and the process noise Q = Γ W Γᵀ; steps : predictions between
    updates; H, V, M0, x0 : as in the model; mean_propagated : False is x̄_i = x̂_{i−1};
    output, skip_first, skip_last : see :class:`EpochFilter`.
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    W: np.ndarray
    steps: int
    H: np.ndarray
    V: np.ndarray
    M0: np.ndarray
    x0: np.ndarray
    n_epochs: int
    mean_propagated: bool = True
    output: str = "posterior"
    skip_first: bool | str = False
    skip_last: bool | str = False
    predict_first: bool = False
    update_P: bool = True
    update_every_step: bool = False

    @classmethod
    def correct(cls, model: LinearModel) -> LinearIngredients:
        return cls(model.Phi, model.Gamma, model.W, model.every, model.H, model.V, model.M0,
                   model.x0, model.n_epochs)

    def epoch_filter(self) -> EpochFilter:
        Q = self.Gamma @ self.W @ self.Gamma.T                 # Q = Γ W Γᵀ
        F, Qe = epoch_transition(self.Phi, Q, self.steps)
        A = F if self.mean_propagated else np.eye(F.shape[0])
        x0, M0 = self.x0, self.M0
        if self.predict_first:                                 # one propagation before z_0:
            x0, M0 = A @ x0, F @ M0 @ F.T + Qe                 # x̄_0 = A x0, M_0 = F M0 Fᵀ + Q_e
        fast = (self.Phi, Q, self.steps) if self.update_every_step else None
        return EpochFilter(A, F, Qe, self.H, self.V, x0, M0, self.n_epochs,
                           self.output, self.skip_first, self.skip_last, self.update_P, fast)


#: The generic catalogue's wording: code -> message template (fields named in each).
LINEAR_MESSAGES: dict[str, str] = {
    "phi-transposed": "Your filter propagates with Φᵀ instead of Φ (x̄ = Φ x̂, M = Φ P Φᵀ + Q): "
                      "a transition matrix written by rows where columns belong, or "
                      "x @ Phi with x a row where Phi @ x is meant.",
    "q-without-gamma": "Your process noise is {used} instead of Q = Γ W Γᵀ: the noise enters "
                       "the state through Γ, so W (a {m}×{m} covariance of the input noise) is "
                       "not the state's process noise.",
    "std-as-variance": "{elem} = {value:.4g} in your filter; it should be {right:.4g}: {label}. "
                       "A covariance holds variances σ² (here σ = {sigma:.4g}, σ² = {right:.4g}).",
    "m0-order": "M0 has {a} and {b} swapped: the state is [{states}], so M0's diagonal is "
                "[{right}]; your filter starts with [{used}].",
    "returns-a-priori": "Your filter returns the a priori estimate and covariance (x̄, M: "
                        "before the update) at each epoch; the contract asks for the a "
                        "posteriori ones (x̂, P: after the update with z at that epoch). Likely "
                        "cause: the values are stored before the update.",
    "first-update-skipped": "Your filter does not use the measurement at t = 0: its first "
                            "estimate is the prior (x̂₀ = x̄₀, P₀ = M0). Update with z₀ before "
                            "the first propagation.",
    "first-update-skipped.covariance": "Your P at t = 0 is the prior M0: the covariance update "
                                       "with z₀ is missing, though your x̂ at t = 0 used z₀; "
                                       "every later gain follows from that P.",
    "last-update-missing": "Your filter is right except at the last epoch (t = {t_last:g} s), "
                           "where x̂ and P are the a priori x̄ and M: the update with the last "
                           "measurement is missing (a loop such as range(n - 1)).",
    "covariance-update-skipped": "Your P at the last epoch (t = {t_last:g} s) is the a priori "
                                 "M: the covariance update with the last measurement is "
                                 "missing, though your x̂ there used it (the propagation is "
                                 "right: every earlier P matches).",
    "predict-before-first-update": "Your filter propagates before its first update: the "
                                   "{measurement} at t = 0 updates a prior already carried "
                                   "{every} {step}(s) ahead (x̄₀ = Φ^{every} x0, M₀ = Φ^{every} "
                                   "M0 Φ^{every}ᵀ + Q) instead of x0 and M0 themselves, and "
                                   "every later row inherits it. The prior holds at t = 0, "
                                   "where z₀ is taken: update first, then propagate (in a "
                                   "predict-then-update loop, skip the prediction at k = 0).",
    "missing-propagation": "Your filter propagates {steps} step(s) between updates; there are "
                           "{every} (propagation every {dt:g} s, a measurement every "
                           "{interval:g} s).",
    "mean-not-propagated": "Your covariance is propagated between measurements but your "
                           "estimate is not: the residual uses x̂ₖ₋₁ where it should use "
                           "x̄ₖ = Φ^{every} x̂ₖ₋₁.",
    "covariance-update-skipped.never": "Your P is never updated: at every epoch it is the a "
                                       "priori M, though your x̂ is updated with the gain "
                                       "K = M Hᵀ (H M Hᵀ + V)⁻¹. The update of P is missing: "
                                       "P = (I − K H) M (I − K H)ᵀ + K V Kᵀ after each update "
                                       "of x̂.",
    "update-every-step": "Your filter updates at every {step} ({every} per measurement "
                         "interval), reusing the last measurement between arrivals; a "
                         "measurement arrives every {interval:g} s, so only those {step}s "
                         "update (the others only propagate).",
    "phi-sign": "Your Φ has {entries} with the wrong sign; the propagation is otherwise right. "
                "Check how each state enters the others.",
    "state-order": "Your H is written for the state order [{order}]; the problem's state is "
                   "[{states}], and Φ, M0 and your outputs follow it. Write H's columns in the "
                   "problem's order.",
}

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
        out.append(Mistake("phi-sign", f"{variant} sign flipped", text("phi-sign",
                                                                       entries=entries),
                           (("Phi", flipped),)))
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
        for m in mistakes:
            g = with_changes(g, m.changes)
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
        W_state = (float(m.W[0, 0]) * np.eye(n) if k == 1 else m.W if k == n else None)
        if W_state is not None and not np.allclose(m.Gamma @ m.W @ m.Gamma.T, W_state):
            used = "W·I" if k == 1 else "W"
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
                ("last-update-missing", (("skip_last", True),), "no update at the last epoch"),
                ("covariance-update-skipped", (("skip_last", "covariance"),),
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
