"""Where the course teaches each finding's fix: one table, keyed by code.

Every code a student can be shown — a checker's finding (:data:`gpsaccel.check.wording.STUDENT`,
the sandbox's outcomes, every catalogue's codes), a homework grader's, and every lesson
self-check's key (``"03.1"``, :mod:`gpsaccel.exercises`) — maps to the one section of a released
lesson that teaches what to do about it (and, where one practises it, an exercise of that
lesson).  The student's renderers add it to each finding (``gpsaccel check``, the feedback file, a
test cell's AssertionError, a self-check's ✗), the instructor's class summary counts codes with
it, and the docs link each code to the section on the rendered site (``docs/checker.md``, written
by ``python -m gpsaccel.lessons release``).

The table is data, on the package's ground floor, so the checker, the grader and the self-checks
read it without importing each other (and without reading a notebook): a section is named by its
lesson's file stem and its heading exactly as the lesson writes it.  ``tests/test_taught.py``
holds every code of every catalogue and wording table to an entry here, and every entry to a
heading that exists, once, in the released lessons.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

#: The lessons, by file stem (``lessons/NN-topic.ipynb``).
L00, L01, L02 = ("00-kalman-filter-from-nothing", "01-truth-and-sensors", "02-error-model")
L03, L04, L05 = ("03-multirate-filter", "04-monte-carlo-checks", "05-filter-forms")
L06, L07, L08 = ("06-what-the-reports-got-wrong", "07-gps-outage", "08-checking-your-filter")
L09, L09B = ("09-ship-multirate", "09b-ship-zeroed-gain-and-wind")
L10, L10B = ("10-coop-model-and-jacobians", "10b-coop-truth-and-lkf")
L11, L11B = ("11-coop-ekf-ukf-and-the-log", "11b-coop-the-course-log")
L12, L13, L14 = ("12-checking-coop-and-ship", "13-checking-any-linear-filter", "14-rts-smoothing")

_MATH = re.compile(r"\$[^$]*\$")
_NOT_SLUG = re.compile(r"[^\w\- ]")


@dataclass(frozen=True)
class Section:
    """A section of a released lesson: ``lesson`` its file stem, ``heading`` the heading's text
    (without the ``#``), ``exercise`` the number of that lesson's exercise that practises it
    ("" none)."""

    lesson: str
    heading: str
    exercise: str = ""

    @property
    def number(self) -> str:
        """The lesson's number as its file name starts: "06", "09b"."""
        return self.lesson.split("-", 1)[0]

    @property
    def notebook(self) -> str:
        return f"{self.lesson}.ipynb"

    @property
    def anchor(self) -> str:
        """The section's anchor on the rendered site (``_lessons/<lesson>.html#<anchor>``): MyST's
        GitHub-style slug of the heading's text (math left out, as MyST leaves it out)."""
        text = _MATH.sub("", self.heading).replace("`", "")
        return _NOT_SLUG.sub("", text.lower().replace(" ", "-"))

    def cite(self) -> str:
        """How a student's text names it: lesson 06, 'Report 003: …' (exercise 2)."""
        return (f"lesson {self.number}, '{self.heading}'"
                + (f" (exercise {self.exercise})" if self.exercise else ""))

    def to_dict(self) -> dict:
        return {"lesson": self.number, "notebook": self.notebook, "section": self.heading,
                "anchor": self.anchor, "exercise": self.exercise}


# ------------------------------------------------------------------------------ the sections
CART_SHRINKS = Section(L00, "Many measurements: the variance shrinks")
CART_DRIFTS = Section(L00, "A cart that drifts: the prediction step")
CALIBRATION = Section(L00, "The calibration problem: three states, two measurements")
FIRST_FIX = Section(L00, "The first GPS fix, by hand")
FORTY = Section(L00, "Forty predictions to the next fix")
LOOP = Section(L00, "The whole loop")
NUMBERS = Section(L01, "The problem, with report 001's numbers")
DRIFT = Section(L01, "The accelerometer alone drifts")
MEASURES = Section(L01, "The GPS and what the filter measures")
DERIVATION = Section(L02, "The derivation")
ON_A_RUN = Section(L02, "Checking the derivation on a run")
INTERVAL = Section(L02, "From one accelerometer step to one GPS interval")
ALGORITHM = Section(L03, "The algorithm: predict at 200 Hz, update at 5 Hz")
SLIDER_03 = Section(L03, "Slider: the filter's numbers")
STATISTICS = Section(L04, "The statistics")
FORMS = Section(L05, "Five ways to write one update")
COST = Section(L06, "The cost of every mistake")
M0_SWAPPED = Section(L06, "Report 001: position and velocity swapped in M0", "2")
SIGMA_VARIANCE = Section(L06, "Report 003: variances and standard deviations mixed up")
TOTAL_STATE = Section(L06, "Report 000: the estimate starts at the total-state means")
OUTAGE = Section(L07, "An outage after calibration: 20–25 s")
MATRICES = Section(L08, "Step 1: the matrices")
WHOLE_FILTER = Section(L08, "Step 2: the whole filter")
NEES = Section(L08, "The consistency test: NEES and its bounds", "2")
CHECK_AGAIN = Section(L08, "Step 3: fix and check again")
NOT_RUN = Section(L08, "Step 5: when the check cannot run your code")
VOYAGE = Section(L09, "One voyage, both filters")
GPS_RATE = Section(L09, "Slider: the GPS rate")
OPTIMAL_UPDATE = Section(L09B, "The optimal multirate update, by hand")
ZEROED = Section(L09B, "The report's multirate: full gain, then zero the GPS columns", "1")
SHIP_MONTE_CARLO = Section(L09B, "The Monte Carlo: RMSE and NEES of the four filters (and the "
                                 "report as written)")
COOP_MODEL = Section(L10, "The model")
JACOBIANS = Section(L10, "Jacobians, by hand, checked numerically")
COOP_TRUTH = Section(L10B, "The truth model")
EKF = Section(L11, "The EKF")
EKF_QTRUE = Section(L11, "The EKF with Q = Qtrue")
TUNING = Section(L11, "Tuning Q with NEES and NIS")
COURSE_LOG = Section(L11B, "The course's observation log (report figures 16–19)")
DT_MODEL = Section(L12, "Step 2: the DT model")
COOP_EKF_CHECK = Section(L12, "Step 3: the whole EKF")
INSTRUCTOR = Section(L13, "Step 1: the instructor's problem")
MISTAKEN = Section(L13, "Step 3: a mistaken filter")
SMOOTH_BIAS = Section(L14, "The bias: known at every instant as well as at the end")
SMOOTH_START = Section(L14, "Position and velocity: the start of the run")


def _each(section: Section, *codes: str) -> dict[str, Section]:
    return dict.fromkeys(codes, section)


#: code (or a lesson self-check's key, "NN.k") -> the section that teaches it.
TAUGHT: dict[str, Section] = {
    # ------------------------------------------------- the model: Φ, Γ, Q, H, V, W, M0
    **_each(CALIBRATION, "phi-transposed", "q-without-gamma", "state-order", "not-symmetric",
            "gamma-order", "joseph-sign"),
    "residual-covariance": FIRST_FIX,
    "prior-scale": NUMBERS,
    **_each(NUMBERS, "v-element", "m0-element", "w-value", "units"),
    "h-element": MEASURES,
    "phi-sign": Section(L02, "The derivation", "5"),
    **_each(DERIVATION, "phi-element", "gamma-sign", "gamma-element"),
    "process-noise-interval": Section(L02, "From one accelerometer step to one GPS interval", "3"),
    **_each(INTERVAL, "phi-interval", "gamma-interval", "q-element", "dt"),
    "std-as-variance": SIGMA_VARIANCE,
    "m0-order": M0_SWAPPED,
    **_each(TOTAL_STATE, "x0-total-state", "x0-wrong"),
    # ------------------------------------------------- the loop: what is updated, when
    **_each(FIRST_FIX, "first-update-skipped", "predict-before-first-update"),
    **_each(LOOP, "update-skipped", "covariance-update-skipped", "mean-update-skipped",
            "last-update-missing", "returns-a-priori", "epoch-shift", "mean-not-propagated",
            "measurement-late"),
    **_each(ALGORITHM, "update-every-step", "missing-propagation", "fixes-skipped"),
    "information-vector": FORMS,
    **_each(FORMS, "p-not-symmetric", "p-not-positive-definite", "p-scaled"),
    # ------------------------------------------------- the comparison and the consistency
    **_each(WHOLE_FILTER, "p-mismatch", "gain-or-residual", "filter-mismatch",
            "p-depends-on-data"),
    **_each(CHECK_AGAIN, "matches-optimal", "ok"),
    "matrix-value": MATRICES,
    **_each(NEES, "inconsistent", "consistent", "nees", "nees-sum", "nees-not-inverted",
            "nees-diagonal", "nees-per-state", "nees-value", "nees-bounds",
            "nees-bounds-one-run"),
    # ------------------------------------------------- the ship (report 004)
    **_each(VOYAGE, "no-input", "input-shift"),
    **_each(OPTIMAL_UPDATE, "missing-as-zero", "update-mismatch"),
    **_each(ZEROED, "zeroed-gain", "report-covariance", "sigma-value"),
    **_each(SHIP_MONTE_CARLO, "monorate-gain", "claimed-not-actual"),
    # ------------------------------------------------- cooperative localization (report 002)
    **_each(JACOBIANS, "jacobian-A", "jacobian-B", "jacobian-C", "jacobians-right",
            "jacobian-sign", "jacobian-blocks"),
    "omega-dt-gamma": COOP_TRUTH,
    **_each(DT_MODEL, "zero-order-hold", "dt-model-right", "uses-own-jacobian"),
    **_each(EKF, "no-angle-wrap", "no-state-wrap", "dt-linearization", "process-noise",
            "euler-propagation", "jacobian-point", "ekf-mismatch", "matches-reference"),
    "nees-nis": TUNING,
    # ------------------------------------------------- the file, the notebook and the sandbox
    **_each(NOT_RUN, "not-defined", "not-callable", "not-a-matrix", "not-a-number", "not-finite",
            "shape", "returns-none", "exception", "nothing-to-check", "nan-output",
            "aliased-output", "state-between-calls", "low-precision", "runner", "no-function",
            "no-kalman-filter", "no-file", "import-error", "return-value", "wrong-shape",
            "not-numeric", "returns-list", "returns-matrix", "filterpy-column", "prints-a-lot",
            "left-processes", "forked", "timeout", "memory-limit", "output-limit", "file-limit",
            "process-limit", "crashed", "uses-checker", "result-refused", "machine-busy",
            "not-found", "link-refused", "ambiguous-entry", "not-run", "grader-error",
            "checker-error"),
    # ------------------------------------------------- the lessons' self-checks
    "00.1": CART_SHRINKS, "00.2": FORTY, "00.3": CART_DRIFTS,
    "01.2": DRIFT,
    "02.3": INTERVAL, "02.4": ON_A_RUN,
    "03.1": SLIDER_03,
    "04.1": STATISTICS, "04.2": STATISTICS,
    "06.2": COST,
    "07.2": OUTAGE, "07.4": OUTAGE,
    "08.2": NEES,
    "09.1": GPS_RATE,
    "10.2": JACOBIANS, "10b.2": COOP_MODEL,
    "11.1": EKF_QTRUE, "11b.1": COURSE_LOG,
    "12.1": COOP_EKF_CHECK, "12.2": COOP_EKF_CHECK,
    "13.1": INSTRUCTOR, "13.2": MISTAKEN, "13.3": INSTRUCTOR,
    "14.1": SMOOTH_START, "14.2": SMOOTH_BIAS,
}


def taught(code: str) -> Section | None:
    """The section that teaches ``code`` (a finding's code or a self-check's key), or None."""
    return TAUGHT.get(code)


def class_lines(counts: Mapping[str, int], noun: str = "student") -> list[str]:
    """The instructor's summary of a class: one line per code, most frequent first, with where
    the course teaches it ("9 students: `phi-sign` → lesson 02, 'The derivation' (exercise 5)")."""
    lines = []
    for code, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        where = taught(code)
        lines.append(f"{n} {noun}{'' if n == 1 else 's'}: `{code}`"
                     + (f" → {where.cite()}" if where else " (no lesson teaches it yet)"))
    return lines
