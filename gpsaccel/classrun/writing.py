"""What a class run writes and shows: CSV, JSON, feedback files, the tables, the terminal.

One writer for ``gpsaccel check`` and ``gpsaccel grade``.  Everything a student controls passes
through :mod:`gpsaccel._untrusted` on the way out: a name is :func:`~gpsaccel._untrusted.shown`
(printable, NFC, bounded) before a table or a CSV holds it, a CSV text cell is guarded
(:func:`~gpsaccel._untrusted.cell`) so a spreadsheet does not evaluate it, a JSON file's
strings are encodable (:func:`~gpsaccel._untrusted.json_safe`), a feedback file's text is
:func:`~gpsaccel._untrusted.clean`.  Every file is written whole or not at all
(:mod:`gpsaccel._atomic`), except the ``.jsonl`` log, appended one line per result as each ends.

:class:`Terminal` is what the commands print through: a reader that goes away (``| head``, a
closed terminal) or a SIGPIPE never stops a run; the rest of the output is dropped and every
file is still written.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import signal
import sys
import threading
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TextIO

from gpsaccel import _untrusted
from gpsaccel._atomic import write_text
from gpsaccel.check.report import no_verdict
from gpsaccel.classrun import statuses

#: Longest submission name shown in the check's table (the JSON keeps it whole).
NAME_WIDTH = 80

#: The first columns of ``grades.csv`` (then one per question, total, possible, status, seconds).
HEADER = ("student", "id", "file")


# ------------------------------------------------------------------------------------ files
def csv_text(rows: Sequence[Sequence[object]]) -> str:
    """``rows`` as CSV text; the caller has passed each text cell a student or a roster controls
    through :func:`gpsaccel._untrusted.cell` (numbers it formatted itself stay as they are)."""
    buf = io.StringIO()
    csv.writer(buf).writerows(rows)
    return buf.getvalue()


def dump_json(path: str | os.PathLike, data: Any, indent: int | None = None,
              ascii: bool = True, mode: int | None = None) -> Path:
    """``data`` as JSON in ``path``, whole or not at all.  ``ascii`` (the default) escapes every
    character that is not ASCII: a name that was not UTF-8 (a lone surrogate of
    :func:`os.fsdecode`) is kept as it was found and read back the same (``grades.json`` names
    the notebooks the similarity report opens again), and no raw U+2028 or U+0085 splits a
    line.  Without it, pass :func:`~gpsaccel._untrusted.json_safe` data.  ``mode``: the file's
    permissions (:func:`gpsaccel._atomic.replacing`)."""
    return write_text(path, json.dumps(data, indent=indent, ensure_ascii=ascii), mode=mode)


#: The permissions of ``check --json``'s file and its log, and of ``grade``'s ``grading.json``:
#: the owner's alone.  Each holds the class's seed (drawn secret unless given), and a box of
#: ``--sandbox basic`` reads what other users may (their folders are hidden from it too).
PRIVATE = 0o600


def write_json(results: Sequence[dict], path: str | os.PathLike, **settings: object) -> Path:
    """``gpsaccel check --json``: ``{"settings": ..., "results": [...]}`` in ``path`` (UTF-8,
    indented), atomically, readable by its owner alone (:data:`PRIVATE`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return dump_json(path, _untrusted.json_safe({"settings": settings, "results": list(results)}),
                     indent=2, ascii=False, mode=PRIVATE)


def log_path(json_path: str | os.PathLike) -> Path:
    """Where results are appended as each check finishes: ``results.json`` -> ``results.jsonl``."""
    p = Path(json_path)
    return p.with_name(p.stem + ".jsonl")


def appender(path: str | os.PathLike) -> Callable[[dict], None]:
    """``on_result`` that appends each result as one JSON line to ``path`` (started empty,
    readable by its owner alone: :data:`PRIVATE`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, PRIVATE)
    try:
        os.fchmod(fd, PRIVATE)  # a log left by an earlier run keeps its mode through O_CREAT
    finally:
        os.close(fd)

    def append(result: dict) -> None:
        with open(path, "a", encoding="utf-8") as f:
            # ASCII: no raw U+2028/U+2029, U+0085 or other separator a line reader splits on
            f.write(json.dumps(_untrusted.json_safe(result), ensure_ascii=True) + "\n")
            f.flush()
            os.fsync(f.fileno())

    return append


def write_feedback(folder: Path, sid: str, text: str) -> Path:
    """``folder/<id>.txt``: a student's feedback, clean of control and bidi characters."""
    return write_text(folder / f"{sid}.txt", _untrusted.clean(text, newlines=True))


def write_grades(grades: Sequence, possible: dict[str, float], path: Path) -> None:
    """``grades.csv``: a header, a row of the points possible, one row per student
    (:class:`~gpsaccel.assignments.scoring.Grade` s); the points of a grade whose status is not
    a score (:func:`gpsaccel.classrun.statuses.scored`) left empty, its status said."""
    qs = list(possible)
    whole = f"{sum(possible.values()):g}"
    rows: list[list[object]] = [
        [*HEADER, *qs, "total", "possible", "status", "seconds", "late"],
        ["Points Possible", "", "", *(f"{possible[q]:g}" for q in qs), whole, whole, "", "",
         ""]]
    for g in grades:
        points = statuses.scored(g.status)
        rows.append([_untrusted.cell(g.student), _untrusted.cell(g.id),
                     _untrusted.cell(_untrusted.shown(g.file, 1000)),
                     *(f"{g.scores.get(q, 0):g}" if points else "" for q in qs),
                     f"{g.total:g}" if points else "", f"{g.max_total:g}", g.status,
                     f"{g.seconds:.1f}", "late" if getattr(g, "late", False) else ""])
    write_text(path, csv_text(rows))


def write_summary(rows: list[dict], grades: Sequence, out: Path) -> None:
    """``summary.csv`` (question, code, students, and the lesson section that teaches the code's
    fix: :mod:`gpsaccel._taught`) and ``summary.png`` (the same as bars)."""
    from gpsaccel._taught import taught

    table: list[list[object]] = [["question", "possible", "mean", "full marks", "students",
                                  "code", "count", "lesson", "section"]]
    for r in rows:
        base = [r["question"], f"{r['possible']:g}", f"{r['mean']:.3f}", r["full"],
                r["students"]]
        if not r["codes"]:
            table.append([*base, "", "", "", ""])
        for code, n in r["codes"].items():
            section = taught(code)
            table.append([*base, _untrusted.cell(code), n, section.number if section else "",
                          section.heading if section else ""])
    table.append([])
    for s, n in Counter(g.status for g in grades).most_common():
        table.append(["status", "", "", "", "", s, n])
    write_text(out / "summary.csv", csv_text(table))
    _figure(rows, out / "summary.png")


def _figure(rows: list[dict], path: Path) -> None:
    import matplotlib
    import matplotlib.ticker

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
        b.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))  # no 0.25 student
        b.set_title("mistake codes")
    else:
        b.axis("off")
    fig.tight_layout()
    savefig(fig, path, dpi=100)
    plt.close(fig)


