r"""The Monte Carlo validation of the calibration filter, as the reports ran it, but as arrays.

Reports 000, 001 and 003 check their filter on an ensemble of N realizations (10,000; 5,000):

* the ensemble-mean error ``e_ave(t_i) = (1/N) Σ_l e^l(t_i)`` (should be ≈ 0), with
  ``e^l = x^l − x̂^l``;
* the sample error variance ``P_ave(t_i) = 1/(N − 1) Σ_l (e^l − e_ave)(e^l − e_ave)ᵀ`` (should be
  ≈ the filter's P(t_i));
* orthogonality ``(1/N) Σ_l (e^l − e_ave) x̂^lᵀ`` (should be ≈ 0);
* independence of the residuals ``(1/N) Σ_l r^l(t_i) r^l(t_m)ᵀ`` (≈ 0 for t_m ≠ t_i).

:func:`monte_carlo` computes exactly these statistics (and the ensemble NEES and NIS) and
:meth:`MonteCarloResult.consistency` says how far each is from theory in units of its own sampling
error (:mod:`gpsaccel.kalman.consistency`), with pass/fail at a stated family-wise false-alarm rate.

One job per module, in the order the engine runs them:

* :mod:`.planning`: :func:`plan`, what does not depend on the data, computed once: the gains
  and covariances (why the ensemble can be filtered as arrays), the truth's deterministic part (the kinematic
  truth of reports 001/003) and the filter's expected values;
* :mod:`.streams`: the random draws: the 200 Hz noise as one exact Gaussian per GPS interval,
  and the seeded blocks that make run l the same realization whatever the chunking;
* :mod:`.reduction`: the filter run on a block of realizations as arrays, reduced to mergeable
  sums (:class:`EnsembleSums`), and the engine's realizations themselves (:func:`realizations`);
* :mod:`.engine`: :func:`monte_carlo`: chunks to an executor, sums merged in order, the result;
* :mod:`.statistics`: :class:`MonteCarloResult`: the statistics, their standard errors and
  z-scores;
* :mod:`.verdicts`: what is printed of a result: the reports' numbers and the verdict table.

Every public name below is importable from this package as from the one module it was before
(``from gpsaccel.calibration.montecarlo import monte_carlo``).  The tunables of the draws,
:data:`~.streams.WHOLE_DRAW_BYTES` and :data:`~.streams.STREAM_EPOCHS`, are not re-exported: they
are read where they live, so set them on :mod:`.streams` (a copy here would be set in vain).  The
plan's module is ``planning``, not ``plan``: a module named like the function it exports would
hide one behind the other.
"""

from gpsaccel.calibration.montecarlo.engine import monte_carlo, whole_blocks
from gpsaccel.calibration.montecarlo.planning import (
    DEFAULT_MAX_LAG,
    EnsemblePlan,
    gps_interval_noise,
    plan,
)
from gpsaccel.calibration.montecarlo.reduction import EnsembleSums, Realizations, realizations
from gpsaccel.calibration.montecarlo.statistics import MonteCarloResult
from gpsaccel.calibration.montecarlo.streams import BLOCK_RUNS

__all__ = ["BLOCK_RUNS", "DEFAULT_MAX_LAG", "EnsemblePlan", "EnsembleSums", "MonteCarloResult",
           "Realizations", "gps_interval_noise", "monte_carlo", "plan", "realizations",
           "whole_blocks"]
