"""The calibration homework's graded questions (instructor side: in the repository, not the wheel).

q1 reads the matrices (values) and checks them for the student's accelerometer rate (variant);
q2 is the file ``kalman_filter.py`` the notebook writes, checked by :func:`gpsaccel.check.submission`
on fresh realizations in a box without gpsaccel; q3 calls ``average_nees`` and ``nees_bounds`` on a
fresh consistent ensemble.  See :mod:`gpsaccel.assignments.questions`.
"""

from __future__ import annotations

import numpy as np

from gpsaccel.assignments._answers import call
from gpsaccel.assignments.calibration import nees_answer, nees_data, rate_model
from gpsaccel.check.report import Report

# ----------------------------------------------------------------------- graded questions
#: Accelerometer rates (Hz) of the per-student variant of question 1: every multiple of 5 Hz
#: (so the 5 Hz GPS falls on an accelerometer step) from 10 Hz to 10 kHz, 1999 rates.  Only Δt
#: enters question 1's matrices (V, W, M0 stay report 000's: the checker's hints name those
#: numbers); 200 students share a rate in about 10 pairs (docs/grading.md).
RATES_HZ = tuple(5 * k for k in range(2, 2001))

#: The public notebook's variant (report 000's numbers): never a student's.
DEFAULT_VARIANT = {"rate_hz": 200}


def variant(number: int) -> dict:
    """The student's numbers: the accelerometer rate of question 1 (never the public 200 Hz)."""
    from gpsaccel.assignments.variants import pick

    return pick(number, {"rate_hz": RATES_HZ}, DEFAULT_VARIANT)


_MATRICES = {"Phi": (3, 3), "Gamma": (3, 1), "H": (2, 3), "V": (2, 2), "W": (1, 1), "M0": (3, 3)}


def _q1_reads(draw):
    from gpsaccel.assignments.notebook import Read

    return [Read(name, (), (shape,), value=True) for name, shape in _MATRICES.items()]


def _q1_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import value
    from gpsaccel.check import model_matrices

    report = Report("question 1: model matrices")
    given = {name: value(report, name, a, name)
             for name, a in zip(_MATRICES, answers, strict=True)}
    if all(v is None for v in given.values()):
        return report
    rate = draw.variant["rate_hz"]
    checked = model_matrices(**{k: v for k, v in given.items() if v is not None},
                             dt=1.0 / rate, model=rate_model(rate))
    checked.findings = report.findings + [_matrix_part(f) for f in checked.findings]
    checked.sort()
    return checked


#: The first symbol of a finding's place (Φ₁₃, V₂₂, M0) -> the matrix it is about (q1's part).
_SYMBOLS = {"Φ": "Phi", "P": "Phi", "Γ": "Gamma", "G": "Gamma", "H": "H", "V": "V", "W": "W",
            "M": "M0"}


def _matrix_part(f):
    """The finding about one matrix as that matrix's part (partial credit); one the checker
    places nowhere (dt, ok) stays the whole question's."""
    from dataclasses import replace

    part = _SYMBOLS.get(f.where[:1], "") if f.where else ""
    return replace(f, part=part) if part and not f.part else f


def _q2_grade(path, draw, timeout: float) -> Report:
    from gpsaccel.check import submission

    return submission(path, n_runs=10, seed=draw.seed % 2**32, timeout=timeout)



def _q3_draw(draw):
    rng = draw.rng()
    N = int(rng.integers(20, 61))
    return N, nees_data(rng, N)


def _q3_reads(draw):
    from gpsaccel.assignments.notebook import Read

    N, (x_true, x_hat, P) = _q3_draw(draw)
    return [Read("average_nees", (x_true, x_hat, P), ((),)),
            Read("nees_bounds", (np.array(N),), ((2,),))]


def _q3_grade(draw, answers) -> Report:
    from gpsaccel.assignments.questions import replay

    N, (x_true, x_hat, P) = _q3_draw(draw)
    reads = _q3_reads(draw)
    report = Report("question 3: NEES")
    out = {}
    for name, args in (("average_nees", (x_true, x_hat, P)), ("nees_bounds", (np.array(N),))):
        fn = replay(reads, answers, name)
        out[name] = call(report, f"{name}(...)", fn, *args, part=name)
    if report.passed:
        return nees_answer(out["average_nees"], out["nees_bounds"], N, x_true, x_hat, P)
    # one function failed to answer: the other is still checked, for its own part
    both = nees_answer(out["average_nees"], out["nees_bounds"], N, x_true, x_hat, P)
    report.findings += [f for f in both.findings
                        if f.part not in report.failed_parts() and f.severity == "error"]
    report.sort()
    return report


def warm() -> None:
    """Imported once in the class's parent (:func:`gpsaccel.assignments.grading.warm`), not in
    every notebook's process: scipy.stats, whose χ² quantiles are q3's bounds (its price a
    notebook: benchmarks/imports.py), and the modules q1 and the variants use.  Modules only:
    nothing is computed."""
    import scipy.stats  # noqa: F401

    import gpsaccel.assignments.variants  # noqa: F401
    import gpsaccel.check.matrices  # noqa: F401

def graded_questions():
    """The calibration homework's graded questions (:mod:`gpsaccel.assignments.questions`)."""
    from gpsaccel.assignments.questions import Question

    return (Question("q1", 3, _q1_reads, _q1_grade,
                     parts=tuple((name, 0.5) for name in _MATRICES)),
            Question("q2", 4, file="kalman_filter.py", grade_file=_q2_grade),
            Question("q3", 3, _q3_reads, _q3_grade,
                     parts=(("average_nees", 1.5), ("nees_bounds", 1.5))))