# ----------------------------------------------------------------------------- what is missing
def _stamp(path: Path) -> tuple[int, int, int] | None:
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_dev, st.st_ino, st.st_mtime_ns


#: Why a file is missing that was named before it was written and not written since (the
#: writer declined, or the record could not be updated after it was written).
PENDING = "not written, or written after the record was last updated"


class Outputs:
    """The files a run writes into ``out``, each either written or named missing with why.

    A write the file system refuses (a full disk, a quota, a read-only folder: an
    :class:`OSError`) costs the files it did not write, never the run, the grades kept in memory
    or the outputs after it.  Every file is replaced whole (:mod:`gpsaccel._atomic`), so a file
    is written by a call exactly when its inode changed: a writer that stops half-way (the
    summary's CSV written, its figure not) names only what it did not write.  ``missing`` maps
    each file (relative to ``out``) to the file system's words; a file written later (the next
    flush, a rerun) leaves it."""

    def __init__(self, out: Path, missing: dict[str, str] | None = None) -> None:
        self.out = Path(out)
        self.missing: dict[str, str] = dict(missing or {})

    def write(self, files: Sequence[str], writer: Callable[..., Any], *args: Any,
              **kwargs: Any) -> Any:
        """``writer(*args, **kwargs)``, which writes ``files``; its value, or None when the
        file system refused a write (the files it did not write are then ``missing``)."""
        before = {f: _stamp(self.out / f) for f in files}
        value, why = None, None
        try:
            value = writer(*args, **kwargs)
        except OSError as exc:
            why = exc.strerror or type(exc).__name__
        for f in files:
            if _stamp(self.out / f) != before[f]:
                self.missing.pop(f, None)
            elif why is not None:
                self.missing[f] = why
        return value

    def pending(self, files: Sequence[str]) -> None:
        """Name ``files`` missing until a write replaces them: recorded before they are
        written, so a record that cannot be updated afterwards does not claim them, and a
        writer that declines to write one (the similarity report, saying why) leaves it
        named."""
        for f in files:
            self.missing.setdefault(f, PENDING)


