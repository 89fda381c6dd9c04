r"""NEES/NIS truth-model testing and Q tuning for cooperative localization (report 002).

Truth-model test (the course's "TMT"): simulate N truth runs with process noise
(:meth:`gpsaccel.coop.model.CoopModel.simulate`), filter each, and at every step k = 1..K average
the N normalised errors::

    ε̄_x,k = (1/N) Σ_i e_ikᵀ P_ik⁻¹ e_ik          (NEES, n = 6 dof per run)
    ε̄_y,k = (1/N) Σ_i r_ikᵀ S_ik⁻¹ r_ik          (NIS,  p = 5 dof per run)

For a consistent filter N·ε̄ ~ χ²(N·n), so ε̄ should lie in [r1, r2] =
[χ²⁻¹(α/2; N·n)/N, χ²⁻¹(1 − α/2; N·n)/N] on a fraction 1 − α of the steps
(:func:`gpsaccel.kalman.consistency.chi2_bounds`).  NEES at neighbouring steps is strongly correlated, so
the fraction inside varies by several points from one N-run set to the next: judge a filter over
several independent sets (:func:`repeated_sets`).

Tuning (:func:`tune_q`): the report tuned Q by hand, multiplying Qtrue by powers of ten and then
adjusting the diagonal.  Here a grid of multipliers of Qtrue's UGV-position, UAV-position and
heading terms is scored on common random numbers (the same truth runs for every candidate) by
``min(NEES fraction, NIS fraction)``; among the candidates within a tolerance of the top score
(the scatter of the fractions between sets) the one closest to Qtrue is chosen.
"""

from __future__ import annotations

import itertools
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v
from gpsaccel.coop.filters import METHODS, FilterResult, run_batch, scaled_q, tuned_q
from gpsaccel.coop.model import CoopModel, Truth
from gpsaccel.kalman import consistency

#: The grids of Qtrue multipliers :func:`tune_q` searches by default (UGV pos, UAV pos, heading):
#: fine steps around Qtrue for the EKF and UKF, powers of ten for the LKF (as the report did).
_FINE = ((1.0, 1.5, 2.0, 3.0, 4.0), (1.0, 1.5, 2.0, 3.0, 4.0), (0.5, 1.0, 2.0))
DEFAULT_GRIDS = {"lkf": ((1.0, 10.0, 100.0, 1e3, 1e4), (1.0, 10.0, 100.0, 1e3, 1e4),
                         (1.0, 10.0, 100.0)),
                 "ekf": _FINE, "ukf": _FINE}


@dataclass
class ConsistencyRun:
    """One N-run NEES/NIS test of one filter.

    t : (K,) s, steps 1..K.  nees_mean, nis_mean : (K,) the N-run averages ε̄_x, ε̄_y.
    nees_bounds, nis_bounds : (r1, r2).  nees_fraction, nis_fraction : fraction of steps inside.
    runtime_s : wall time of the filter over all N runs (s), truth simulation excluded.
    """

    method: str
    Q: np.ndarray
    n_runs: int
    alpha: float
    t: np.ndarray
    nees_mean: np.ndarray
    nis_mean: np.ndarray
    nees_bounds: tuple[float, float]
    nis_bounds: tuple[float, float]
    runtime_s: float
    result: FilterResult | None = None
    truth: Truth | None = None

    @classmethod
    def of(cls, method: str, Q: np.ndarray, alpha: float, t: np.ndarray, nees: np.ndarray,
           nis: np.ndarray, runtime_s: float, result: FilterResult | None = None,
           truth: Truth | None = None) -> ConsistencyRun:
        """The test of the per-run NEES and NIS ``nees``, ``nis`` (N, K): their averages over the
        runs and the two-sided χ² bounds of N runs at ``alpha``."""
        N = nees.shape[0]
        return cls(method, Q, N, alpha, t, nees.mean(axis=0), nis.mean(axis=0),
                   consistency.chi2_bounds(6, N, alpha), consistency.chi2_bounds(5, N, alpha),
                   runtime_s, result, truth)

    @property
    def nees_fraction(self) -> float:
        return consistency.fraction_inside(self.nees_mean, self.nees_bounds)

    @property
    def nis_fraction(self) -> float:
        return consistency.fraction_inside(self.nis_mean, self.nis_bounds)


