r"""Check a student's whole filter: run it on simulated data, compare, diagnose, test consistency.

The student's file defines ``kalman_filter(z) -> (x_hat, P)`` for the report-000 problem: ``z`` is
the (n_gps, 2) array of GPS-minus-accelerometer measurements [δp, δv] (m, m/s), ``x_hat`` the
(n_gps, 3) a posteriori estimates of [δp, δv, b] and ``P`` the (n_gps, 3, 3) a posteriori
covariances, at the GPS times t = 0, 0.2, ..., 30 s.

What :func:`submission` does
----------------------------
The check is :class:`CalibrationProblem`, the linear pipeline of :mod:`gpsaccel.check.linear`
(also every instructor's linear problem) with report 000's simulation, catalogue
(:mod:`gpsaccel.calibration.mistakes`) and wording; the steps:

1. Simulates ``n_runs`` realizations from ``numpy.random.default_rng(seed)`` with the error-model
   truth (:func:`gpsaccel.simulate`), so it knows the true state of each.
2. Runs the student's file (or folder) in a sandbox (:mod:`gpsaccel.sandbox`: bwrap or
   basic, with time, memory, file, process and output limits), one call ``kalman_filter(z[r])``
   per run; a crash, an endless loop, wrong shapes, NaN, lists, a flood of prints, a broken limit,
   an import of gpsaccel each become a finding, never an exception here.
3. Only then, with every process of the student's gone, runs the optimal filter on the same data
   and compares P and x̂ with it.  Distances are in units of the
   optimal σ = √diag P_ref::

       d_P = max |P_ij − P_ref,ij| / (σ_i σ_j)     d_x = max |x̂_i − x̂_ref,i| / σ_i

   (max over runs, GPS times and elements).  The filter **passes** when both are at most
   :data:`TOLERANCE` = 1e-6 on every realization.  The problem has one optimal filter, so every
   correct form passes (covariance, information or Joseph update; filterpy or by hand; a filter
   that steps only at GPS times with Φ⁴⁰ and the 40-step process noise): they agree to ~1e-11 σ,
   while the smallest effect of a catalogued mistake (phi-sign on P) is 3e-4 σ.
4. Recognises mistakes in what is returned before anything else
   (:func:`_recognised_output_mistake`): ``aliased-output``, ``state-between-calls`` (naming the
   first wrong run), ``low-precision`` (float32), ``p-scaled``, ``epoch-shift``,
   ``last-update-missing``; each would otherwise read as a wrong M0, H or V.  Then diagnoses a
   failing filter against the catalogue (:mod:`gpsaccel.calibration.mistakes`): P does not
   depend on the data, so P is matched first against every covariance mistake and every
   combination of up to three that touch different ingredients; then x̂ against the matched
   entry with each combination of the mean mistakes.  A match (both within the tolerance) is
   reported under its code; a right P with a wrong x̂ that matches nothing is a gain or residual
   mistake; a P that matches nothing is located (t = 0 or the propagation, and the first element
   that departs), with the nearest catalogue entry as a hint only when it is within
   :data:`HINT_FACTOR` = 10 times the tolerance.
5. Tests consistency over the runs with the student's own P, to show what a mistake does:
   the ensemble-mean error (z = ē_i √N / √P_ii at every time and state) and the ensemble-average
   NEES (N·ε̄ ~ χ²(3N) at every time), each as a family of two-sided tests with a family-wise
   false-alarm rate ``alpha`` (Bonferroni over the times and states).  For a correct filter the
   two together raise a false alarm with probability at most 2·alpha.  These are reported as
   warnings (or notes when they hold): they never decide ``passed``, the comparison does.

Measured false alarms (200 runs per check): 140 checks of five correct forms on 140 seeds, all
passed (largest distances 1.9e-13 in P, 4.1e-11 in x̂); the consistency tests at alpha = 0.01
alarmed once in 540 correct checks (0.19 %; Bonferroni over correlated times is conservative).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from gpsaccel import sandbox as sb
from gpsaccel.calibration import mistakes as cat
from gpsaccel.calibration.model import STATE_NAMES, CalibrationModel
from gpsaccel.calibration.simulation import simulate
from gpsaccel.check.linear import (  # noqa: F401 - the calibration names of the linear pipeline
    COMBINED,
    HINT_FACTOR,
    LOW_PRECISION,
    TOLERANCE,
    Answer,
    CandidateFilters,
    Cases,
    LinearProblem,
    Mistake,
    answer,
    candidate_filters,
    candidates,
)
from gpsaccel.check.problem import Argument, Function
from gpsaccel.check.report import Report
from gpsaccel.problems import PROBLEM_TITLES
from gpsaccel.sandbox import Output

#: The function a submission defines.
FUNCTION = "kalman_filter"

#: Realizations per check.  The pass decision compares with the one optimal answer run by run, so
#: it needs few: measured with benchmarks/check_runs.py, every calibration fixture (6 correct forms,
#: 22 mistakes, sharper diagnoses included) gets exactly its expected codes on 3 seeds at n_runs =
#: 2, 3, 5 and 10 alike; only the informational consistency tests want more (at 10 their χ²(30)
#: average-NEES bounds are [1.6, 4.7]).  The same script times a check at each n_runs.
DEFAULT_RUNS = 10


# ---------------------------------------------------------------------------------- the data
@dataclass(frozen=True, eq=False)
class Data(Cases):
    """The realizations a check runs on (no answer in it), and the model they come from.

    z : (n_runs, n_gps, 2) measurements; x_true : (n_runs, n_gps, 3) true error states.
    """

    model: CalibrationModel = CalibrationModel()


def make_data(model: CalibrationModel, n_runs: int, seed: int) -> Data:
    rng = np.random.default_rng(seed)
    runs = [simulate(model, rng) for _ in range(n_runs)]
    return Data(seed, np.stack([r.z for r in runs]), np.stack([r.x_gps for r in runs]), model)


def with_answer(data: Data) -> Answer:
    """The optimal filter run on ``data`` (computed only once no student process is alive)."""
    return answer(cat.reference(data.model), data.z)


@lru_cache(maxsize=4)
def _default_data(n_runs: int, seed: int) -> Data:
    return make_data(CalibrationModel(), n_runs, seed)


@lru_cache(maxsize=8)
def _candidates(model: CalibrationModel, max_combined: int
                ) -> tuple[list[tuple[Mistake, ...]], np.ndarray]:
    """The catalogue's candidate filters and their covariances (:func:`linear.candidates`),
    cached per model object."""
    return candidates(cat.CalibrationCatalogue(model), max_combined)


#: Report 000's catalogue on the default model, one per process, shared by every check of the
#: default model (and by :func:`gpsaccel.calibration.mistakes.catalogue`): its mistakes are the
#: model's numbers (no data).
_default_catalogue = cat.default_catalogue


@lru_cache(maxsize=2)
def _default_candidate_filters(max_combined: int) -> CandidateFilters:
    """The default catalogue's candidate filters, built (never run) once per process
    (:meth:`CalibrationProblem.prepare`); kept by :func:`forget_answers`: they hold no answer."""
    return candidate_filters(_default_catalogue(), max_combined)


def forget_answers() -> None:
    """Drop every cached answer (the catalogue's covariances, the optimal P among them), so none
    is in this process's memory while a student's code runs."""
    _candidates.cache_clear()


def calls(z: np.ndarray) -> list[sb.Call]:
    """One sandbox call ``kalman_filter(z[r])`` per run, returning x̂ (n_gps, 3), P (n_gps, 3, 3)."""
    n_gps = z.shape[1]
    outputs = (sb.Output("x_hat", (n_gps, 3)), sb.Output("P", (n_gps, 3, 3)))
    return [sb.Call(FUNCTION, (z[r],), outputs) for r in range(z.shape[0])]


# ------------------------------------------------------------------------------- the problem
class CalibrationProblem(LinearProblem):
    """Report 000: ``kalman_filter(z) -> (x_hat, P)`` on the calibration model (module docstring).

    ``model`` (report 000's defaults when None), ``alpha`` (family-wise false-alarm rate of each
    consistency test) and ``tol`` (distance, units of the optimal σ, within which P and x̂ count
    as equal) are the check's.
    """

    name = "calibration"
    title = PROBLEM_TITLES["calibration"]
    tolerance = "1e-6 σ in x̂ and P (see gpsaccel.check.problems.calibration)"
    default_runs = DEFAULT_RUNS
    step = "accelerometer step"
    messages = cat.MESSAGES  # report 000's one table: its catalogue's and its checker's wording
    renames = {"no-function": "no-kalman-filter"}
    student = {"phi-sign": "A sign of Φ is wrong: look at how the accelerometer bias enters "
                           "position and velocity (the accelerometer reads a + b)."}

    def __init__(self, model: CalibrationModel | None = None, alpha: float = 0.01,
                 tol: float = TOLERANCE) -> None:
        super().__init__(alpha=alpha, tol=tol)
        if model is not None and not isinstance(model, CalibrationModel):
            raise ValueError(f"model must be a CalibrationModel, got {type(model).__name__}")
        self._model_given = model is not None
        self._catalogue: cat.CalibrationCatalogue | None = None
        self.model = model if model is not None else CalibrationModel()
        m = self.model
        self.t, self.states, self.every, self.n_steps = m.t_gps, STATE_NAMES, m.gps_every, \
            m.n_steps
        self.functions = (Function(FUNCTION, (Argument("z", (m.n_gps, 2), "GPS − integrated "
                                                       "accelerometer [δp (m), δv (m/s)] at t = 0, "
                                                       f"{m.t_gps[1]:g}, ..., {m.t_gps[-1]:g} s"),),
                                   (Output("x_hat", (m.n_gps, 3)), Output("P", (m.n_gps, 3, 3))),
                                   "the a posteriori [δp, δv, b] and P at every GPS time"),)

    def catalogue(self) -> cat.CalibrationCatalogue:
        if not self._model_given:
            return _default_catalogue()
        if self._catalogue is None:
            self._catalogue = cat.CalibrationCatalogue(self.model)
        return self._catalogue

    def codes(self) -> tuple[str, ...]:
        return self.catalogue().codes()

    def candidate_filters(self, max_combined: int = COMBINED) -> CandidateFilters:
        if self._model_given:
            return super().candidate_filters(max_combined)
        return _default_candidate_filters(max_combined)

    def simulate(self, n_runs: int, seed: int) -> Data:
        if self._model_given:
            return make_data(self.model, n_runs, seed)
        return _default_data(n_runs, seed)

    def answer(self, cases: Cases) -> Answer:
        return with_answer(cases)  # type: ignore[arg-type]

    def candidates(self, max_combined: int = 3) -> tuple[list[tuple[Mistake, ...]], np.ndarray]:
        return _candidates(self.model, max_combined)

    def forget(self) -> None:
        forget_answers()

    def message_fields(self, cases: Cases) -> dict[str, object]:
        t = self.t
        return {**super().message_fields(cases), "n_gps": self.model.n_gps,
                "rows": f"one row per GPS time t = {t[0]:g}, {t[1]:g}, ..., {t[-1]:g} s",
                "work": f"{self.n_steps} accelerometer steps per run should take well under a "
                        f"second"}


def submission(path: str | os.PathLike, n_runs: int = DEFAULT_RUNS, seed: int = 0,
               timeout: float = 60,
               model: CalibrationModel | None = None, alpha: float = 0.01,
               tol: float = TOLERANCE, sandbox: str = "auto", limits: sb.Limits | None = None,
               allow_gpsaccel: bool = False) -> Report:
    """Check the submission ``path`` that defines ``kalman_filter(z) -> (x_hat, P)``.

    Parameters
    ----------
    path : the student's ``.py`` file, or a folder (one student's) holding one file that defines
        kalman_filter and its helper modules and data files (:func:`sandbox.load_submission`).
    n_runs : realizations to run it on (≥ 2; :data:`DEFAULT_RUNS` = 10, see there).
    seed : seed of the realizations (``numpy.random.default_rng(seed)``).
    timeout : time limit (s) for the student's box (import and all runs), on the box's fair
        clock (:mod:`gpsaccel.sandbox.clock`).
    model, alpha, tol : those of :class:`CalibrationProblem`.
    sandbox : ``"auto"``, ``"bwrap"`` or ``"basic"`` (:mod:`gpsaccel.sandbox`).
    limits : the box's limits (:class:`sandbox.Limits`; its ``time`` is replaced by ``timeout``).
    allow_gpsaccel : let the submission import gpsaccel (e.g. for the model matrices).

    The optimal filter is run only after the box is empty: no process of the student's is alive
    while the answer is in memory.  Returns a :class:`~gpsaccel.check.report.Report`; it does not
    raise for anything the student's file does.  Arguments of the caller are validated
    (ValueError naming the argument).
    """
    return CalibrationProblem(model, alpha, tol).check(
        path, n_runs=n_runs, seed=seed, timeout=timeout, sandbox=sandbox, limits=limits,
        allow_gpsaccel=allow_gpsaccel)


def assert_submission(path: str | os.PathLike, **kwargs: object) -> Report:
    """:func:`submission` for a grader cell: raise AssertionError with the findings if it fails."""
    report = submission(path, **kwargs)  # type: ignore[arg-type]
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report


def _register() -> None:
    from gpsaccel import registry

    registry.add_problem("calibration", CalibrationProblem, system="calibration",
                         title=CalibrationProblem.title, replace=True)


_register()
