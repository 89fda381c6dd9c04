r"""What the calibration reports got wrong, and what each mistake costs, computed exactly.

The reports (000, 001, 003) solve the same problem with slips in their numbers.  The package draws
their figures with the corrected model (:func:`gpsaccel.calibration.reports.report_model`) and
measures every slip here: a mistake is a *truth* (what the simulation draws) and a *filter* (what
the student's filter believes), and :func:`error_statistics` computes the exact mean and
covariance of the actual error x − x̂ of that filter on that truth, with no sampling at all.

Exact error statistics of a (possibly mismatched) linear filter
---------------------------------------------------------------
Between GPS epochs the truth moves as x_{i+1} = F x_i + u_i + d_i with F = Φ⁴⁰, u_i ~ N(0, Q_e),
Q_e = Σ_{j<40} Φʲ ΓWΓᵀ Φʲᵀ, and a deterministic d_i that is zero for the error-model truth and,
for the closed-form ("kinematic") truth, the Euler integration error of a(t) (the truth integrates
a(t) exactly, the accelerometer by Euler's rule, and the difference does not depend on p0, v0, b or
w).  The filter, written at the epochs (:class:`gpsaccel.calibration.mistakes.EpochFilter`), runs
x̄_i = A x̂_{i−1} and x̂_i = x̄_i + K_i (z_i − H x̄_i) with z_i = H x_i + η_i, η_i ~ N(0, V).  With
s = [x − E x; x̂ − E x̂] the pair is linear, so its covariance C propagates exactly::

    between epochs   C ← T C Tᵀ + diag(Q_e, 0),        T = diag(F, A)
    update           C ← U C Uᵀ + diag(0, K V Kᵀ),     U = [[I, 0], [K H, I − K H]]
    means            E x̄_i = A E x̂_{i−1},   E x̂_i = (I − K H) E x̄_i + K H E x_i

and the actual error e = x − x̂ has mean E x − E x̂ and covariance [I, −I] C [I, −I]ᵀ.  For the
optimal filter on the error-model truth this covariance equals the filter's own P (the tests check
it to 1e-9); a Monte Carlo ensemble converges to it (:func:`monte_carlo_errors`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel.calibration.mistakes import EpochFilter, mutant, reference
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.reports import report_model
from gpsaccel.calibration.simulation import simulate_many, truth_mean
from gpsaccel.kalman.update import epoch_transition


@dataclass(frozen=True, eq=False)
class ErrorStatistics:
    """Exact statistics of the actual error e = x − x̂ at the GPS times (see the module docstring).

    t : (n_gps,) GPS times (s).
    mean : (n_gps, 3) E[e] in [m, m/s, m/s²].
    cov : (n_gps, 3, 3) Cov[e].
    P : (n_gps, 3, 3) what the filter claims (its own P).
    """

    t: np.ndarray
    mean: np.ndarray
    cov: np.ndarray
    P: np.ndarray

    @property
    def rms(self) -> np.ndarray:
        """(n_gps, 3) root-mean-square actual error √(diag Cov + mean²)."""
        return np.sqrt(np.diagonal(self.cov, axis1=1, axis2=2) + self.mean**2)

    @property
    def claimed_sigma(self) -> np.ndarray:
        """(n_gps, 3) the filter's σ = √diag P."""
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2))

    @property
    def sigma(self) -> np.ndarray:
        """(n_gps, 3) actual standard deviation √diag Cov (about the mean)."""
        return np.sqrt(np.diagonal(self.cov, axis1=1, axis2=2))


def error_statistics(truth_model: CalibrationModel, filt: EpochFilter,
                     truth: str = "error-model") -> ErrorStatistics:
    """Exact mean and covariance of the actual error of ``filt`` on ``truth_model``'s truth."""
    if not isinstance(truth_model, CalibrationModel):
        raise ValueError(f"truth_model must be a CalibrationModel, got {type(truth_model).__name__}")
    if filt.n_gps != truth_model.n_gps:
        raise ValueError(f"filt has {filt.n_gps} epochs but truth_model {truth_model.n_gps} GPS times")
    K, M, P = filt.gains
    F, Qe = epoch_transition(truth_model.Phi, truth_model.Q, truth_model.gps_every)
    H, V, A = truth_model.H, truth_model.V, filt.A
    n, I = 3, np.eye(3)
    Z = np.zeros((n, n))
    m_x = truth_mean(truth_model, truth)
    C = np.zeros((2 * n, 2 * n))
    C[:n, :n] = truth_model.M0
    T = np.block([[F, Z], [Z, A]])
    noise_prop = np.block([[Qe, Z], [Z, Z]])
    D = np.hstack([I, -I])
    mean = np.empty((filt.n_gps, n))
    cov = np.empty((filt.n_gps, n, n))
    m_hat = np.asarray(filt.x0, dtype=float)
    for i in range(filt.n_gps):
        if i:
            C = T @ C @ T.T + noise_prop
            m_hat = A @ m_hat
        if filt.output == "prior":  # what the filter reports is x̄ (before the update)
            mean[i], cov[i] = m_x[i] - m_hat, D @ C @ D.T
        Ki = K[i]
        KH = Ki @ H
        U = np.block([[I, Z], [KH, I - KH]])
        C = U @ C @ U.T
        C[n:, n:] += Ki @ V @ Ki.T
        C = (C + C.T) / 2
        m_hat = m_hat + KH @ (m_x[i] - m_hat)
        if filt.output != "prior":
            mean[i], cov[i] = m_x[i] - m_hat, D @ C @ D.T
    claimed = M if filt.output == "prior" else P
    return ErrorStatistics(truth_model.t_gps, mean, cov, claimed)