def truth_runs(model: CoopModel, n_runs: int, seed: int | np.random.SeedSequence) -> Truth:
    """N truth runs from a seed (an int or a ``SeedSequence``)."""
    return model.simulate(np.random.default_rng(seed), n_runs)


def consistency_test(model: CoopModel, method: str, Q: np.ndarray | None = None,
                     n_runs: int = 50, seed: int = 0, alpha: float = 0.05,
                     truth: Truth | None = None, keep: bool = False,
                     result: FilterResult | None = None) -> ConsistencyRun:
    """NEES and NIS of ``method`` ('lkf', 'ekf', 'ukf') over N truth runs (or the given ``truth``).

    ``Q`` defaults to the tuned Q of the method.  ``keep`` keeps the filter result and the truth
    on the returned object (for plots of a typical run).  ``result``: this filter already run on
    ``truth`` (``run_batch(method, model, truth.y, Q)``), read instead of filtering again (the
    same numbers; ``runtime_s`` is then NaN: nothing was timed here).
    """
    method = _v.choice("method", method, METHODS)
    alpha = _v.probability("alpha", alpha)
    if truth is None:
        n_runs = _v.integer("n_runs", n_runs, minimum=1)
        truth = truth_runs(model, n_runs, seed)
    Q = tuned_q(method, model) if Q is None else _v.spd_matrix("Q", Q, 6)
    if result is None:
        return _tests(model, method, [(Q, truth)], alpha, keep)[0]
    if result.method != method or np.shape(result.x_hat) != truth.x.shape:
        raise ValueError(f"result must be the {method.upper()}'s on the truth's {truth.n_runs} "
                         f"runs, got the {result.method.upper()}'s of shape "
                         f"{np.shape(result.x_hat)}")
    return ConsistencyRun.of(method, Q, alpha, model.t[1:], result.nees(truth.x)[:, 1:],
                             result.nis()[:, 1:], float("nan"), result if keep else None,
                             truth if keep else None)


#: Runs filtered in one call by :func:`_tests`: the per-step cost of a call is shared by its runs,
#: so a run's CPU falls with the runs a call holds and has flattened by here
#: (``benchmarks/coop_chunk.py``); each run adds ~1 MB of output to the call.
_CHUNK_RUNS = 200