def missing_lines(missing: dict[str, str], again: str) -> list[str]:
    """The terminal's lines on the files a run could not write (none when every one was):
    which, why, and how to write them once there is room (``again``: the command that rewrites
    the class-wide files from the recorded grades; a student's feedback needs that student
    graded again)."""
    if not missing:
        return []
    feedback = sorted(f for f in missing if f.startswith("feedback/"))
    files = [f for f in missing if f not in feedback]
    whys = sorted(set(missing.values()))
    lines = [f"NOT WRITTEN ({'; '.join(whys)}): {len(missing)} file(s), listed in grading.json's "
             f"'missing'"]
    if files:
        lines.append(f"  {', '.join(files)}: once there is room, {again}")
    if "grading.json" in missing:
        lines.append("  grading.json could not be updated: its 'missing' may name files "
                     "written since")
    if feedback:
        names = [f[len("feedback/"):-len(".txt")] for f in feedback]
        shown = ", ".join(names[:20]) + (f", and {len(names) - 20} more" if len(names) > 20
                                         else "")
        lines.append(f"  the feedback of {shown}: once there is room, grade each again with "
                     f"--student ID")
    return lines


# ----------------------------------------------------------------------------------- tables
def _shown_name(r: dict) -> str:
    return _untrusted.shown(str(r["details"].get("path", r["subject"])), NAME_WIDTH)


def table(results: Sequence[dict]) -> str:
    """The instructor's table of a class's check: submission, passed, seconds, codes (names and
    codes :func:`~gpsaccel._untrusted.shown`).  "again" where the check gave no verdict
    (:func:`~gpsaccel.check.report.no_verdict`): not the student's fail."""
    names = [_shown_name(r) for r in results]
    name_w = max([len(n) for n in names] + [10])
    head = f"{'submission':<{name_w}}  {'passed':<6}  {'seconds':>7}  codes"
    lines = [head, "-" * max(len(head), 40)]
    again = [r["passed"] is not True and no_verdict(False, list(r["codes"])) for r in results]
    for name, r, a in zip(names, results, again, strict=True):
        lines.append(f"{name:<{name_w}}  "
                     f"{'yes' if r['passed'] is True else 'again' if a else 'NO':<6}  "
                     f"{r['seconds']:7.1f}  {_untrusted.printable(', '.join(r['codes'])) or '-'}")
    n_pass = sum(r["passed"] is True for r in results)
    summary = f"{n_pass} of {len(results)} passed"
    if any(again):
        summary += (f"; {sum(again)} without a verdict (the machine or the checker, not the "
                    f"student's code: check them again)")
    lines.append(summary)
    return "\n".join(lines)


def reports(results: Sequence[dict]) -> str:
    """Every check's report in full (``gpsaccel check -v``), printable, a blank line after
    each."""
    return "".join(_untrusted.printable(r["text"], keep_newlines=True) + "\n\n"
                   for r in results)