def monte_carlo_errors(truth_model: CalibrationModel, filt: EpochFilter, n_runs: int,
                       seed: int = 0, truth: str = "error-model") -> np.ndarray:
    """Actual errors x − x̂ (n_runs, n_gps, 3) of ``filt`` on ``n_runs`` simulated realizations.

    The sampled counterpart of :func:`error_statistics` (realizations from
    :func:`gpsaccel.calibration.simulation.simulate_many` with ``seed``; the filter applied to all at once).
    """
    runs = simulate_many(truth_model, n_runs, seed=seed, truth=truth)
    z = np.stack([r.z for r in runs])
    x = np.stack([r.x_gps for r in runs])
    x_hat, _ = filt.apply(z)
    return x - x_hat


# --------------------------------------------------------------------------------------------------
# The reports' mistakes

@dataclass(frozen=True, eq=False)
class Erratum:
    """One mistake of one report, as a truth and a filter.

    Each filter mistake is measured on the error-model truth, which its model describes exactly,
    so that its cost is not mixed with the closed-form truth's Euler mismatch (reports 001/003
    simulate the closed form); that mismatch is an erratum of its own (:func:`euler_mismatch`).

    report : "000", "001" or "003".  key : short name.  wrote / correct : what the report has and
    what it should be.  truth_model, truth : what is simulated.  filt : the mistaken filter.
    baseline : the filter to compare with (the correct filter on the same truth, unless the
    mistake changes the problem itself, then the correct filter on the stated problem).
    baseline_model : the truth of the baseline (the stated problem).
    """

    report: str
    key: str
    wrote: str
    correct: str
    truth_model: CalibrationModel
    truth: str
    filt: EpochFilter
    baseline: EpochFilter
    baseline_model: CalibrationModel

    def statistics(self) -> tuple[ErrorStatistics, ErrorStatistics]:
        """(mistaken, baseline) exact error statistics.

        The baseline of the Euler mismatch is the same filter on the error-model truth (the truth
        its model describes exactly); every other baseline runs on the erratum's own truth.
        """
        base_truth = "error-model" if self.key == "euler-mismatch" else self.truth
        return (error_statistics(self.truth_model, self.filt, self.truth),
                error_statistics(self.baseline_model, self.baseline, base_truth))


def x0_total_state() -> Erratum:
    """Report 000: the error-state estimate starts at the total-state means [0, 100, 0]."""
    m = report_model("000")
    return Erratum("000", "x0-total-state", "x̄0 = [p̄0, v̄0, 0] = [0, 100, 0]", "x̄0 = 0",
                   m, "error-model", mutant("x0-total-state", m), reference(m), m)


def phi13_sign() -> Erratum:
    """Report 001: Φ₁₃ written +Δt²/2 (it is −Δt²/2)."""
    m = report_model("001")
    return Erratum("001", "phi13-sign", "Φ₁₃ = +Δt²/2", "Φ₁₃ = −Δt²/2",
                   m, "error-model", mutant("phi-sign", m), reference(m), m)


def m0_swapped() -> Erratum:
    """Report 001: M0 written diag(1, 100, 0.01), position and velocity swapped."""
    m = report_model("001")
    return Erratum("001", "m0-swapped", "M0 = diag(1, 100, 0.01)", "M0 = diag(100, 1, 0.01)",
                   m, "error-model", mutant("m0-order", m), reference(m), m)


def w_written() -> Erratum:
    """Report 001: W written 0.0016 (it is 0.0004)."""
    m = report_model("001")
    return Erratum("001", "w-0.0016", "W = 0.0016 (m/s²)²", "W = 0.0004 (m/s²)²",
                   m, "error-model", mutant("w-value", m), reference(m), m)


def process_noise_on_gps_interval() -> Erratum:
    """Report 003: Φ and Γ built on the GPS interval, Q = Γ(0.2) W Γ(0.2)ᵀ once per fix."""
    m = report_model("003")
    return Erratum("003", "q-on-gps-interval", "Q = Γ(T)WΓ(T)ᵀ, T = 0.2 s, one step per fix",
                   "Q_e = Σ_{j<40} Φʲ Γ(Δt)WΓ(Δt)ᵀ Φʲᵀ", m, "error-model",
                   mutant("process-noise-interval", m), reference(m), m)