def _tests(model: CoopModel, method: str, jobs: list[tuple[np.ndarray, Truth]], alpha: float,
           keep: bool = False, progress: bool = False, executor: object = None
           ) -> list[ConsistencyRun]:
    """One consistency test per (Q, truth) job, the jobs' runs stacked into few filter calls
    (one Q per run): the per-step cost of a call is shared by every set and candidate in it.
    For the EKF and UKF each run's numbers are those of its own call, bit for bit.  The LKF with
    one shared Q (one job) updates all its runs in one matrix product, whose last bits depend on
    how many runs a call holds: its numbers may differ in the last bits between calls cut
    differently (a pool against a serial run); no lesson prints that many digits.  ``runtime_s``
    is the calls' filter time shared out by runs.  ``progress``: a tqdm.auto bar over the runs, one step per
    call (a lesson's long cell shows that it is working).

    ``executor`` (:func:`gpsaccel.executors.resolve_executor`; None: here): where the calls run.
    The runs are cut into calls of at most :data:`_CHUNK_RUNS`, as many as a multiple of the
    pool's workers and of equal size, so every worker gets the same share (a set may be cut between
    two calls).  The numbers do not depend on the cut (but for the LKF's last bits, above): a
    run's numbers do not depend on the others in its call, and each set's averages are taken over
    its runs in order.  ``keep`` (one
    result per job) keeps each job whole in one call."""
    from tqdm.auto import tqdm

    from gpsaccel.executors import resolve_executor

    sizes = [tr.n_runs for _, tr in jobs]
    bar = tqdm(total=sum(sizes), desc=f"{method.upper()} runs", unit="run",
               leave=False, disable=None if progress and sys.stderr is not None else True)
    with bar, resolve_executor(executor) as ex:
        workers = 1 if executor is None else _workers(ex)
        cuts = np.cumsum([0, *sizes]) if keep else _cuts(sum(sizes), workers)
        y = np.concatenate([tr.y for _, tr in jobs])
        x = np.concatenate([tr.x for _, tr in jobs])
        Qs = np.concatenate([np.broadcast_to(Q, (tr.n_runs, 6, 6)) for Q, tr in jobs])
        futures = [ex.submit(_filter_chunk, model, method, y[a:b], x[a:b],
                             Qs[a:b] if len(jobs) > 1 else jobs[0][0], keep)
                   for a, b in itertools.pairwise(cuts)]
        parts = []
        for (a, b), future in zip(itertools.pairwise(cuts), futures, strict=True):
            parts.append(future.result())
            bar.update(b - a)
    nees = np.concatenate([p[0] for p in parts])
    nis = np.concatenate([p[1] for p in parts])
    runtime = sum(p[2] for p in parts)
    out: list[ConsistencyRun] = []
    for j, ((Q, tr), start) in enumerate(zip(jobs, np.cumsum([0, *sizes]), strict=False)):
        part = slice(start, start + tr.n_runs)
        out.append(ConsistencyRun.of(method, Q, alpha, model.t[1:], nees[part], nis[part],
                                     runtime * tr.n_runs / len(nees),
                                     parts[j][3] if keep else None, tr if keep else None))
    return out


def _workers(ex: object) -> int:
    """How many calls a pool runs at once (its ``_max_workers`` when it says; else the CPUs)."""
    return int(getattr(ex, "_max_workers", None) or os.cpu_count() or 1)


