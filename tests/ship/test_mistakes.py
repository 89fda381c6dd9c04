"""The ship mistake catalogue: without a mistake it is the optimal multirate filter."""

from __future__ import annotations

import itertools

import numpy as np

from gpsaccel.kalman.multirate import run_multirate
from gpsaccel.ship import mistakes
from gpsaccel.ship.model import ShipModel
from gpsaccel.ship.simulation import simulate_ensemble
from gpsaccel.ship.zeroed_gain import run_zeroed_gain

M = ShipModel(n_samples=300)
ENS = simulate_ensemble(M, 3, np.random.default_rng(1))
Z = mistakes.schedule_z(M, ENS.z)
SCHED = M.schedule(multirate=True)


def test_optimal_variant_is_run_multirate_and_zeroed_is_run_zeroed_gain():
    ref = mistakes.run(M, Z, ENS.u)
    for r in range(3):
        res = run_multirate(M, Z[r][SCHED.steps], schedule=SCHED, u=ENS.u)
        np.testing.assert_allclose(ref.x_hat[r, 1:], res.x_hat, rtol=0, atol=1e-9)
        np.testing.assert_allclose(ref.P[1:], res.P, rtol=0, atol=1e-12)
    for cov, report in (("joseph", False), ("report", True)):
        entry = {m.code: m for m in mistakes.catalogue()}
        v = mistakes.Variant((entry["zeroed-gain"],) + ((entry["report-covariance"],) if report
                                                        else ()))
        out = mistakes.run(M, Z, ENS.u, v)
        zg = run_zeroed_gain(M, Z[0][SCHED.steps], schedule=SCHED, covariance=cov, u=ENS.u)
        # with the report's non-symmetric M the gain depends on how it is written: here
        # M Hᵀ S⁻¹, in run_zeroed_gain (S⁻¹ H Mᵀ)ᵀ; they agree to rounding only for the Joseph form
        atol = 1e-9 if cov == "joseph" else 1e-2
        np.testing.assert_allclose(out.x_hat[0, 1:], zg.x_hat, rtol=0, atol=atol)
        np.testing.assert_allclose(out.P[1:], zg.P, rtol=0, atol=atol)
        np.testing.assert_allclose(out.P_true[1:], zg.P_actual, rtol=0, atol=atol)


def test_variants_are_distinct_and_the_zeroed_gain_costs_little():
    ref = mistakes.run(M, Z, ENS.u)
    sd = np.sqrt(np.diagonal(ref.P, axis1=-2, axis2=-1))
    vs = mistakes.variants()
    assert vs[0].codes == () and len(vs) == 12 + len(mistakes.shared_catalogue())
    outs, singular = [], []
    for v in vs[1:]:
        try:
            out = mistakes.run(M, Z, ENS.u, v)
        except np.linalg.LinAlgError:  # its S turns singular: a student's filter stops too
            singular.append(str(v))
            continue
        assert (np.abs(out.x_hat - ref.x_hat) / sd).max() > 1e-3, v
        excess = mistakes.sigma_excess(out.P_true, ref.P)
        # nothing beats the optimal gain (P_true is the error's covariance of a gain-only one)
        assert excess.min() > -1e-9 or not v.gain_only, v
        if v.codes == ("zeroed-gain",):
            assert 0 < excess.max() < 1e-3
        outs.append((str(v), out.x_hat, out.P))
    assert singular == ["joseph-sign ((I + K H) M (I + K H)ᵀ + K V Kᵀ)"]
    for (a, xa, Pa), (b, xb, Pb) in itertools.combinations(outs, 2):  # a match is unambiguous
        d = max((np.abs(xa - xb) / sd).max(),
                (np.abs(Pa - Pb) / (sd[:, :, None] * sd[:, None, :])).max())
        assert d > 1e-4, (a, b, d)


def test_each_shared_entry_runs_through_the_hook_with_the_true_covariance_of_its_gains():
    """A variant that changes only the gains (V's σ, Joseph's sign, V left out of S, ...) has the
    Joseph recursion of its gains for its true covariance: its estimates' errors over many voyages
    match it (NEES about n); one that changes the mean is flagged, its cost said otherwise."""
    entry = {m.variant: m for m in mistakes.shared_catalogue()}
    gain = mistakes.Variant((entry["every element of W: σ for σ² (0.5, 0.5, 0.05)"],))
    mean = mistakes.Variant((entry["x̄₀ = 0"],))
    assert gain.gain_only and not mean.gain_only
    ens = simulate_ensemble(M, 200, np.random.default_rng(3))
    out = mistakes.run(M, mistakes.schedule_z(M, ens.z), ens.u, gain)
    e = ens.x - out.x_hat
    nees = np.einsum("rki,kij,rkj->rk", e[:, 1:], np.linalg.inv(out.P_true[1:]), e[:, 1:])
    # 200 voyages: the mean NEES of 9 states has standard error √(2·9/200) = 0.3 at each step
    assert abs(nees.mean(axis=0)[-50:].mean() - 9) < 1.0