def position_sigma_as_variance() -> Erratum:
    """Report 003: posiSigma = 10 (a standard deviation) used as the variance M0₁₁."""
    m = report_model("003")
    return Erratum("003", "m0-position-10", "M0₁₁ = 10 m² (posiSigma)", "M0₁₁ = 100 m²",
                   m, "error-model", mutant("std-as-variance", m, variant="M0₁₁ = 10, δp's prior variance"),
                   reference(m), m)


def bias_variance_as_sigma() -> Erratum:
    """Report 003: biasSigma = 0.01 (a variance) used as the bias's standard deviation in the truth.

    The simulated biases are then ten times smaller (σ_b = 0.01 m/s², not 0.1 m/s²) while the filter
    keeps M0₃₃ = 0.01: the filter is told the bias is far more uncertain than the truth makes it.
    """
    m = report_model("003")
    truth = m.replace(M0=np.diag([100.0, 1.0, 1e-4]))
    return Erratum("003", "bias-sigma-0.01", "truth b ~ N(0, 0.01²)", "b ~ N(0, 0.01)",
                   truth, "error-model", reference(m), reference(m), m)


def velocity_noise_variance() -> Erratum:
    """Report 003: 0.04 (m/s, a standard deviation) used as the GPS velocity-noise variance.

    Truth and filter both use V₂₂ = 0.04 (m/s)², so the checks pass; the cost is against the
    problem as stated, V₂₂ = 0.0016 (m/s)².
    """
    m = report_model("003")
    wrong = m.replace(V=np.diag([1.0, 0.04]))
    return Erratum("003", "v22-0.04", "V₂₂ = 0.04 (m/s)² (σ = 0.2 m/s)",
                   "V₂₂ = 0.0016 (m/s)² (σ = 0.04 m/s)", wrong, "error-model",
                   reference(wrong), reference(m), m)


def euler_mismatch(report: str = "001") -> Erratum:
    """Reports 001/003: the closed-form truth against the filter's Euler error model.

    The baseline is the same filter on the error-model truth (for which the model is exact).
    """
    m = report_model(report)
    return Erratum(report, "euler-mismatch", "truth a(t) integrated exactly",
                   "the model's Euler integration", m, "kinematic", reference(m), reference(m), m)


ALL_ERRATA = (x0_total_state, phi13_sign, m0_swapped, w_written, process_noise_on_gps_interval,
              position_sigma_as_variance, bias_variance_as_sigma, velocity_noise_variance,
              euler_mismatch)


@dataclass(frozen=True)
class Cost:
    """One erratum's cost, per state [δp, δv, b].

    rms_end, baseline_rms_end : RMS actual error at the last GPS time (30 s), mistaken and baseline.
    ratio_min, ratio_max : range over t of RMS actual error / claimed σ (1 = honest; > 1 the filter
        claims more accuracy than it has, < 1 it claims less).
    worst_mean_over_sigma : max over t of |E e| / claimed σ (a bias the filter does not know of).
    """

    report: str
    key: str
    rms_end: np.ndarray
    baseline_rms_end: np.ndarray
    ratio_min: np.ndarray
    ratio_max: np.ndarray
    worst_mean_over_sigma: np.ndarray


def cost(erratum: Erratum, skip_first: int = 1) -> Cost:
    """The :class:`Cost` of ``erratum``; the first ``skip_first`` epochs are left out of the ranges
    (at t = 0 every filter has just taken its first fix; the transient is not the mistake's)."""
    wrong, base = erratum.statistics()
    s = slice(skip_first, None)
    ratio = wrong.rms[s] / wrong.claimed_sigma[s]
    return Cost(erratum.report, erratum.key, wrong.rms[-1], base.rms[-1], ratio.min(axis=0),
                ratio.max(axis=0), (np.abs(wrong.mean[s]) / wrong.claimed_sigma[s]).max(axis=0))


def cost_table(errata=ALL_ERRATA) -> str:
    """A printed table of :func:`cost` for ``errata`` (callables returning an :class:`Erratum`).

    Three numbers per column: δp (m), δv (m/s), b (m/s²).
    """
    head = (f"{'rep.':<4} {'mistake':<17} {'RMS error at 30 s, mistaken / correct':<52} "
            f"{'RMS/σ claimed, min..max':<33} {'max |mean|/σ':<16}")
    lines = [head, "-" * len(head)]
    for make in errata:
        c = cost(make())
        pair = ", ".join(f"{a:.3g}/{b:.3g}" for a, b in zip(c.rms_end, c.baseline_rms_end,
                                                               strict=True))
        rng = ", ".join(f"{lo:.2f}..{hi:.2f}" for lo, hi in zip(c.ratio_min, c.ratio_max,
                                                                 strict=True))
        bias = ", ".join(f"{v:.2f}" for v in c.worst_mean_over_sigma)
        lines.append(f"{c.report:<4} {c.key:<17} {pair:<52} {rng:<33} {bias:<16}")
    return "\n".join(lines)
