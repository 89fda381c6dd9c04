"""What grading a class writes: ``grades.csv`` and ``grades.json`` after every notebook, the
feedback files, ``summary.csv``/``summary.png`` and the run's record ``grading.json`` (the output
of :func:`gpsaccel.assignments.grading.grade`, module docstring there)."""

from __future__ import annotations

import csv
import io
import json
import math
import time
from collections import Counter
from dataclasses import asdict
from pathlib import Path

import numpy as np

from gpsaccel import _untrusted
from gpsaccel._atomic import write_text
from gpsaccel.assignments.scoring import Grade
from gpsaccel.assignments.submissions import Entry


def _cell(value: str) -> str:
    """A CSV text cell a spreadsheet will not evaluate (=, +, -, @ lead a formula)."""
    return "'" + value if value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


HEADER = ("student", "id", "file")


def write_csv(grades: list[Grade], possible: dict[str, float], path: Path) -> None:
    """``grades.csv``: a header, a row of the points possible, one row per student."""
    buf = io.StringIO()
    w = csv.writer(buf)
    qs = list(possible)
    w.writerow([*HEADER, *qs, "total", "possible", "status", "seconds"])
    w.writerow(["Points Possible", "", "", *(f"{possible[q]:g}" for q in qs),
                f"{sum(possible.values()):g}", f"{sum(possible.values()):g}", "", ""])
    for g in grades:
        w.writerow([_cell(g.student), _cell(g.id), _cell(_untrusted.shown(g.file, 1000)),
                    *(f"{g.scores.get(q, 0):g}" for q in qs),
                    f"{g.total:g}", f"{g.max_total:g}", g.status, f"{g.seconds:.1f}"])
    write_text(path, buf.getvalue())


def summary(grades: list[Grade], possible: dict[str, float]) -> list[dict]:
    """Per question: mean score, its possible, and how many students got each mistake code."""
    out = []
    for q, pts in possible.items():
        scored = [g.scores.get(q, 0.0) for g in grades]
        codes = Counter(c for g in grades for c in dict.fromkeys(g.codes.get(q, [])))
        out.append({"question": q, "possible": pts, "mean": float(np.mean(scored)) if scored
                    else math.nan, "full": sum(s >= pts for s in scored), "students":
                    len(scored), "codes": dict(codes.most_common())})
    return out


def write_summary(rows: list[dict], grades: list[Grade], out: Path) -> None:
    """``summary.csv`` (question, code, students, and the lesson section that teaches the code's
    fix: :mod:`gpsaccel._taught`) and ``summary.png`` (the same as bars)."""
    from gpsaccel._taught import taught

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["question", "possible", "mean", "full marks", "students", "code", "count",
                "lesson", "section"])
    for r in rows:
        base = [r["question"], f"{r['possible']:g}", f"{r['mean']:.3f}", r["full"],
                r["students"]]
        if not r["codes"]:
            w.writerow([*base, "", "", "", ""])
        for code, n in r["codes"].items():
            section = taught(code)
            w.writerow([*base, _cell(code), n, section.number if section else "",
                        section.heading if section else ""])
    statuses = Counter(g.status for g in grades)
    w.writerow([])
    for s, n in statuses.most_common():
        w.writerow(["status", "", "", "", "", s, n])
    write_text(out / "summary.csv", buf.getvalue())
    _figure(rows, out / "summary.png")


def _figure(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gpsaccel._atomic import savefig

    codes = [(f"{r['question']}: {c}", n) for r in rows for c, n in r["codes"].items()]
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, max(3.0, 0.3 * len(codes) + 1.5)))
    names = [r["question"] for r in rows]
    a.bar(names, [r["mean"] / r["possible"] if r["possible"] else 0 for r in rows])
    a.set_ylim(0, 1)
    a.set_ylabel("mean score / points possible")
    a.set_title(f"{rows[0]['students'] if rows else 0} students")
    if codes:
        b.barh([c for c, _ in codes][::-1], [n for _, n in codes][::-1])
        b.set_xlabel("students")
        b.set_title("mistake codes")
    else:
        b.axis("off")
    fig.tight_layout()
    savefig(fig, path, dpi=100)
    plt.close(fig)


