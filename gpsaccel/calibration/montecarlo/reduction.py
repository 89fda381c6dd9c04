r"""A block of realizations filtered as arrays and reduced to sums that merge.

:func:`_run_block` runs the truth, the measurements and the filter for every column of a block of
standard normals (:mod:`.streams`) with the plan's gains (:mod:`.planning`), and returns their
sufficient statistics, :class:`EnsembleSums`: count, means, centred co-moments, the residual
products Σ r_i r_{i−k}ᵀ up to ``max_lag`` and any pairs asked for, Σ NEES, Σ NIS.  Chunks merge in
order (Chan et al.'s pairwise update, :meth:`EnsembleSums.merge`), so memory does not grow with
``n_runs``, only linearly with the duration, and the statistics depend on the chunking only
through floating-point rounding (≪ 1e-12 relative).

:func:`realizations` keeps the arrays instead of reducing them: the engine's measurements and
truths, for running filterpy on the very same realizations.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.calibration.model import CalibrationModel
from gpsaccel.calibration.montecarlo.planning import EnsemblePlan, plan
from gpsaccel.calibration.montecarlo.streams import _ArrayNormals, _standard_normals


def _run_block(pl: EnsemblePlan, xi: np.ndarray | _ArrayNormals,
               keep: bool = False) -> tuple[EnsembleSums, dict[str, np.ndarray] | None]:
    """Truth, measurements, filter and sums for each column of standard normals xi (n_normals, m).

    Everything is linear, so every quantity is its expected value (``pl.mean_*``, the filter run
    on the deterministic offset; zero for the error model) plus a zero-mean part driven by the
    noise.  ``xi`` is the (n_normals, m) array of standard normals or a streamed source of them.
    The loop runs the zero-mean part only — x̃_i = Φ_N x̃_{i−1} + u_{i−1},
    r̃_i = x̃_i[:2] + η_i − x̄̃_i[:2], x̂̃_i = x̄̃_i + K_i r̃_i, ẽ_i = x̃_i − x̂̃_i — with every
    quantity a (component, run) array, so that each step is one small matrix times m columns.
    Per epoch it accumulates G_i = Σ w wᵀ of w = [ẽ; x̂̃; 1] (which holds Σ ẽ ẽᵀ, Σ ẽ x̂̃ᵀ and
    the sums Σ ẽ, Σ x̂̃), and the residual products Σ r̃_i r̃_{i−k}ᵀ for k = 0 .. max_lag from a
    ring of the last max_lag + 1 residuals (each written twice, at q and q + max_lag + 1 with
    q = −i mod (max_lag + 1), so that r̃_i, r̃_{i−1}, ... r̃_{i−k} are one contiguous slice), the
    requested pairs, and with ``full`` every residual.  The expected values go back in afterwards,
    exactly: with r = r̃ + ρ, Σ r rᵀ = Σ r̃ r̃ᵀ + ρ (Σ r̃)ᵀ + (Σ r̃) ρᵀ + m ρ ρᵀ, and likewise
    Σ e eᵀ for NEES = tr(P⁻¹ e eᵀ) and NIS = tr(S⁻¹ r rᵀ).  The co-moments are centred on the
    expected values, so no precision is lost to a large mean.

    With ``keep`` it also returns the full arrays (epoch, component, run): x (true error state),
    z, x_bar, x_hat, r.
    """
    normals = xi if isinstance(xi, _ArrayNormals) else _ArrayNormals(xi, pl.n_gps)
    m, n, L = normals.m, pl.n_gps, pl.max_lag
    Phi_N, K = pl.Phi_N, pl.K
    LQ, LV = pl.LQ[:2, :2], pl.LV
    w = np.empty((7, m))  # [ẽ; x̂̃; 1]
    w[6] = 1.0
    xhat = w[3:6]
    G = np.empty((n, 7, 7))
    Kr = np.empty((3, m))
    ring = np.empty((2 * (L + 1), 2, m))  # r̃_i at q and q + L + 1, q = −i mod (L + 1)
    band = np.zeros((n, L + 1, 2, 2))  # Σ r̃_i r̃_{i−k}ᵀ
    s_r = np.empty((n, 2))  # Σ r̃_i
    earlier: dict[int, np.ndarray] = {mm: np.empty(0) for _, mm in pl.pairs}  # r̃_m kept for
    # the requested pairs (each filled at its epoch m, before the later epoch i reads it)
    later: dict[int, list[int]] = {}
    for j, (i, _) in enumerate(pl.pairs):
        later.setdefault(i, []).append(j)
    pair_sums = np.zeros((len(pl.pairs), 2, 2))
    r_all = np.empty((2 * n, m)) if pl.full else None  # stacked r̃: r̃_0[p], r̃_0[v], r̃_1[p], ...
    ubuf, ebuf = np.empty((2, m)), np.empty((2, m))
    x = pl.L0 @ normals.x0  # x̃_0 ~ N(0, M0)
    xbar = np.zeros((3, m))  # x̄_0 = x0 is deterministic
    if keep:
        kept = {k: np.empty((n, d, m)) for k, d in
                (("x", 3), ("z", 2), ("x_bar", 3), ("x_hat", 3), ("r", 2))}
    for i, un, en in normals.epochs():
        # u_{i−1} = L_Q ξ and η_i = L_V ξ (both factors lower triangular 2x2)
        for out, Lf, xn in ((ubuf, LQ, un), (ebuf, LV, en)):
            if xn is None:
                continue
            np.multiply(Lf[0, 0], xn[0], out=out[0])
            np.multiply(Lf[1, 0], xn[0], out=out[1])
            out[1] += Lf[1, 1] * xn[1]
        if i > 0:
            x = Phi_N @ x
            x[:2] += ubuf  # x̃_i = Φ_N x̃_{i−1} + u_{i−1}
            xbar = Phi_N @ xhat  # x̄̃_i = Φ_N x̂̃_{i−1}
        q = (-i) % (L + 1)
        r = ring[q]
        np.add(x[:2], ebuf, out=r)
        r -= xbar[:2]  # r̃_i = H x̃_i + η_i − H x̄̃_i
        ring[q + L + 1] = r
        k = min(i, L)
        window = ring[q:q + k + 1].reshape(2 * (k + 1), m)  # r̃_i, r̃_{i−1}, ..., r̃_{i−k}
        band[i, :k + 1] = (r @ window.T).reshape(2, k + 1, 2).transpose(1, 0, 2)
        s_r[i] = r.sum(axis=1)
        for j in later.get(i, ()):
            pair_sums[j] = r @ earlier[pl.pairs[j][1]].T
        if i in earlier:
            earlier[i] = r.copy()
        if r_all is not None:
            r_all[2 * i:2 * i + 2] = r
        np.matmul(K[i], r, out=Kr)
        np.add(xbar, Kr, out=xhat)  # x̂̃_i = x̄̃_i + K_i r̃_i
        np.subtract(x, xhat, out=w[:3])  # ẽ_i
        np.matmul(w, w.T, out=G[i])
        if keep:
            kept["x"][i], kept["x_bar"][i], kept["x_hat"][i] = x, xbar, xhat
            kept["z"][i], kept["r"][i] = x[:2] + ebuf, r
    # -- the sums, expected values put back
    sw = G[:, 6, :6]  # Σ w (n, 6)
    de, dx = sw[:, :3] / m, sw[:, 3:] / m  # block means of ẽ and x̂̃
    C = G[:, :6, :6] - m * (sw[:, :, None] / m) * (sw[:, None, :] / m)
    mu = pl.mean_e
    see = G[:, :3, :3] + mu[:, :, None] * sw[:, None, :3] + sw[:, :3, None] * mu[:, None, :] \
        + m * mu[:, :, None] * mu[:, None, :]  # Σ e eᵀ
    rr_full = None
    if r_all is not None:
        rr_full = r_all @ r_all.T
    _add_residual_means(pl, m, s_r, band, pair_sums, rr_full)
    rr_diag = band[:, 0]  # Σ r_i r_iᵀ
    sums = EnsembleSums(
        n=m, mean_e=mu + de, mean_xhat=pl.mean_xhat + dx,
        mean_r=pl.mean_r + s_r / m,
        C_ee=C[:, :3, :3], C_ex=C[:, :3, 3:], C_xx=C[:, 3:, 3:], rr_band=band,
        rr_pairs=pair_sums, rr_full=rr_full,
        nees=np.einsum("iab,iba->i", pl.P_inv, see),
        nis=np.einsum("iab,iba->i", pl.S_inv, rr_diag))
    if not keep:
        return sums, None
    kept["x"] += pl.offset[:, :, None]
    kept["z"] += pl.offset[:, :2, None]
    kept["x_bar"] += pl.mean_xprior[:, :, None]
    kept["x_hat"] += pl.mean_xhat[:, :, None]
    kept["r"] += pl.mean_r[:, :, None]
    return sums, kept


def _add_residual_means(pl: EnsemblePlan, m: int, s_r: np.ndarray, band: np.ndarray,
                        pair_sums: np.ndarray, rr_full: np.ndarray | None) -> None:
    """Put the expected residuals ρ = ``pl.mean_r`` back into the products of the zero-mean
    residuals r̃ of m runs, in place: Σ r_i r_mᵀ = Σ r̃_i r̃_mᵀ + ρ_i (Σ r̃_m)ᵀ + (Σ r̃_i) ρ_mᵀ
    + m ρ_i ρ_mᵀ, for the lag band, the requested pairs and the full matrix (when kept).
    Nothing to do for the error model (ρ = 0)."""
    rho, n, L = pl.mean_r, pl.n_gps, pl.max_lag
    if not rho.any():
        return

    def shift(i, mm):
        return (rho[i][..., :, None] * s_r[mm][..., None, :]
                + s_r[i][..., :, None] * rho[mm][..., None, :]
                + m * rho[i][..., :, None] * rho[mm][..., None, :])
    ii = np.arange(n)[:, None]
    mm = ii - np.arange(L + 1)[None, :]
    band += np.where((mm >= 0)[..., None, None], shift(ii, np.maximum(mm, 0)), 0.0)
    if pl.pairs:
        pi, pm = np.array(pl.pairs).T
        pair_sums += shift(pi, pm)
    if rr_full is not None:
        rv, sv = rho.reshape(-1), s_r.reshape(-1)
        rr_full += np.outer(rv, sv)
        rr_full += np.outer(sv, rv)
        rr_full += m * np.outer(rv, rv)


@dataclass(eq=False)
class EnsembleSums:
    """Sufficient statistics of a set of runs; two sets merge with :meth:`merge`.

    n : runs.  mean_e, mean_xhat (n_gps, 3) and mean_r (n_gps, 2): means.
    C_ee, C_ex, C_xx (n_gps, 3, 3): centred co-moments Σ (e − ē)(e − ē)ᵀ, Σ (e − ē)(x̂ − x̂̄)ᵀ,
    Σ (x̂ − x̂̄)(x̂ − x̂̄)ᵀ.
    rr_band (n_gps, max_lag + 1, 2, 2): Σ r_i r_{i−k}ᵀ (zero where i − k < 0).
    rr_pairs (len(pairs), 2, 2): Σ r_i r_mᵀ for the plan's requested pairs (i, m).
    rr_full (2 n_gps, 2 n_gps) or None: Σ r rᵀ over the stacked residuals [r_0; r_1; ...], only
    when the full matrix was asked for.
    nees, nis (n_gps,): Σ eᵀ P⁻¹ e and Σ rᵀ S⁻¹ r.
    """

    n: int
    mean_e: np.ndarray
    mean_xhat: np.ndarray
    mean_r: np.ndarray
    C_ee: np.ndarray
    C_ex: np.ndarray
    C_xx: np.ndarray
    rr_band: np.ndarray
    rr_pairs: np.ndarray
    rr_full: np.ndarray | None
    nees: np.ndarray
    nis: np.ndarray

    def merge(self, other: EnsembleSums, in_place: bool = False) -> EnsembleSums:
        """The sums of both sets (Chan, Golub & LeVeque's pairwise update of the co-moments).

        With ``in_place`` the residual products (the largest arrays, O(n_gps · max_lag)) are
        added into this object's arrays, which the result then shares: the engine's running
        total uses it, so that a merge holds two copies of them, not three.
        """
        n = self.n + other.n
        fa, fb = self.n / n, other.n / n
        de = other.mean_e - self.mean_e
        dx = other.mean_xhat - self.mean_xhat
        w = self.n * other.n / n
        rr_band, rr_pairs = ((np.add(a, b, out=a) if in_place else a + b)
                             for a, b in ((self.rr_band, other.rr_band),
                                          (self.rr_pairs, other.rr_pairs)))
        a, b = self.rr_full, other.rr_full
        rr_full = None if a is None or b is None else (np.add(a, b, out=a) if in_place else a + b)
        return EnsembleSums(
            n,
            self.mean_e + fb * de,
            self.mean_xhat + fb * dx,
            fa * self.mean_r + fb * other.mean_r,
            self.C_ee + other.C_ee + w * de[:, :, None] * de[:, None, :],
            self.C_ex + other.C_ex + w * de[:, :, None] * dx[:, None, :],
            self.C_xx + other.C_xx + w * dx[:, :, None] * dx[:, None, :],
            rr_band, rr_pairs, rr_full,
            self.nees + other.nees,
            self.nis + other.nis,
        )



@dataclass(frozen=True, eq=False)
class Realizations:
    """The engine's realizations ``runs`` (global run indices), for checking it against filterpy.

    x_gps (m, n_gps, 3): the true error state at the GPS times; z (m, n_gps, 2) the measurement
    (m, m/s); x_bar, x_hat (m, n_gps, 3) and residuals (m, n_gps, 2) the engine's filter.
    """

    runs: np.ndarray
    t: np.ndarray
    x_gps: np.ndarray
    z: np.ndarray
    x_bar: np.ndarray
    x_hat: np.ndarray
    r: np.ndarray


def realizations(model: CalibrationModel, start: int, stop: int, seed: int = 0,
                 truth: str = "error-model") -> Realizations:
    """Runs ``start`` .. ``stop − 1`` of the ensemble ``monte_carlo(model, ..., seed, truth)`` uses.

    Feed ``z[l]`` to :func:`gpsaccel.run_multirate` to run filterpy on realization l; its
    ``x_gps[l] − x_hat`` is the error the engine accumulated for that run.
    """
    seed = _v.integer("seed", seed, minimum=0)
    start = _v.integer("start", start, minimum=0)
    stop = _v.integer("stop", stop, minimum=start + 1)
    pl = plan(model, truth)
    out = _run_block(pl, _standard_normals(seed, pl.n_normals, start, stop), keep=True)[1]
    assert out is not None  # keep=True keeps them
    runs_first = {k: np.ascontiguousarray(v.transpose(2, 0, 1)) for k, v in out.items()}
    return Realizations(np.arange(start, stop), pl.t, runs_first["x"], runs_first["z"],
                        runs_first["x_bar"], runs_first["x_hat"], runs_first["r"])

