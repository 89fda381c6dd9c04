"""Grade a class: ``otter run`` on every submitted notebook, in parallel, one isolated job each.

:func:`grade` takes a folder of submissions (``*.ipynb``, one per student, named as the instructor
likes) and writes into ``out``:

* ``grades.csv``: one row per submission — the file, one column per question, total, possible,
  status (``graded``, ``timeout``, ``error``) and seconds;
* ``feedback/NAME.txt``: per question the score and the tests' messages (the checkers' findings,
  with their codes), or why the notebook could not be graded.

Each notebook runs in its own isolated job (:func:`gpsaccel.assignments.isolation.run_isolated`):
a notebook that crashes, loops or attacks its process loses its own grade only.  What comes back
is untrusted: ``results.json`` is read as data (size-capped JSON, never a pickle), only the
questions of the master count, and each score is clipped to [0, the master's points].  Note that
otter runs the tests inside the student's kernel: a hostile notebook can still forge its *own*
result (as on Gradescope), not anyone else's.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import shutil
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from gpsaccel.assignments.isolation import run_isolated

#: Largest results.json read (bytes).
MAX_RESULTS_BYTES = 5 * 2**20

#: Wall-clock limit per notebook (s), default.
TIMEOUT = 600

STATUSES = ("graded", "timeout", "error")


@dataclass
class Grade:
    """One submission's grade.

    submission : the notebook's file name; scores : question -> points earned (0 when missing);
    possible : question -> points available (from the master); status : ``graded``, ``timeout``
    or ``error``; feedback : the text written to ``feedback/``; seconds : wall time of its job.
    """

    submission: str
    scores: dict[str, float]
    possible: dict[str, float]
    status: str
    feedback: str
    seconds: float
    outputs: dict[str, str] = field(default_factory=dict)

    @property
    def total(self) -> float:
        return sum(self.scores.values())

    @property
    def max_total(self) -> float:
        return sum(self.possible.values())


def _safe_name(name: str) -> str:
    """A file name that cannot leave the folder or start a spreadsheet formula."""
    stem = re.sub(r"[^\w.\-]+", "_", Path(name).stem).lstrip(".=+-@") or "submission"
    return stem[:100]


def _cell(value: str) -> str:
    """A CSV text cell that a spreadsheet will not evaluate (=, +, -, @ lead a formula)."""
    return "'" + value if value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


def parse_results(text: str, possible: dict[str, float]) -> tuple[dict[str, float],
                                                                  dict[str, str]]:
    """Scores and test output per question from otter's results.json text (untrusted).

    Only the master's questions count; a score that is missing, not a finite number, or out of
    [0, points] is clipped (a question absent from the results scores 0).
    """
    data = json.loads(text)
    scores = {q: 0.0 for q in possible}
    outputs = {q: "" for q in possible}
    tests = data.get("tests", []) if isinstance(data, dict) else []
    for test in tests if isinstance(tests, list) else []:
        if not isinstance(test, dict) or test.get("name") not in possible:
            continue
        q = test["name"]
        score = test.get("score")
        if isinstance(score, (int, float)) and not isinstance(score, bool) and math.isfinite(score):
            scores[q] = min(max(float(score), 0.0), possible[q])
        out = test.get("output")
        outputs[q] = out[:20_000] if isinstance(out, str) else ""
    return scores, outputs


def _feedback(grade: Grade, output_tail: str) -> str:
    lines = [f"{grade.submission}: {grade.total:g} / {grade.max_total:g} points "
             f"({grade.status})", ""]
    if grade.status == "timeout":
        lines += ["The notebook did not finish within the time limit; nothing after that was "
                  "graded. Look for a loop that never ends or a very slow cell.", ""]
    elif grade.status == "error":
        lines += ["The notebook could not be graded (no results came back). The grader's last "
                  "output:", "", output_tail[-3000:], ""]
    for q, points in grade.possible.items():
        lines.append(f"{q}: {grade.scores[q]:g} / {points:g}")
        text = grade.outputs.get(q, "").strip()
        if text:
            lines += ["    " + line for line in text.splitlines()]
        lines.append("")
    return "\n".join(lines)


def grade_one(submission: Path, autograder: Path, possible: dict[str, float],
              timeout: float = TIMEOUT) -> Grade:
    """Grade one notebook with ``otter run`` in an isolated job; never raises for its content."""
    submission = Path(submission)
    with tempfile.TemporaryDirectory(prefix="gpsaccel-grade-") as tmp:
        tmp = Path(tmp)
        job = tmp / "job"
        results = job / "results"
        results.mkdir(parents=True)
        # the notebook's own name is not trusted either: otter gets a fixed one
        nb = job / "submission.ipynb"
        try:
            shutil.copyfile(submission, nb)
        except OSError as exc:
            grade = Grade(submission.name, {q: 0.0 for q in possible}, possible, "error", "", 0.0)
            grade.feedback = _feedback(grade, f"cannot read {submission.name}: {exc}")
            return grade
        cmd = [sys.executable, "-m", "otter", "run", "--no-logo", "-a", str(autograder.resolve()),
               "-o", str(results), str(nb)]
        job_result = run_isolated(cmd, job, timeout)
        status, scores, outputs = "error", {q: 0.0 for q in possible}, {}
        path = results / "results.json"
        if job_result.timed_out:
            status = "timeout"
        elif path.is_file() and path.stat().st_size <= MAX_RESULTS_BYTES:
            try:
                scores, outputs = parse_results(path.read_text(encoding="utf-8"), possible)
                status = "graded"
            except (ValueError, UnicodeDecodeError):
                status = "error"
    grade = Grade(submission.name, scores, possible, status, "", job_result.seconds, outputs)
    grade.feedback = _feedback(grade, job_result.output)
    return grade


def write_csv(grades: list[Grade], path: Path) -> None:
    """``grades.csv``: submission, one column per question, total, possible, status, seconds."""
    questions = list(grades[0].possible) if grades else []
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["submission", *questions, "total", "possible", "status", "seconds"])
        for g in grades:
            w.writerow([_cell(g.submission), *(f"{g.scores[q]:g}" for q in questions),
                        f"{g.total:g}", f"{g.max_total:g}", g.status, f"{g.seconds:.1f}"])


def grade(submissions: Path | str, name: str, out: Path | str | None = None,
          autograder: Path | str | None = None, jobs: int | None = None,
          timeout: float = TIMEOUT) -> list[Grade]:
    """Grade every ``*.ipynb`` in ``submissions`` for homework ``name``; write CSV and feedback.

    autograder : the zip from :func:`~gpsaccel.assignments.generate.generate`; None generates it
        from the master (``otter assign`` without running its tests).
    out : where ``grades.csv`` and ``feedback/`` go (default ``submissions/grades``).
    jobs : notebooks graded at once (default: the number of CPUs, at most 4).
    timeout : wall-clock limit (s) per notebook.
    """
    from gpsaccel.assignments.generate import generate, master_notebook, questions

    submissions = Path(submissions)
    if not submissions.is_dir():
        raise ValueError(f"submissions must be a folder of notebooks, got {submissions}")
    if timeout <= 0 or not math.isfinite(timeout):
        raise ValueError(f"timeout must be a positive number of seconds, got {timeout!r}")
    jobs = min(4, os.cpu_count() or 1) if jobs is None else int(jobs)
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    possible = questions(master_notebook(name))
    out = Path(out) if out is not None else submissions / "grades"
    notebooks = sorted(p for p in submissions.glob("*.ipynb") if p.is_file())
    with tempfile.TemporaryDirectory(prefix="gpsaccel-autograder-") as tmp:
        if autograder is None:
            autograder = generate(name, Path(tmp) / "dist", run_tests=False).autograder
        autograder = Path(autograder)
        if not autograder.is_file():
            raise ValueError(f"autograder must be the zip written by `gpsaccel assignment`, "
                             f"got {autograder}")
        t0 = time.perf_counter()
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            grades = list(pool.map(lambda p: grade_one(p, autograder, possible, timeout),
                                   notebooks))
        elapsed = time.perf_counter() - t0
    feedback = out / "feedback"
    feedback.mkdir(parents=True, exist_ok=True)
    used: set[str] = set()
    for g in grades:
        stem = _safe_name(g.submission)
        while stem in used:
            stem += "_"
        used.add(stem)
        (feedback / f"{stem}.txt").write_text(g.feedback, encoding="utf-8")
    write_csv(grades, out / "grades.csv")
    (out / "summary.txt").write_text(
        f"{len(grades)} notebooks graded in {elapsed:.1f} s with {jobs} jobs\n", encoding="utf-8")
    return grades