def brief(result: dict, more: str) -> str:
    """One file's check as its student first reads it: each finding's line and the lesson that
    teaches its fix (:func:`gpsaccel.check.report.brief`), then ``more`` (what ``-v`` adds),
    printable."""
    import textwrap

    from gpsaccel.check.report import brief as first_look

    return (_untrusted.printable(first_look(result), keep_newlines=True) + "\n"
            + textwrap.fill(_untrusted.printable(more), width=100, break_on_hyphens=False,
                            break_long_words=False))


def check_mistakes(results: Sequence[dict]) -> list[str]:
    """Under a class's table: how many submissions made each mistake, and which lesson section
    teaches its fix (:func:`gpsaccel._taught.class_lines`); a check without a verdict (the
    machine's, :func:`gpsaccel.check.report.no_verdict`) made none."""
    from gpsaccel._taught import class_lines

    counts = Counter(str(c) for r in results if not no_verdict(False, list(r["codes"]))
                     for c in dict.fromkeys(r["codes"]))
    if not counts:
        return []
    return ["mistakes, and where the course teaches each:"] + [
        "  " + _untrusted.printable(line) for line in class_lines(counts, noun="submission")]


def grade_mistakes(grades: Sequence) -> list[str]:
    """Per question, how many students made each mistake and which lesson section teaches its
    fix (:func:`gpsaccel._taught.class_lines`; the same counts as ``summary.csv``)."""
    from gpsaccel._taught import class_lines

    lines = []
    for q in grades[0].possible if grades else ():
        counts = Counter(c for g in grades for c in dict.fromkeys(g.codes.get(q, [])))
        lines += [_untrusted.printable(f"{q}: {line}") for line in class_lines(counts)]
    return lines


def grades_table(grades: Sequence) -> str:
    """The instructor's table of a class's grades: student, total / possible ("-" where the
    status is not a score), status, seconds (each name as the grade shows it: printable)."""
    width = max([len(g.student) for g in grades] + [0])
    return "\n".join(f"{g.student:<{width}}  {statuses.cell(g.status, g.total) or '-':>5} / "
                     f"{g.max_total:g}  {g.status:<13} {g.seconds:5.1f} s" for g in grades)


# --------------------------------------------------------------------------------- terminal
class Terminal:
    """Standard output and error for a command's lines, which a reader that went away cannot
    stop: at the first ``BrokenPipeError`` the stream is pointed at ``/dev/null`` (what was
    still buffered for it is dropped too, and Python's own flush at exit finds nothing to
    complain about), and the run goes on to write every file.  Use :func:`terminal`."""

    def __init__(self) -> None:
        self.gone: set[str] = set()

    def out(self, text: str = "", end: str = "\n") -> None:
        self._write("stdout", text, end)

    def err(self, text: str) -> None:
        self._write("stderr", text, "\n")

    def _write(self, which: str, text: str, end: str) -> None:
        if which in self.gone:
            return
        stream: TextIO = getattr(sys, which)
        try:
            stream.write(text + end)
            if which == "stderr":
                stream.flush()
        except BrokenPipeError:
            self._drop(which)

    def flush(self) -> None:
        for which in ("stdout", "stderr"):
            try:
                getattr(sys, which).flush()
            except BrokenPipeError:
                self._drop(which)

    def _drop(self, which: str) -> None:
        self.gone.add(which)
        stream = getattr(sys, which)
        with contextlib.suppress(OSError, ValueError, AttributeError):
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, stream.fileno())
            os.close(null)
        with contextlib.suppress(BrokenPipeError, OSError, ValueError):
            stream.flush()  # the buffered rest goes to /dev/null


@contextlib.contextmanager
def terminal() -> Iterator[Terminal]:
    """A :class:`Terminal` for a command's body; SIGPIPE ignored meanwhile (a closed pipe is an
    error to handle, never a signal that ends the run half-way), everything flushed at the
    end."""
    term = Terminal()
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGPIPE, signal.SIG_IGN) if main else None
    try:
        yield term
    finally:
        term.flush()
        if previous is not None:
            signal.signal(signal.SIGPIPE, previous)
