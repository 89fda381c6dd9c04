r"""Monorate, optimal multirate and the report's zeroed-gain multirate on the ship: a Monte Carlo.

The filters compared (:data:`FILTERS`), all on the same ``n_runs`` simulated voyages of
:class:`~gpsaccel.ship.model.ShipModel`:

``monorate``        every sensor at every step, the optimal filter (the multirate driver with
                    the all-every-step schedule).
``multirate``       GPS at 1 Hz, IMU at 10 Hz; the optimal update with the rows that arrived
                    (the multirate driver).
``zeroed-joseph``   the report's update (full gain, GPS columns zeroed between fixes) with the
                    Joseph covariance of the gain it applies, from which its next gains follow.
``zeroed-report``   the same update with the report's covariance (I − K H) M, which also feeds
                    its next gains.
``report-as-written``  as ``zeroed-report`` and, at GPS steps, the monorate filter's gain, which
                    the report's loop applies (``BD(:,:,n) = B(:,:,n)``).

How it runs.  The gains of a linear filter do not depend on the data, so each filter runs once
on run 0 (through :func:`~gpsaccel.kalman.multirate.run_multirate` or
:func:`~gpsaccel.ship.zeroed_gain.run_zeroed_gain`) and the whole ensemble is then moved by
:func:`~gpsaccel.kalman.gain_sequence.apply_gains` as arrays, far cheaper than a filter run per
realization (benchmarks/ship_ensemble.py measures the two side by side).

Statistics, over runs r = 1..R and epochs k = 1..N−1 (every step carries some measurement)::

    RMSE_j   = √( mean_{r,k} e_{r,k,j}² )                  per state j, e = x − x̂
    ε̄_k      = mean_r e_{r,k}ᵀ P_k⁻¹ e_{r,k}                 NEES with the covariance the filter
                                                             carries (P_k is the same in every run)
    [r1, r2] = chi2_bounds(9, R, 0.05)                       95 % two-sided bounds of ε̄_k

For the zeroed-gain filters NEES is also computed against their true covariance (Joseph form of
the gains applied, ``P_actual``).  The report's (I − K H) M is not symmetric; its NEES is
eᵀ P⁻¹ e with that matrix as it is, solved, never symmetrised.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.kalman.consistency import chi2_bounds, fraction_inside
from gpsaccel.kalman.gain_sequence import apply_gains
from gpsaccel.kalman.multirate import MultirateResult, run_multirate
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.simulation import ShipEnsemble, simulate_ensemble
from gpsaccel.ship.zeroed_gain import run_zeroed_gain

FILTERS = ("monorate", "multirate", "zeroed-joseph", "zeroed-report", "report-as-written")

#: One line on each filter for tables and legends.
DESCRIPTIONS = {
    "monorate": "monorate (all sensors every step)",
    "multirate": "multirate, optimal (rows that arrived)",
    "zeroed-joseph": "zeroed gain, Joseph covariance",
    "zeroed-report": "zeroed gain, report's (I−KH)M",
    "report-as-written": "report as written (+ monorate gain at GPS)",
}


def quadratic_form(e: np.ndarray, P: np.ndarray) -> np.ndarray:
    """eᵀ P⁻¹ e for errors e (R, n_epochs, n) and one P (n_epochs, n, n) per epoch → (R, n_epochs).

    Solved with P as given (LU), so it also serves a non-symmetric P; for a symmetric positive
    definite P it equals :func:`gpsaccel.kalman.consistency.nees`.
    """
    e_t = np.transpose(e, (1, 2, 0))  # (n_epochs, n, R)
    return np.einsum("kir,kir->rk", e_t, np.linalg.solve(P, e_t))


@dataclass(frozen=True, eq=False)
class FilterStatistics:
    """One filter's Monte Carlo statistics (see the module docstring).

    rmse : (dim_x,) per state, units of the state.
    nees : (n_epochs,) ε̄_k with the filter's own covariance.
    nees_actual : the same with its true (Joseph) covariance; None for the optimal filters.
    result : the single filter run on run 0 (gains, covariances; a MultirateResult or a
        ZeroedGainResult).
    x_hat : (R, n_epochs, dim_x) every run's a posteriori estimate.
    """

    name: str
    rmse: np.ndarray
    nees: np.ndarray
    nees_actual: np.ndarray | None
    result: MultirateResult
    x_hat: np.ndarray

    @property
    def description(self) -> str:
        return DESCRIPTIONS.get(self.name, self.name)


@dataclass(frozen=True, eq=False)
class ShipComparison:
    """The comparison of :func:`compare_ship_filters`; ``str()`` prints the RMSE and NEES tables."""

    model: ShipModel
    ensemble: ShipEnsemble
    seed: int
    bounds: tuple[float, float]
    filters: dict[str, FilterStatistics]

    @property
    def n_runs(self) -> int:
        n = self.ensemble.n_runs
        assert n is not None  # a comparison's ensemble always has the runs axis
        return n

    @property
    def t_epochs(self) -> np.ndarray:
        return self.filters["multirate"].result.t_meas

    def inside(self, name: str, actual: bool = False) -> float:
        """Fraction of epochs whose ε̄_k is inside the 95 % bounds."""
        s = self.filters[name]
        nees = s.nees_actual if actual else s.nees
        if nees is None:
            raise ValueError(f"actual: filter {name!r} has no actual NEES (its P is the truth's)")
        return fraction_inside(nees, self.bounds)

    def covariance_excess(self, name: str, reference: str = "multirate") -> np.ndarray:
        """(n_epochs,) smallest eigenvalue of P_actual(name) − P(reference), in units of the
        reference's largest eigenvalue at that epoch (≥ 0 up to rounding when the reference is
        optimal: no gain sequence beats the optimal one)."""
        res = self.filters[name].result
        P = getattr(res, "P_actual", res.P)
        P_ref = self.filters[reference].result.P
        D = P - P_ref
        D = (D + np.swapaxes(D, 1, 2)) / 2
        return np.linalg.eigvalsh(D)[:, 0] / np.linalg.eigvalsh(P_ref)[:, -1]

    def sigma_excess(self, name: str, reference: str = "multirate") -> np.ndarray:
        """(n_epochs, dim_x) √diag P_actual(name) / √diag P(reference) − 1: the exact loss in
        standard deviation of each state against the reference, no Monte Carlo noise."""
        res = self.filters[name].result
        P = getattr(res, "P_actual", res.P)
        P_ref = self.filters[reference].result.P
        return np.sqrt(np.diagonal(P, axis1=1, axis2=2) / np.diagonal(P_ref, axis1=1, axis2=2)) - 1

    def __str__(self) -> str:
        names = list(self.filters)
        width = max(len(DESCRIPTIONS.get(n, n)) for n in names) + 2
        states = self.model.state_names
        head = f"{'filter':<{width}}" + "".join(f"{s:>9}" for s, _ in states)
        units = f"{'RMSE, unit':<{width}}" + "".join(f"{u:>9}" for _, u in states)
        lines = [f"ship (report 004): {self.n_runs} Monte Carlo runs, seed {self.seed}, "
                 f"{self.t_epochs.size} epochs (k = 1..{self.model.n_steps})",
                 "", head, units, "-" * len(head)]
        for n in names:
            s = self.filters[n]
            lines.append(f"{s.description:<{width}}" + "".join(f"{v:9.4f}" for v in s.rmse))
        r1, r2 = self.bounds
        lines += ["", f"NEES averaged over runs, 95 % bounds [{r1:.3f}, {r2:.3f}] for "
                      f"{self.n_runs} runs x 9 states",
                  f"{'filter':<{width}} {'mean NEES':>10} {'inside':>8}   {'true-P NEES':>11} "
                  f"{'inside':>8}"]
        lines.append("-" * len(lines[-1]))
        for n in names:
            s = self.filters[n]
            row = f"{s.description:<{width}} {s.nees.mean():10.3f} {self.inside(n):8.1%}"
            if s.nees_actual is not None:
                row += f"   {s.nees_actual.mean():11.3f} {self.inside(n, actual=True):8.1%}"
            lines.append(row)
        others = [n for n in names if n not in ("monorate", "multirate")]
        if "multirate" in names and others:
            lines += ["", "exact cost against the optimal multirate filter (true covariances, "
                          "no sampling noise): σ_true/σ_opt − 1",
                      f"{'filter':<{width}} {'x: mean':>10} {'x: max':>10} {'y: mean':>10} "
                      f"{'y: max':>10}"]
            lines.append("-" * len(lines[-1]))
            for n in others:
                ex = self.sigma_excess(n)
                lines.append(f"{DESCRIPTIONS.get(n, n):<{width}} {ex[:, 0].mean():10.2e} "
                             f"{ex[:, 0].max():10.2e} {ex[:, 3].mean():10.2e} {ex[:, 3].max():10.2e}")
        return "\n".join(lines)


def run_filter(name: str, model: ShipModel, z_mono: np.ndarray, z_multi: np.ndarray,
               u: np.ndarray, monorate: MultirateResult | None = None) -> MultirateResult:
    """One run of filter ``name`` (:data:`FILTERS`) on measurements of the matching schedule.

    ``z_mono`` / ``z_multi``: (n_epochs, 9) on the monorate / multirate schedules.
    ``report-as-written`` needs the ``monorate`` result (its gains are reused at GPS steps).
    """
    name = _v.choice("name", name, FILTERS)
    mono, multi = model.schedule(multirate=False), model.schedule(multirate=True)
    if name == "monorate":
        return run_multirate(model, z_mono, schedule=mono, u=u)
    if name == "multirate":
        return run_multirate(model, z_multi, schedule=multi, u=u)
    if name == "zeroed-joseph":
        return run_zeroed_gain(model, z_multi, schedule=multi, covariance="joseph", u=u)
    if name == "zeroed-report":
        return run_zeroed_gain(model, z_multi, schedule=multi, covariance="report", u=u)
    if monorate is None:
        monorate = run_multirate(model, z_mono, schedule=mono, u=u)
    if not np.array_equal(mono.steps, multi.steps):
        raise ValueError("report-as-written needs the same epochs on both schedules")
    return run_zeroed_gain(model, z_multi, schedule=multi, covariance="report", u=u,
                           full_epoch_gains=monorate.K)


def compare_ship_filters(model: ShipModel | None = None, n_runs: int = 200, seed: int = 0,
                         filters: tuple[str, ...] = FILTERS) -> ShipComparison:
    """Simulate ``n_runs`` voyages (``numpy.random.default_rng(seed)``) and filter them all.

    ``model`` is the 9-state ship (report 004's numbers when None); its GPS/IMU rates make the
    multirate schedule.  Returns RMSE per state and NEES over time for every filter.
    """
    model = ShipModel() if model is None else model
    if not isinstance(model, ShipModel) or model.wind:
        raise ValueError("model must be a 9-state ShipModel (wind=False)")
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    seed = _v.integer("seed", seed, minimum=0)
    for f in filters:
        _v.choice("filters", f, FILTERS)
    ens = simulate_ensemble(model, n_runs, np.random.default_rng(seed))
    schedules = {False: model.schedule(multirate=False), True: model.schedule(multirate=True)}
    z = {k: ens.measurements(s) for k, s in schedules.items()}
    stats: dict[str, FilterStatistics] = {}
    mono_result = None
    for name in filters:
        multirate = name != "monorate"
        res = run_filter(name, model, z[False][0], z[True][0], ens.u, monorate=mono_result)
        if name == "monorate":
            mono_result = res
        sched = schedules[multirate]
        est = apply_gains(model.Phi, model.H, model.x0, sched, res.K, z[multirate],
                          B=model.B, u=ens.u)
        e = ens.x[:, sched.steps] - est.x_hat
        rmse = np.sqrt(np.mean(e**2, axis=(0, 1)))
        nees = quadratic_form(e, res.P).mean(axis=0)
        actual = getattr(res, "P_actual", None)
        nees_actual = None if actual is None else quadratic_form(e, actual).mean(axis=0)
        stats[name] = FilterStatistics(name, rmse, nees, nees_actual, res, est.x_hat)
    return ShipComparison(model, ens, seed, chi2_bounds(9, n_runs, 0.05), stats)


# --------------------------------------------------------------------------- the wind bias
@dataclass(frozen=True, eq=False)
class WindComparison:
    """A steady wind on the ship, filtered with and without the two wind states.

    t : (n_epochs,) epoch times (s) of the multirate schedule.
    wind : (R, n_epochs, 2) the true wind force (N).
    wind_hat, wind_sigma : (R, n_epochs, 2), (n_epochs, 2) the 11-state filter's estimate and σ.
    track_error_plain, track_error_wind : (R, n_epochs) ‖(x, y) − (x̂, ŷ)‖ (m) of the 9-state and
        the 11-state filter.
    nees_wind : (n_epochs,) run-averaged NEES of the 11-state filter (11 states).
    bounds : 95 % bounds for it.
    """

    wind_force: np.ndarray
    t: np.ndarray
    wind: np.ndarray
    wind_hat: np.ndarray
    wind_sigma: np.ndarray
    track_error_plain: np.ndarray
    track_error_wind: np.ndarray
    mean_error_plain: np.ndarray
    mean_error_wind: np.ndarray
    nees_wind: np.ndarray
    bounds: tuple[float, float]

    @property
    def track_rmse(self) -> tuple[float, float]:
        """(9-state, 11-state) RMS track error over runs and epochs (m)."""
        return (float(np.sqrt(np.mean(self.track_error_plain**2))),
                float(np.sqrt(np.mean(self.track_error_wind**2))))

    def __str__(self) -> str:
        plain, wind = self.track_rmse
        r1, r2 = self.bounds
        fx, fy = self.wind_force
        return "\n".join([
            f"steady wind ({fx:g}, {fy:g}) N, {self.wind.shape[0]} runs, multirate schedule",
            f"track RMSE, 9-state filter (no wind state):  {plain:.3f} m",
            f"track RMSE, 11-state filter (wind states):   {wind:.3f} m",
            f"mean error (x, y) over the last 50 s, 9-state: "
            f"({self.mean_error_plain[0]:+.3f}, {self.mean_error_plain[1]:+.3f}) m",
            f"mean error (x, y) over the last 50 s, 11-state: "
            f"({self.mean_error_wind[0]:+.3f}, {self.mean_error_wind[1]:+.3f}) m",
            f"wind estimate at t = {self.t[-1]:g} s: mean ({self.wind_hat[:, -1, 0].mean():.3f}, "
            f"{self.wind_hat[:, -1, 1].mean():.3f}) N, σ ({self.wind_sigma[-1, 0]:.3f}, "
            f"{self.wind_sigma[-1, 1]:.3f}) N",
            f"11-state NEES: mean {self.nees_wind.mean():.3f}, "
            f"{fraction_inside(self.nees_wind, self.bounds):.1%} of epochs in [{r1:.2f}, {r2:.2f}]",
        ])


def compare_wind(model: ShipModel | None = None, n_runs: int = 200, seed: int = 0,
                 wind_force: tuple[float, float] = (0.8, -0.5)) -> WindComparison:
    """A wind of ``wind_force`` (N), drifting with the wind model's ``wind_drift``, on every run;
    the 9-state multirate filter (unaware) and the 11-state one (wind states) on the same data.

    ``model``: the 11-state ship (``ShipModel(wind=True)`` when None).
    """
    model = ShipModel(wind=True) if model is None else model
    if not isinstance(model, ShipModel) or not model.wind:
        raise ValueError("model must be a ShipModel with wind=True")
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    force = _v.finite_array("wind_force", wind_force, (2,))
    plain = model.replace(wind=False)
    ens = simulate_ensemble(model, n_runs, np.random.default_rng(seed), wind_force=force)
    sched = model.schedule(multirate=True)
    z = ens.measurements(sched)
    steps = sched.steps
    out = {}
    for m in (plain, model):
        res = run_multirate(m, z[0], schedule=sched, u=ens.u)
        est = apply_gains(m.Phi, m.H, m.x0, sched, res.K, z, B=m.B, u=ens.u)
        out[m.wind] = (res, est.x_hat)
    truth_xy = ens.x[:, steps][:, :, [0, 3]]
    err = {w: truth_xy - x[:, :, [0, 3]] for w, (_, x) in out.items()}
    late = ens.t[steps] >= ens.t[steps][-1] - 50.0
    res_w, x_w = out[True]
    e_w = ens.x[:, steps] - x_w
    return WindComparison(
        force, ens.t[steps], ens.wind[:, steps], x_w[:, :, 9:],
        np.sqrt(np.diagonal(res_w.P, axis1=1, axis2=2)[:, 9:]),
        np.linalg.norm(err[False], axis=2), np.linalg.norm(err[True], axis=2),
        err[False][:, late].mean(axis=(0, 1)), err[True][:, late].mean(axis=(0, 1)),
        quadratic_form(e_w, res_w.P).mean(axis=0), chi2_bounds(11, n_runs, 0.05))
