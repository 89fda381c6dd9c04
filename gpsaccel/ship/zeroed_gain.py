r"""Report 004's multirate filter: compute the full gain, then zero the columns of missing sensors.

What the report does (its ``BD(:,1,n) = zeros; BD(:,4,n) = zeros``) at a step where some
components of z are not measured::

    K_full = M Hᵀ (H M Hᵀ + V)⁻¹                 the gain as if every component had arrived
    K      = K_full with the columns of the missing components set to 0
    x̂      = x̄ + K (z − H x̄)                    (missing components contribute nothing)

This is *not* the optimal update with the rows that did arrive.  The optimal one (the multirate
driver, :func:`gpsaccel.kalman.multirate.run_multirate`) uses only those rows r::

    K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹

The two differ because (H M Hᵀ + V)⁻¹ couples the components: the columns of K_full that are kept
were computed on the assumption that the missing measurements would also correct the estimate, so
they under-weight what did arrive.  Any gain K gives the a posteriori error covariance of the
Joseph form, valid for every K (not only the optimal one)::

    P = (I − K H) M (I − K H)ᵀ + K V Kᵀ

whereas the short form ``P = (I − K H) M`` that the report uses holds only for the optimal gain;
with a zeroed gain it is not even symmetric, and it claims less uncertainty than the filter has.

Two covariances (``covariance=``)
---------------------------------
``"joseph"``: the filter carries the Joseph covariance of the gain it applies, and computes the
    next gains from it: a self-consistent suboptimal filter; its P is its true error covariance.
``"report"``: the filter carries ``(I − K H) M`` and computes the next gains from it, exactly as
    the report's loop.  Its true error covariance is then propagated alongside with the Joseph
    form of the same gains (``P_actual``), so its claim can be checked.

The report also applies, at the steps where the GPS arrives, the gain of its *monorate* filter
(``BD(:,:,n) = B(:,:,n)``), not the gain of the filter being run; ``full_epoch_gains`` reproduces
that (pass the monorate run's gains).  The known input enters the prediction as in the driver:
x̄_{k+1} = Φ x̂_k + B u_k, M_{k+1} = Φ P_k Φᵀ + Q.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.multirate import LinearGaussianModel, MultirateResult, check_inputs, run_multirate
from gpsaccel.kalman.schedule import Schedule
from gpsaccel.kalman.update import epoch_transition, gain, joseph_update, partial_update

COVARIANCES = ("joseph", "report")


@dataclass(frozen=True, eq=False)
class ZeroedGainResult(MultirateResult):
    """A :class:`~gpsaccel.kalman.multirate.MultirateResult` plus what the zeroed gain needs.

    P : the covariance the filter carries and reports (Joseph or the report's (I − K H) M).
    P_actual : (n_epochs, n, n) the true a posteriori error covariance of the gains applied
        (Joseph form; equal to P when ``covariance="joseph"``).
    M_actual : the matching true a priori covariance.
    K_full : (n_epochs, n, p) the full gain before its columns were zeroed (of a hook with
        ``zeroed``, as every run of :func:`run_zeroed_gain`).
    covariance : ``"joseph"`` or ``"report"``.
    """

    P_actual: np.ndarray
    M_actual: np.ndarray
    K_full: np.ndarray
    covariance: str


class ZeroedGainUpdate:
    """The report's update as a hook of the multirate driver (:class:`UpdateHook`).

    At epoch i, with the filter at (x̄, C) (C = M for the Joseph variant, the report's carried
    covariance otherwise)::

        K_full = C Hᵀ (H C Hᵀ + V)⁻¹    (all p components, as if all had arrived)
        K      = K_full, columns of missing components zeroed  (or the given full-epoch gain)
        x̂      = x̄ + K r                 r = z − H x̄ on the components that arrived, 0 elsewhere
        C      ← Joseph(C, K)  or  (I − K H) C                  (``covariance``)

    and the true covariance of this filter's error is carried alongside,
    M_actual = Φ_n P_actual Φ_nᵀ + Q_n between epochs, P_actual = Joseph(M_actual, K), with the
    system's own Φ, Q, M0 (and ``V_true``, the V of each call unless given).

    The same hook is every other gain a filter of the ship may apply (the catalogue of
    :mod:`gpsaccel.ship.mistakes` runs through it): ``zeroed=False`` the optimal gain of the rows
    that arrived, ``V_gain`` the V of the gain's S (the filter's P is updated with V), ``form``
    the filter's covariance update (:func:`gpsaccel.kalman.update.covariance_update`, over
    ``covariance``'s); whatever the filter computes, P_actual is the covariance of its error as
    long as its mean is x̄ = Φ x̂ + B u with the system's Φ.  :meth:`update` is the update on
    arrays (x̄ one run (n,) or many (R, n) sharing C), :meth:`__call__` the driver's hook.
    """

    def __init__(self, Phi: np.ndarray, Q: np.ndarray, M0: np.ndarray, steps: np.ndarray,
                 covariance: str, full_epoch_gains: np.ndarray | None, *, zeroed: bool = True,
                 V_gain: np.ndarray | None = None, form: str | None = None,
                 V_true: np.ndarray | None = None) -> None:
        self.Phi, self.Q, self.steps = Phi, Q, steps
        self.covariance, self.full_epoch_gains = covariance, full_epoch_gains
        self.zeroed, self.V_gain, self.V_true = zeroed, V_gain, V_true
        self.form = form or ("short" if covariance == "report" else "joseph")
        n_epochs, n = len(steps), M0.shape[0]
        self.C_actual = M0.copy()
        self._transitions: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.M_actual = np.empty((n_epochs, n, n))
        self.P_actual = np.empty((n_epochs, n, n))
        self.K_full: list[np.ndarray] = []

    def _propagate_actual(self, i: int) -> None:
        """C_actual from the previous epoch (or step 0) to epoch i."""
        n_steps = int(self.steps[i] - (self.steps[i - 1] if i else 0))
        if n_steps not in self._transitions:
            self._transitions[n_steps] = epoch_transition(self.Phi, self.Q, n_steps)
        F, Qn = self._transitions[n_steps]
        self.C_actual = F @ self.C_actual @ F.T + Qn

    def __call__(self, kf, i: int, z: np.ndarray, rows: np.ndarray, H: np.ndarray,
                 V: np.ndarray) -> np.ndarray:
        x, kf.P, K = self.update(kf.x[:, 0], kf.P, i, z, rows, H, V)
        kf.x = x.reshape(-1, 1)
        return K

    def update(self, x: np.ndarray, C: np.ndarray, i: int, z: np.ndarray, rows: np.ndarray,
               H: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x̂, C, K) of epoch i from the a priori (x̄, C); the true covariance moves along."""
        self._propagate_actual(i)
        self.M_actual[i] = self.C_actual
        p = H.shape[0]
        if self.zeroed:                    # the gain before its columns are zeroed
            self.K_full.append(gain(C, H, V if self.V_gain is None else self.V_gain)[0])
        given = None
        if self.full_epoch_gains is not None and rows.size == p:
            given = self.full_epoch_gains[i].copy()
        x, C, K = partial_update(x, C, z, H, V, rows, given, zeroed=self.zeroed,
                                 V_gain=self.V_gain, form=self.form)
        self.C_actual = joseph_update(self.C_actual, K, H, V if self.V_true is None
                                      else self.V_true)
        self.P_actual[i] = self.C_actual
        return x, C, K


