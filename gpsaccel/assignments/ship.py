r"""The ship homework's checks: the multirate update with the rows that arrived; the zeroed gain.

Report 004's ship (:mod:`gpsaccel.ship.model`): 9 states, every one measured (H = I), the GPS rows
(x, y positions) at 1 Hz, the IMU rows at 10 Hz.  At a step where only some rows r arrived, the
optimal update uses those rows only::

    K_r = M H_rᵀ (H_r M H_rᵀ + V_r)⁻¹,   x̂ = x̄ + K_r (z_r − H_r x̄),
    P = (I − K_r H_r) M (I − K_r H_r)ᵀ + K_r V_r K_rᵀ

The report instead computes the full gain and zeroes the columns of the missing rows
(:mod:`gpsaccel.ship.zeroed_gain`).  Question 1 checks the student's ``update(x_bar, M, z, H, V)``
(NaN in z = not arrived) on cases built from the ship's own covariances; question 2 asks what the
zeroed gain costs, computed with the package's two filters.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from gpsaccel import registry
from gpsaccel.assignments._answers import array, assert_report, call
from gpsaccel.check.findings import mistake_finding
from gpsaccel.check.report import Report
from gpsaccel.ship.mistakes import MESSAGES as SHIP_MESSAGES
from gpsaccel.ship.model import GPS_ROWS, ShipModel

__all__ = ["assert_report", "cost_answer", "optimal_update", "update_answer", "update_mistakes",
           "zeroed_update"]

#: The homework's wording: the ``homework.*`` entries of the ship's one table
#: (:data:`gpsaccel.ship.mistakes.MESSAGES`), code (or code.part) -> template.
TEXT = {k.removeprefix("homework."): v for k, v in SHIP_MESSAGES.items()
        if k.startswith("homework.")}

#: Distance (units of the reference σ) within which x̂ and P count as equal.
TOL = 1e-6

#: Relative tolerance of the numeric answers of question 2.  The three σ of a voyage (optimal,
#: zeroed gain's claim, its actual) differ in the 4th significant digit (0.41448, 0.41427, 0.41455
#: m for the report's ship), so the question asks for 6 digits: rounded to 6, a value is within
#: 1.3e-5 of the exact one (leading digit 4 of 10).
RTOL = 2e-5


def optimal_update(x_bar, M, z, H, V):
    """The update with the rows of z that are finite (module docstring); (x̂, P).  The ship's
    one update (:func:`gpsaccel.ship.mistakes.update`)."""
    from gpsaccel.ship.mistakes import update

    return update(x_bar, M, z, H, V)


def zeroed_update(x_bar, M, z, H, V, short_form: bool = False):
    """Report 004's update: full gain, columns of the missing rows zeroed; (x̂, P)."""
    from gpsaccel.ship.mistakes import update

    codes = ("zeroed-gain", "report-covariance") if short_form else ("zeroed-gain",)
    return update(x_bar, M, z, H, V, tuple(m for m in update_mistakes() if m.code == codes[-1]))


def update_mistakes() -> tuple:
    """The mistakes question 1 names: the ship's :func:`gpsaccel.ship.mistakes.update_catalogue`."""
    from gpsaccel.ship.mistakes import update_catalogue

    return update_catalogue()


@lru_cache(maxsize=1)
def _ship_covariances() -> tuple[np.ndarray, np.ndarray]:
    """A priori covariances M of the ship's multirate filter at an IMU-only and a GPS epoch."""
    from gpsaccel.kalman.multirate import run_multirate
    from gpsaccel.ship.simulation import simulate_ship

    model = ShipModel()
    voyage = simulate_ship(model, np.random.default_rng(0))
    sched = model.schedule()
    res = run_multirate(model, voyage.measurements(sched), schedule=sched, u=voyage.u)
    gps = np.flatnonzero(res.used[:, GPS_ROWS[0]])
    imu_only = np.flatnonzero(~res.used[:, GPS_ROWS[0]] & res.used[:, 1])
    return res.M[imu_only[5]].copy(), res.M[gps[3]].copy()