class _Log:
    """What a run writes, each file whole (:mod:`gpsaccel._atomic`), after every notebook.

    ``grades.csv`` (and ``grades.json``, the same rows with their codes) always hold a row for
    every student: a full run starts them ``not-graded``; a regrade (``student``) keeps the
    student's old row until the new one is written.  ``grading.json`` holds the class record;
    a regrade appends itself to its ``regrades``."""

    def __init__(self, out: Path, possible: dict[str, float], student: str | None,
                 progress: bool = False) -> None:
        self.out, self.possible, self.student, self.progress = out, possible, student, progress
        self.record = out / "grading.json"
        self.kept_path = out / "grades.json"
        self.feedback = out / "feedback"
        self.previous = self._json(self.record, {})
        self.old = [Grade(**d) for d in self._json(self.kept_path, [])] if student else []
        for g in self.old:  # a row of an earlier version, without its id
            g.id = g.id or _untrusted.student_id(g.student)
        self.entries: list[Entry] = []
        self.grades: list[Grade | None] = []
        self.t0 = time.perf_counter()

    @staticmethod
    def _json(path: Path, default):  # noqa: ANN001, ANN205 - a dict or a list
        return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else default

    def start(self, entries: list[Entry], info: dict) -> None:
        from tqdm.auto import tqdm

        self.bar = tqdm(total=len(entries), desc=info["assignment"], unit="notebook",
                        leave=False, disable=None if self.progress else True)
        self.entries, self.grades = entries, [None] * len(entries)
        self.feedback.mkdir(exist_ok=True)
        if self.student is None or not isinstance(self.previous, dict) or not self.previous:
            self.info = {**info, "regrades": []}
        else:  # the class record stays; the regrade is appended to it
            self.info = self.previous
            self.info.setdefault("regrades", []).append(
                {k: info[k] for k in ("student", "seed", "started")})
        write_text(self.record, json.dumps(self.info, indent=2))
        if self.student is None:  # a full run: the feedback of students no longer there is stale
            keep = {f"{e.id}.txt" for e in entries}
            for f in self.feedback.glob("*.txt"):
                if f.name not in keep:
                    f.unlink()
        self.flush()

    def rows(self) -> list[Grade]:
        now = [g for g in self.grades if g is not None]
        if self.student is None:
            missing = [Grade(e.shown, "", {q: 0.0 for q in self.possible}, self.possible,
                             "not-graded", id=e.id)
                       for e, g in zip(self.entries, self.grades, strict=True) if g is None]
            return sorted(now + missing, key=lambda g: (g.student.lower(), g.id))
        new = {g.id for g in now}
        kept = [g for g in self.old if g.id not in new]
        return sorted(kept + now, key=lambda g: (g.student.lower(), g.id))

    def flush(self) -> None:
        current = self.rows()
        write_csv(current, self.possible, self.out / "grades.csv")
        write_text(self.kept_path, json.dumps([{**asdict(x), "feedback": ""} for x in current]))

    def done(self, i: int, data: dict) -> None:
        g = Grade(**data)
        g.student = _untrusted.clean(g.student)
        g.feedback = _untrusted.clean(g.feedback, newlines=True)
        self.bar.set_postfix_str(f"{g.student[:40]}: {g.status}")
        self.bar.update()
        write_text(self.feedback / f"{self.entries[i].id}.txt", g.feedback)
        self.grades[i] = g
        self.flush()

    def finish(self, interrupted: bool) -> None:
        self.bar.close()
        self.flush()
        final = self.rows()
        if not interrupted:
            write_summary(summary(final, self.possible), final, self.out)
        entry = self.info["regrades"][-1] if self.student is not None and \
            self.info.get("regrades") else self.info
        entry["seconds"] = round(time.perf_counter() - self.t0, 1)
        entry["graded"] = sum(g is not None for g in self.grades)
        entry["interrupted"] = interrupted
        write_text(self.record, json.dumps(self.info, indent=2))