def run_zeroed_gain(model: LinearGaussianModel, z: np.ndarray, schedule: Schedule | None = None,
                    covariance: str = "joseph", u: np.ndarray | None = None,
                    full_epoch_gains: np.ndarray | None = None) -> ZeroedGainResult:
    """Filter ``z`` (n_epochs, p) on ``schedule`` with the report's zeroed-column gain.

    Same inputs as :func:`~gpsaccel.kalman.multirate.run_multirate` (a NaN or a component the
    schedule does not deliver is missing; its gain column is zeroed), run by that driver with
    :class:`ZeroedGainUpdate` as its update.  ``full_epoch_gains`` (n_epochs, n, p), if given, is
    applied instead of the filter's own gain at every epoch where all p components arrive (the
    report's reuse of its monorate gain).
    """
    covariance = _v.choice("covariance", covariance, COVARIANCES)
    inputs = check_inputs(model, z, schedule, u)
    schedule = inputs.schedule
    p, n = inputs.H.shape
    if full_epoch_gains is not None:
        full_epoch_gains = _v.finite_array("full_epoch_gains", full_epoch_gains,
                                           (schedule.n_epochs, n, p))
    hook = ZeroedGainUpdate(np.asarray(model.Phi, dtype=float), np.asarray(model.Q, dtype=float),
                            np.asarray(model.M0, dtype=float), schedule.steps, covariance,
                            full_epoch_gains)
    # the report's short form is unsymmetrised on purpose: no numerical-guard warning for it
    res = run_multirate(model, inputs.z, "filterpy", schedule, inputs.u, update=hook,
                        check=covariance == "joseph")
    base = {f.name: getattr(res, f.name) for f in fields(MultirateResult)}
    base["method"] = f"zeroed-gain ({covariance})"
    return ZeroedGainResult(**base, P_actual=hook.P_actual, M_actual=hook.M_actual,
                            K_full=np.stack(hook.K_full), covariance=covariance)