#: One update's inputs: x_bar, M, z, H, V.
UpdateInputs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def cases(seed: int = 0) -> list[tuple[str, UpdateInputs]]:
    """(label, (x_bar, M, z, H, V)) test cases: IMU-only, all rows, one GPS row, none arrived."""
    model = ShipModel()
    H, V = model.H, model.V
    rng = np.random.default_rng(seed)
    M_imu, M_gps = _ship_covariances()
    L = rng.standard_normal((9, 9))
    M_rand = L @ L.T / 9 + np.diag(rng.uniform(0.1, 1.0, 9))
    out: list[tuple[str, UpdateInputs]] = []
    for label, M, missing in (("IMU rows only (GPS missing)", M_imu, list(GPS_ROWS)),
                              ("every row arrived", M_gps, []),
                              ("x position only missing, random M", M_rand, [GPS_ROWS[0]]),
                              ("nothing arrived", M_rand, list(range(9)))):
        x_bar = rng.standard_normal(9)
        z = H @ x_bar + rng.standard_normal(9) * np.sqrt(np.diag(V)) * 2
        z[missing] = np.nan
        out.append((label, (x_bar, M.copy(), z, H.copy(), V.copy())))
    return out


def _matches(x, P, x_ref, P_ref) -> tuple[bool, float, float]:
    sd = np.sqrt(np.diag(P_ref))
    dx = float(np.max(np.abs(x - x_ref) / sd))
    dP = float(np.max(np.abs(P - P_ref) / np.outer(sd, sd)))
    return dx <= TOL and dP <= TOL, dx, dP


def update_answer(update: object, seed: int = 0) -> Report:
    """Check ``update(x_bar, M, z, H, V) -> (x_hat, P)`` on :func:`cases`; never raises.

    Its two outputs are two parts (``x_hat``, ``P``: partial credit): a case where only one of
    them departs from the optimal update is a finding of that part, and the other is still
    checked on the cases after it; a recognised mistake of the update (:func:`update_mistakes`,
    which changes both), a departure of both, or an update that cannot be called or returns the
    wrong shapes concerns the whole question.  The student reads the mistake's code and what
    their update does, never the optimal update's formulas."""
    from gpsaccel.ship.mistakes import update as ship_update

    report = Report("question 1: the multirate update")
    failed: set[str] = set()
    for label, args in cases(seed):
        out = call(report, "update(x_bar, M, z, H, V)", update, *(a.copy() for a in args))
        if out is None:
            break
        if not isinstance(out, (tuple, list)) or len(out) != 2:
            report.add("return-value", text=TEXT["return-value"], where="update",
                       observed={"type": type(out).__name__})
            break
        x = array(report, "x_hat", out[0], (9,))
        P = array(report, "P", out[1], (9, 9))
        if x is None or P is None:
            break
        x_ref, P_ref = optimal_update(*args)
        ok, dx, dP = _matches(x, P, x_ref, P_ref)
        if ok:
            continue
        mistake = next((m for m in update_mistakes()
                        if _matches(x, P, *ship_update(*args, mistakes=(m,)))[0]), None)
        if mistake is not None:
            mistake_finding(report, mistake, where=label)
            break
        part = "x_hat" if dP <= TOL else "P" if dx <= TOL else ""
        if part in failed:
            continue  # that part is already lost; the other is still checked
        failed.add(part)
        report.add("update-mismatch", TEXT["update-mismatch.formulas"], text=TEXT[
            "update-mismatch"], where=label, part=part, observed={
                "dx": dx, "dP": dP, "what": TEXT[f"update-mismatch.{part or 'both'}"],
                "none": TEXT["update-mismatch.none"] if label == "nothing arrived" else ""})
        if not part or failed == {"x_hat", "P"}:
            break
    if report.passed:
        report.add("ok", severity="note", text=TEXT["ok.update"],
                   observed={"n": len(cases(seed))})
    report.sort()
    return report