def _cuts(total: int, workers: int) -> np.ndarray:
    """Boundaries of equal calls over ``total`` runs: at most :data:`_CHUNK_RUNS` runs each, their
    number a multiple of ``workers``."""
    calls = -(-total // _CHUNK_RUNS)
    calls = min(total, -(-calls // workers) * workers)
    return np.linspace(0, total, calls + 1).round().astype(int)


def _filter_chunk(model: CoopModel, method: str, y: np.ndarray, x: np.ndarray, Q: np.ndarray,
                  keep: bool) -> tuple[np.ndarray, np.ndarray, float, FilterResult | None]:
    """One filter call over these runs (``Q`` one per run, or one for all): (NEES, NIS) per run and
    step 1..K, the filter's wall time, the result itself if ``keep``.  Module-level: a process pool
    runs it, and sends back only the statistics unless ``keep`` (a result is ~1 MB a run)."""
    t0 = time.perf_counter()
    res = run_batch(method, model, y, Q)
    runtime = time.perf_counter() - t0
    return res.nees(x)[:, 1:], res.nis()[:, 1:], runtime, res if keep else None


def set_seeds(seed: int, n_sets: int) -> list[np.random.SeedSequence]:
    """Independent seeds of ``n_sets`` Monte Carlo sets, spawned from ``seed``."""
    return np.random.SeedSequence(seed).spawn(_v.integer("n_sets", n_sets, minimum=1))


def repeated_sets(model: CoopModel, method: str, Q: np.ndarray | None = None,
                  n_sets: int = 5, n_runs: int = 50, seed: int = 0,
                  alpha: float = 0.05, truths: Sequence[Truth] | None = None,
                  progress: bool = False, executor: object = None) -> list[ConsistencyRun]:
    """``n_sets`` independent N-run consistency tests (seeds spawned from ``seed``).

    ``truths``: the sets already simulated (:func:`repeated_truths`), for a second filter on the
    same sets without simulating them again; ``n_sets``, ``n_runs`` and ``seed`` are then unused.
    ``progress``: a tqdm bar over the runs filtered.  ``executor``: where the sets are simulated
    and filtered, one set a task (:func:`gpsaccel.executors.resolve_executor`; None: here); the
    numbers do not depend on it (each set has its own seed and its own filter call).
    """
    method = _v.choice("method", method, METHODS)
    alpha = _v.probability("alpha", alpha)
    Q = tuned_q(method, model) if Q is None else _v.spd_matrix("Q", Q, 6)
    if truths is None:
        truths = repeated_truths(model, n_sets, n_runs, seed, executor=executor)
    elif not truths:
        raise ValueError("truths holds no set: give at least one Truth (or leave it None)")
    return _tests(model, method, [(Q, tr) for tr in truths], alpha, progress=progress,
                  executor=executor)


def repeated_sets_by_q(model: CoopModel, method: str, Qs: dict[str, np.ndarray | None],
                       truths: Sequence[Truth], alpha: float = 0.05, progress: bool = False,
                       executor: object = None) -> dict[str, list[ConsistencyRun]]:
    """:func:`repeated_sets` of one filter ('ekf', 'ukf') with several Q on the same ``truths``,
    in one pass: ``{label: the tests of Qs[label]}`` (None: the tuned Q).

    Every Q's sets go into the same filter calls (one Q per run), so a call's per-step cost is
    paid once for all of them (lesson 11's EKF with Qtrue and with its tuned Q: half the calls);
    each number is that of :func:`repeated_sets` with that Q alone, bit for bit.  Not the LKF,
    whose shared covariance a Q per run would undo (see :func:`_tests`)."""
    method = _v.choice("method", method, ("ekf", "ukf"))
    alpha = _v.probability("alpha", alpha)
    if not truths:
        raise ValueError("truths holds no set: give at least one Truth")
    given = {label: tuned_q(method, model) if Q is None else _v.spd_matrix("Q", Q, 6)
             for label, Q in Qs.items()}
    tests = _tests(model, method, [(Q, tr) for Q in given.values() for tr in truths], alpha,
                   progress=progress, executor=executor)
    n = len(truths)
    return {label: tests[i * n:(i + 1) * n] for i, label in enumerate(given)}


def repeated_truths(model: CoopModel, n_sets: int = 5, n_runs: int = 50, seed: int = 0,
                    executor: object = None) -> list[Truth]:
    """The truth sets of :func:`repeated_sets` (``n_sets`` of ``n_runs`` runs from ``seed``),
    one set a task on ``executor`` (None: here; the same sets either way, each from its seed)."""
    from gpsaccel.executors import resolve_executor

    n_runs = _v.integer("n_runs", n_runs, minimum=1)
    seeds = set_seeds(seed, n_sets)
    if executor is None:
        return [truth_runs(model, n_runs, s) for s in seeds]
    with resolve_executor(executor) as ex:
        futures = [ex.submit(truth_runs, model, n_runs, s) for s in seeds]
        return [f.result() for f in futures]


@dataclass
class TuningResult:
    """Every candidate tried by :func:`tune_q`: scales (UGV pos, UAV pos, heading) and fractions.

    ``tol``: candidates whose score is within ``tol`` of the highest count as equally good (one
    50-run set's NEES fraction scatters by several points); among them :attr:`best` is the one
    closest to Qtrue (smallest Σ log² of its multipliers), so Q is inflated only as far as the
    tests can tell it helps.  ``tests``: every (candidate, set) consistency test, candidate by
    candidate (:meth:`candidate`).
    """

    method: str
    scales: list[tuple[float, float, float]]
    nees_fraction: np.ndarray
    nis_fraction: np.ndarray
    tol: float = 0.02
    tests: list[ConsistencyRun] | None = None

    def candidate(self, scales: tuple[float, float, float]) -> list[ConsistencyRun]:
        """The consistency tests of the candidate ``scales``, one per set (what :func:`tune_q`
        measured: a caller that wants the numbers of one Q on the tuning sets need not run it
        again)."""
        if self.tests is None:
            raise ValueError("this TuningResult keeps no tests (made without tune_q)")
        per = len(self.tests) // len(self.scales)
        i = self.scales.index(tuple(float(v) for v in scales))  # type: ignore[arg-type]
        return self.tests[i * per:(i + 1) * per]

    @property
    def score(self) -> np.ndarray:
        """min(NEES fraction, NIS fraction) of each candidate."""
        return np.minimum(self.nees_fraction, self.nis_fraction)

    @property
    def inflation(self) -> np.ndarray:
        """Distance of each candidate from Qtrue: Σ log²(multiplier)."""
        return np.array([sum(np.log(s) ** 2 for s in sc) for sc in self.scales])

    @property
    def best(self) -> tuple[float, float, float]:
        """The candidate closest to Qtrue among those scoring within ``tol`` of the top score."""
        good = self.score >= self.score.max() - self.tol
        i = int(np.argmin(np.where(good, self.inflation, np.inf)))
        return self.scales[i]

    def table(self, top: int = 10) -> str:
        """The ``top`` candidates by score as a fixed-width table; the chosen one marked."""
        order = np.lexsort((self.inflation, -self.score))[:top]
        best = self.best
        lines = [f"{self.method.upper()} Q = Qtrue scaled by (UGV pos, UAV pos, heading); "
                 f"* = chosen (closest to Qtrue within {self.tol:g} of the top score)",
                 f"{'scales':<22} {'NEES in':>8} {'NIS in':>8}"]
        for i in order:
            sc = "(" + ", ".join(f"{s:g}" for s in self.scales[i]) + ")"
            mark = " *" if self.scales[i] == best else ""
            lines.append(f"{sc:<22} {self.nees_fraction[i]:8.3f} {self.nis_fraction[i]:8.3f}{mark}")
        if best not in [self.scales[i] for i in order]:
            i = self.scales.index(best)
            lines.append(f"{str(best):<22} {self.nees_fraction[i]:8.3f} "
                         f"{self.nis_fraction[i]:8.3f} *")
        return "\n".join(lines)


def tune_q(model: CoopModel, method: str, grid: Sequence[Sequence[float]] | None = None,
           n_runs: int = 50, n_sets: int = 1, seed: int = 2024, alpha: float = 0.05,
           tol: float = 0.02, progress: bool = False, executor: object = None) -> TuningResult:
    """Search Q = Qtrue scaled by every (UGV pos, UAV pos, heading) multiplier in ``grid``.

    Every candidate sees the same truth runs (common random numbers, ``n_sets`` sets of ``n_runs``
    spawned from ``seed``); fractions are averaged over the sets.  ``grid`` defaults to
    :data:`DEFAULT_GRIDS` of the method.  ``progress``: a tqdm bar over the runs filtered.
    ``executor``: where the candidates are filtered, one (candidate, set) a task (see
    :func:`_tests`; the numbers do not depend on it).
    """
    method = _v.choice("method", method, METHODS)
    grid = DEFAULT_GRIDS[method] if grid is None else grid
    if len(grid) != 3:
        raise ValueError(f"grid must hold 3 lists of multipliers (UGV pos, UAV pos, heading), "
                         f"got {len(grid)}")
    truths = [truth_runs(model, n_runs, s) for s in set_seeds(seed, n_sets)]
    scales = [(float(a), float(b), float(c)) for a, b, c in itertools.product(*grid)]
    alpha = _v.probability("alpha", alpha)
    jobs = [(scaled_q(model.Qtrue, *sc), tr) for sc in scales for tr in truths]
    tests = _tests(model, method, jobs, alpha, progress=progress, executor=executor)
    per = len(truths)
    nees_f = [np.mean([r.nees_fraction for r in tests[i:i + per]])
              for i in range(0, len(tests), per)]
    nis_f = [np.mean([r.nis_fraction for r in tests[i:i + per]])
             for i in range(0, len(tests), per)]
    return TuningResult(method, scales, np.array(nees_f), np.array(nis_f), tol, tests)


def format_sets(runs_by_label: dict[str, list[ConsistencyRun]]) -> str:
    """A table: per filter, the NEES/NIS fractions inside the bounds (mean, min-max over sets)."""
    lines = [f"{'filter':<22} {'sets':>4} {'N':>4} {'NEES in: mean [min, max]':>26} "
             f"{'NIS in: mean [min, max]':>25} {'NEES avg':>9} {'NIS avg':>8}"]
    for label, runs in runs_by_label.items():
        ne = np.array([r.nees_fraction for r in runs])
        ni = np.array([r.nis_fraction for r in runs])
        na = np.mean([r.nees_mean.mean() for r in runs])
        sa = np.mean([r.nis_mean.mean() for r in runs])
        lines.append(f"{label:<22} {len(runs):4d} {runs[0].n_runs:4d} "
                     f"{ne.mean():10.3f} [{ne.min():.3f}, {ne.max():.3f}] "
                     f"{ni.mean():9.3f} [{ni.min():.3f}, {ni.max():.3f}] {na:9.2f} {sa:8.2f}")
    return "\n".join(lines)


def summary(model: CoopModel | None = None, n_runs: int = 50, n_sets: int = 5, seed: int = 0,
            alpha: float = 0.05, progress: bool = False) -> str:
    """The issue's table: per filter the Q, NEES/NIS fractions over sets, NIS on the log, runtime.

    LKF, EKF and UKF with their tuned Q, and the EKF and UKF with Q = Qtrue, all on the same
    ``n_sets`` truth sets of ``n_runs`` runs; the runtime is one 100-second run of the filterpy
    implementation (wall clock, this machine).  ``progress``: a tqdm bar on stderr (when it is a
    terminal), one step per truth set simulated and per (filter, set) tested.
    """
    from tqdm.auto import tqdm

    from gpsaccel.coop.filters import run_filter

    model = CoopModel() if model is None else model
    cases = [("LKF (tuned Q)", "lkf", None), ("EKF (tuned Q)", "ekf", None),
             ("UKF (tuned Q)", "ukf", None), ("EKF (Q = Qtrue)", "ekf", model.Qtrue),
             ("UKF (Q = Qtrue)", "ukf", model.Qtrue)]
    bar = tqdm(total=n_sets * (1 + len(cases)), desc="coop", unit="set", leave=False,
               disable=None if progress else True)
    with bar:
        truths = []
        for s in set_seeds(seed, n_sets):
            truths.append(truth_runs(model, n_runs, s))
            bar.update()
        sets: dict[str, list[ConsistencyRun]] = {}
        for label, m, Q in cases:
            bar.set_postfix_str(label)
            Qm = tuned_q(m, model) if Q is None else Q
            sets[label] = _tests(model, m, [(Qm, tr) for tr in truths], alpha)
            bar.update(len(truths))
    y = model.log()
    lines = [f"NEES/NIS over {n_sets} sets of {n_runs} truth runs (seed {seed}), alpha = {alpha:g}",
             format_sets(sets), "",
             f"{'filter':<22} {'Q diagonal':<44} {'log NIS avg':>11} {'one run (s)':>11}"]
    for label, m, Q in cases:
        Q = tuned_q(m, model) if Q is None else Q
        t0 = time.perf_counter()
        res = run_filter(m, model, y, Q)
        dt = time.perf_counter() - t0
        qd = ", ".join(f"{q:.3g}" for q in np.diag(Q))
        lines.append(f"{label:<22} {qd:<44} {res.nis()[1:].mean():11.2f} {dt:11.3f}")
    return "\n".join(lines)
