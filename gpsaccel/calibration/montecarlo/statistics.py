r"""The result of the Monte Carlo: its statistics, their standard errors and z-scores.

:class:`MonteCarloResult` holds what :func:`~.engine.monte_carlo` measured over the ensemble
(e_ave, P_ave, orthogonality, the residual products, NEES, NIS) next to what theory says of it
(P, S, Cov x̂, the predicted mean error), and turns each statistic into z-scores that are exactly
N(0, 1) for a consistent filter (:mod:`gpsaccel.kalman.consistency`).  The text made of them, the
reports' numbers and the verdict table, is :mod:`.verdicts`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo import verdicts
from gpsaccel.kalman.consistency import (
    ConsistencyReport,
    cross_moment_se,
    sample_covariance_se,
    z_cross_products,
    z_ensemble_normalized_squared,
    z_sample_covariance,
    z_sample_mean,
)


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """The ensemble statistics of :func:`~.engine.monte_carlo`.  Units: m, m/s, m/s² and their
    products; n below is the number of GPS epochs (151 on the defaults).

    Attributes
    ----------
    n_runs, seed, truth : what was run.
    t : (n,) GPS times (s).
    e_ave : (n, 3) ensemble-mean error (1/N) Σ e, e = x − x̂.
    P_ave : (n, 3, 3) sample error covariance with the N − 1 divisor (reports' Eq. 16).
    P : (n, 3, 3) the filter's a posteriori covariance.
    orthogonality : (n, 3, 3) (1/N) Σ (e − e_ave) x̂ᵀ (reports' Eq. 17).
    residual_lags : (n, L + 1, 2, 2) (1/N) Σ r(t_i) r(t_{i−k})ᵀ for k = 0 .. L = ``max_lag``
        (Eq. 18 for every pair up to that lag; NaN where i − k < 0).  Any product is read with
        :meth:`residual_product`: report 000's r(30 s) r(29.8 s)ᵀ is ``residual_product(150, 149)``.
    residual_pairs : the requested pairs (i, m), i > m, beyond ``max_lag``, and
        residual_pair_products : (len(residual_pairs), 2, 2) their (1/N) Σ r(t_i) r(t_m)ᵀ.
    residual_full : (n, n, 2, 2) every pair, only with ``full_residual_matrix=True`` (else None);
        also as :attr:`residual_correlation`.
    residual_mean : (n, 2) (1/N) Σ r.
    S : (n, 2, 2) the residual covariance H M Hᵀ + V.
    nees, nis : (n,) ensemble averages of eᵀ P⁻¹ e and rᵀ S⁻¹ r.
    estimate_covariance : (n, 3, 3) the theoretical covariance of x̂ (for orthogonality's error).
    estimate_sample_covariance : (n, 3, 3) the sample covariance of x̂ (N − 1 divisor).
    predicted_mean_error : (n, 3) the mean error theory predicts for this truth: zero for the
        error model, the filter's error on the deterministic path d for the kinematic truth.
    """

    n_runs: int
    seed: int
    truth: str
    t: np.ndarray
    e_ave: np.ndarray
    P_ave: np.ndarray
    P: np.ndarray
    orthogonality: np.ndarray
    residual_lags: np.ndarray
    residual_pairs: tuple[tuple[int, int], ...]
    residual_pair_products: np.ndarray
    residual_full: np.ndarray | None
    residual_mean: np.ndarray
    S: np.ndarray
    nees: np.ndarray
    nis: np.ndarray
    estimate_covariance: np.ndarray
    estimate_sample_covariance: np.ndarray
    predicted_mean_error: np.ndarray
    model: CalibrationModel = field(repr=False)

    @property
    def sigma(self) -> np.ndarray:
        """(n, 3) the filter's standard deviations √diag P."""
        return np.sqrt(np.diagonal(self.P, axis1=1, axis2=2))

    @property
    def e_ave_se(self) -> np.ndarray:
        """(n, 3) standard error of e_ave for a consistent filter, √(diag P / N)."""
        return self.sigma / np.sqrt(self.n_runs)

    @property
    def P_ave_se(self) -> np.ndarray:
        """(n, 3, 3) standard error of each element of P_ave, √((P_ab² + P_aa P_bb)/(N − 1)).

        At t = 0 for P_ave[δp, δp]: 0.990 · √(2/9999) = 0.014 m² on report 000's numbers.
        """
        return sample_covariance_se(self.P, self.n_runs)

    @property
    def orthogonality_se(self) -> np.ndarray:
        """(n, 3, 3) standard error of the orthogonality matrix, √((N − 1) P_aa Cov x̂_bb) / N."""
        d_e = np.diagonal(self.P, axis1=1, axis2=2)
        d_x = np.diagonal(self.estimate_covariance, axis1=1, axis2=2)
        return cross_moment_se(d_e[:, :, None], d_x[:, None, :], self.n_runs, centered=True)

    @property
    def max_lag(self) -> int:
        """The largest lag k of :attr:`residual_lags` (every product Σ r_i r_{i−k}ᵀ up to it)."""
        return self.residual_lags.shape[1] - 1

    @property
    def residual_correlation(self) -> np.ndarray:
        """(n, n, 2, 2) (1/N) Σ r(t_i) r(t_m)ᵀ for every pair: only kept on request, since it
        takes 32 n² bytes (10 GB for an hour at 5 Hz); ValueError otherwise."""
        if self.residual_full is None:
            raise ValueError(
                "residual_correlation: the full matrix of residual products was not kept; run "
                "monte_carlo(..., full_residual_matrix=True), or read single products with "
                f"residual_product(i, m) (lags up to max_lag = {self.max_lag}, plus "
                "residual_pairs=...)")
        return self.residual_full

    def residual_product(self, i: int, m: int) -> np.ndarray:
        """(2, 2) (1/N) Σ r(t_i) r(t_m)ᵀ, from the lag band, the requested pairs or the full
        matrix; ValueError saying how to keep it when none has it.  Negative indices count from
        the end, as in numpy."""
        n = self.t.size
        i, m = (_v.integer(name, v, minimum=-n) % n for name, v in (("i", i), ("m", m)))
        if max(i, m) >= n:
            raise ValueError(f"i and m must be epoch indices < {n}, got {(i, m)}")
        if self.residual_full is not None:
            return self.residual_full[i, m]
        if abs(i - m) <= self.max_lag:
            return self.residual_lags[i, i - m] if i >= m else self.residual_lags[m, m - i].T
        later, earlier = max(i, m), min(i, m)
        if (later, earlier) in self.residual_pairs:
            out = self.residual_pair_products[self.residual_pairs.index((later, earlier))]
            return out if i > m else out.T
        raise ValueError(
            f"residual_product({i}, {m}): lag {abs(i - m)} > max_lag = {self.max_lag} and the pair "
            f"was not requested; run monte_carlo(..., residual_pairs=[({i}, {m})]) or a larger "
            f"max_lag")

    def residual_product_se(self, i: int, m: int) -> np.ndarray:
        """(2, 2) standard error of :meth:`residual_product` (i ≠ m), √(S_i,aa S_m,bb / N) for
        independent residuals."""
        d = np.diagonal(self.S, axis1=1, axis2=2)
        return cross_moment_se(d[i][:, None], d[m][None, :], self.n_runs)

    def residual_correlation_se(self) -> np.ndarray:
        """(n, n, 2, 2) standard error of :attr:`residual_correlation` off the diagonal (i ≠ m),
        √(S_i,aa S_m,bb / N) for independent residuals (32 n² bytes; see
        :meth:`residual_product_se` for one pair)."""
        d = np.diagonal(self.S, axis1=1, axis2=2)
        return cross_moment_se(d[:, None, :, None], d[None, :, None, :], self.n_runs)

    def z_scores(self) -> dict[str, np.ndarray]:
        """z-scores of every statistic against theory for a consistent filter (NaN: no spread).

        Each is exactly N(0, 1) under theory, for any N (:mod:`gpsaccel.kalman.consistency`):

        ``e_ave`` (n, 3): e_ave / √(P_aa / N).
        ``P_ave`` (n, 3, 3): diagonal through χ²(N − 1); off the diagonal the regression form of
            :func:`~gpsaccel.kalman.consistency.z_sample_covariance` (element (a, b) conditions on b).
        ``orthogonality`` (n, 3, 3): N O_ab / √(P_aa Σ (x̂_b − x̂̄_b)²), exact because e is
            independent of x̂ (:func:`~gpsaccel.kalman.consistency.z_cross_products`).
        ``residual_lags`` (n, L + 1, 2, 2): for the pair (t_i, t_{i−k}), k ≥ 1,
            N R_ab / √(S_i,aa Σ r_{i−k},b²), exact because r_i is independent of r_{i−k}; NaN for
            k = 0 and where i − k < 0.  ``residual_pairs`` (len(residual_pairs), 2, 2): the same
            for the requested pairs.  ``residual_correlation`` (n, n, 2, 2), only when the full
            matrix was kept: every pair t_m < t_i, NaN for i ≤ m (each pair counts once).
        ``nees``, ``nis`` (n,): N·NEES ~ χ²(3N), N·NIS ~ χ²(2N).

        The standard errors (:attr:`e_ave_se`, :attr:`P_ave_se`, :attr:`orthogonality_se`,
        :meth:`residual_correlation_se`) are the unconditional ones, for plotting; the z-scores
        use the sample's own Σ b² where that makes them exact, so z is close to, not equal to,
        value / SE.
        """
        N, n = self.n_runs, self.t.size
        d_P = np.diagonal(self.P, axis1=1, axis2=2)
        d_X = np.diagonal(self.estimate_sample_covariance, axis1=1, axis2=2) * (N - 1)
        ortho = z_cross_products(N * self.orthogonality, d_P[:, :, None], d_X[:, None, :])
        d_S = np.diagonal(self.S, axis1=1, axis2=2)
        power = N * np.einsum("mbb->mb", self.residual_lags[:, 0])  # Σ_l r_m,b²
        L = self.max_lag
        later = np.arange(n)[:, None] - np.arange(L + 1)[None, :]  # epoch i − k
        lz = z_cross_products(N * np.nan_to_num(self.residual_lags), d_S[:, None, :, None],
                              power[np.maximum(later, 0)][:, :, None, :])
        lz[(later < 0) | (np.arange(L + 1)[None, :] == 0)] = np.nan
        pi = np.array([p[0] for p in self.residual_pairs], dtype=int)
        pm = np.array([p[1] for p in self.residual_pairs], dtype=int)
        pz = z_cross_products(N * self.residual_pair_products, d_S[pi][:, :, None],
                              power[pm][:, None, :])
        extra = {}
        if self.residual_full is not None:
            rz = z_cross_products(N * self.residual_full, d_S[:, None, :, None],
                                  power[None, :, None, :])
            rz[np.triu_indices(n)] = np.nan  # keep pairs t_m < t_i only
            extra["residual_correlation"] = rz
        return {
            "e_ave": z_sample_mean(self.e_ave, d_P, N),
            "P_ave": z_sample_covariance(self.P_ave, self.P, N),
            "orthogonality": ortho,
            "residual_lags": lz,
            "residual_pairs": pz,
            **extra,
            "nees": z_ensemble_normalized_squared(self.nees, 3, N),
            "nis": z_ensemble_normalized_squared(self.nis, 2, N),
        }

    def summary(self) -> str:
        """The numbers the reports printed, each with its standard error (what the CLI prints):
        :func:`.verdicts.summary`."""
        return verdicts.summary(self)

    def consistency(self, alpha: float = 0.01) -> ConsistencyReport:
        """Verdicts on every statistic, family-wise false-alarm rate ``alpha`` for the table:
        :func:`.verdicts.consistency`."""
        return verdicts.consistency(self, alpha)