@lru_cache(maxsize=4)
def zeroed_gain_cost(mass_kg: float = 12.0, gps_rate_hz: float = 1.0) -> dict[str, float]:
    """Question 2's answers for the ship of ``mass_kg`` with the GPS at ``gps_rate_hz``: σ of x at
    the end of the voyage (seed 0; the covariances do not depend on the measurements) for the
    optimal multirate filter, the report's zeroed-gain filter's claim ((I − K H) M) and its
    actual error (Joseph)."""
    from gpsaccel.kalman.multirate import run_multirate
    from gpsaccel.ship.simulation import simulate_ship
    from gpsaccel.ship.zeroed_gain import run_zeroed_gain

    model = ShipModel(mass=float(mass_kg), gps_rate_hz=float(gps_rate_hz))
    voyage = simulate_ship(model, np.random.default_rng(0))
    sched = model.schedule()
    z = voyage.measurements(sched)
    opt = run_multirate(model, z, schedule=sched, u=voyage.u)
    rep = run_zeroed_gain(model, z, schedule=sched, covariance="report", u=voyage.u)
    return {"sigma_optimal": math.sqrt(opt.P[-1][0, 0]),
            "sigma_claimed": math.sqrt(rep.P[-1][0, 0]),
            "sigma_actual": math.sqrt(rep.P_actual[-1][0, 0])}


def cost_answer(sigma_optimal: object, sigma_zeroed: object, mass_kg: float = 12.0,
                gps_rate_hz: float = 1.0) -> Report:
    """Check question 2 for the student's ship (``mass_kg``, ``gps_rate_hz``): σ_x at t = 100 s
    of the optimal filter and the zeroed gain's *actual* one.  The messages name the mistake,
    never the right value."""
    report = Report("question 2: what the zeroed gain costs")
    want = zeroed_gain_cost(float(mass_kg), float(gps_rate_hz))
    for name, value, key in (("sigma_optimal", sigma_optimal, "sigma_optimal"),
                             ("sigma_zeroed", sigma_zeroed, "sigma_actual")):
        try:
            if value is None:  # np.asarray(None, dtype=float) is nan: "= nan" for no answer
                raise TypeError
            v = float(np.asarray(value, dtype=float).reshape(()))
        except (TypeError, ValueError):
            report.add("not-a-number", text=TEXT["not-a-number"], where=name,
                       observed={"value": str(value)[:60]}, part=name)
            continue
        if not math.isfinite(v):
            report.add("not-a-number", text=TEXT["not-a-number.finite"], where=name,
                       observed={"value": v}, part=name)
            continue
        right = want[key]
        if math.isclose(v, right, rel_tol=RTOL):
            continue
        if math.isclose(v, right**2, rel_tol=RTOL):
            report.add("std-as-variance", text=TEXT["std-as-variance"], where=name, part=name,
                       observed={"value": v}, expected={name: right})
        elif key == "sigma_actual" and math.isclose(v, want["sigma_claimed"], rel_tol=RTOL):
            report.add("claimed-not-actual", text=TEXT["claimed-not-actual"], where=name,
                       part=name, observed={"value": v}, expected={name: right})
        elif key == "sigma_actual" and math.isclose(v, want["sigma_optimal"], rel_tol=RTOL):
            report.add("sigma-value", text=TEXT["sigma-value.optimal"], where=name, part=name,
                       observed={"value": v}, expected={name: right})
        elif key == "sigma_optimal" and math.isclose(v, want["sigma_actual"], rel_tol=RTOL):
            report.add("sigma-value", text=TEXT["sigma-value.zeroed"], where=name, part=name,
                       observed={"value": v}, expected={name: right})
        else:
            report.add("sigma-value", text=TEXT["sigma-value"], where=name, part=name,
                       observed={"value": v, "rtol": RTOL}, expected={name: right})
    if report.passed:
        report.add("ok", severity="note", text=TEXT["ok.cost"])
    report.sort()
    return report


# the homework, for `gpsaccel assignment` / `gpsaccel grade` (its master: assignments/ship/)
registry.add_assignment(
    "ship", __name__, system="ship", problem="ship",
    title="The ship: the multirate update and what the zeroed gain costs (report 004)")
