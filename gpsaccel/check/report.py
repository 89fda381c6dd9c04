"""What a checker returns: findings as data, a pass/fail verdict, and two renderers.

A :class:`Finding` is one thing the checker noticed, as data: a stable ``code`` (tests, graders and
the instructor's table key on it), ``where`` it shows (an element such as Φ₁₃, a time, a run),
``observed`` (the student's own values: what their code returned, printed or raised, and the
limits of the check) and ``expected`` (what it should have been), in separate fields.  Its
student text is a template (``text``, with ``{fields}``) that is formatted with ``where`` and
``observed`` only; ``detail`` is the instructor's prose, which may quote expected values
(``message`` is the instructor's whole text).

Two renderers, so that feedback never hands out an answer *by construction*:

* the student's (:meth:`Finding.for_student`, :meth:`Report.for_student`, ``str(report)``,
  :meth:`Report.to_dict`, and :func:`brief`, the first look of ``gpsaccel check FILE``): it works
  on a :class:`StudentFinding`, a projection that has no ``expected`` and no ``detail`` field, so
  nothing it prints can come from them;
* the instructor's (:meth:`Finding.for_instructor`, :meth:`Report.instructor_text`,
  ``to_dict(instructor=True)``), which shows the expected values too.

A finding made the old way (``add(code, message)``, prose only) keeps its prose for the
instructor; its student text is the code's template from :data:`gpsaccel.check.wording.STUDENT`
(or a plain sentence naming the code), never the prose.  No regular expression scrubs any text.

Every finding of a student's text says where the course teaches its fix: the lesson section of
its code (:mod:`gpsaccel._taught`), under each finding, a note's too, and in the JSON
(``taught``).

``severity`` is ``"error"`` (the check fails), ``"warning"`` (worth reading, the check still
passes) or ``"note"`` (information, e.g. the statistics of a correct filter).  A :class:`Report`
passes when it holds no error.  ``part`` names the part of a question a finding is about (partial
credit, :class:`gpsaccel.assignments.questions.Question`); "" concerns the whole question.
"""

from __future__ import annotations

import string
import textwrap
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gpsaccel._taught import Section, taught
from gpsaccel.check.wording import STUDENT, UNWORDED

SEVERITIES = ("error", "warning", "note")


def _jsonable(value: object) -> Any:
    """A JSON-serialisable copy of an observed value (arrays as lists, numpy scalars as numbers)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def fill(template: str, where: str, observed: Mapping[str, object]) -> str:
    """``template`` formatted with ``where`` and the ``observed`` fields only, or "" when it
    names any other field (an expected value, a typo): the caller then falls back to the code's
    own wording, never to anything else."""
    fields = {"where": where, **observed}
    try:
        return string.Formatter().vformat(template, (), fields)
    except (KeyError, IndexError, ValueError, TypeError, AttributeError):
        return ""


def used(template: str, fields: Mapping[str, object]) -> dict[str, object]:
    """The entries of ``fields`` that ``template`` names (what a finding keeps as observed)."""
    names = {name.split(".")[0].split("[")[0]
             for _, name, _, _ in string.Formatter().parse(template) if name}
    return {k: v for k, v in fields.items() if k in names}


@dataclass(frozen=True)
class StudentFinding:
    """What a student may see of a finding: no ``expected`` field, no instructor prose.

    message : the student text (the template filled with ``where`` and ``observed``).
    """

    code: str
    message: str
    severity: str
    where: str = ""
    observed: Mapping[str, object] = field(default_factory=dict)
    part: str = ""

    def __str__(self) -> str:
        return f"[{self.severity}] {self.code}: {self.message}"

    @property
    def taught(self) -> Section | None:
        """The lesson section that teaches this code's fix (None: no lesson names it)."""
        return taught(self.code)

    def see(self) -> str:
        """Where the course teaches the fix, as the student's text says it under the finding."""
        return see(self.code)

    def to_dict(self) -> dict:
        section = self.taught
        return {"code": self.code, "severity": self.severity, "message": self.message,
                "where": self.where, "observed": _jsonable(self.observed), "part": self.part,
                "taught": section.to_dict() if section else None}


def see(code: str) -> str:
    """The line under a finding of ``code``, whatever its severity (a note's section explains
    what it reports, as the JSON's ``taught`` says): the lesson section that teaches its fix, or
    "" for a code no lesson teaches."""
    section = taught(code)
    return f"→ {section.cite()}" if section else ""


@dataclass(frozen=True)
class Finding:
    """One observation of a checker (module docstring).

    code : stable identifier, e.g. ``"phi-sign"``, ``"timeout"``, ``"nees"``.
    detail : the instructor's prose (may quote expected values); "" when ``text`` says it all.
    severity : ``"error"`` fails the check, ``"warning"`` and ``"note"`` do not.
    text : the student template ({where} and the observed fields); "" for the code's own.
    where, observed, expected, part : see the module docstring.
    """

    code: str
    detail: str = ""
    severity: str = "error"
    text: str = ""
    where: str = ""
    observed: Mapping[str, object] = field(default_factory=dict)
    expected: Mapping[str, object] = field(default_factory=dict)
    part: str = ""

    def __post_init__(self) -> None:
        if self.severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, got {self.severity!r}")

    def for_student(self) -> StudentFinding:
        """The student's projection: the template filled from ``where`` and ``observed`` only."""
        template = self.text or STUDENT.get(self.code, "")
        text = fill(template, self.where, self.observed) if template else ""
        if not text:
            text = fill(STUDENT.get(self.code, ""), self.where, self.observed) or \
                UNWORDED.format(code=self.code)
        return StudentFinding(self.code, text, self.severity, self.where, dict(self.observed),
                              self.part)

    def for_instructor(self) -> str:
        """The instructor's text: the student's text, the instructor's prose and the expected
        values."""
        text = self.for_student().message if self.text else ""
        if self.detail:
            text += (" — for the instructor: " if text else "") + self.detail
        if self.expected:
            text += " [expected: " + ", ".join(f"{k} = {_short(v)}"
                                              for k, v in self.expected.items()) + "]"
        return text

    @property
    def message(self) -> str:
        """The instructor's whole text (:meth:`for_instructor`); a student reads
        :meth:`for_student`."""
        return self.for_instructor()

    def __str__(self) -> str:
        return str(self.for_student())


def _short(value: object) -> str:
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.6g}"
    if isinstance(value, np.ndarray):
        return np.array2string(value, precision=6, max_line_width=200)
    return str(value)


def no_verdict(passed: bool, codes: list[str]) -> bool:
    """A check that failed only for reasons that are ours, not the student's (the machine too busy
    to give the box its time, a lost box: :func:`gpsaccel.sandbox.outcomes.ours`): it says nothing
    about the code, so it reads "NO VERDICT", not "FAILED", and is to be run again."""
    from gpsaccel.sandbox.outcomes import ours

    return not passed and bool(codes) and all(ours(c) for c in codes)


def render(subject: str, passed: bool, codes: list[str], lines: list[str | tuple[str, str]],
           tables: list[str]) -> str:
    """The readable text of a report (one renderer for both audiences; each passes its lines, a
    line with what goes under it: where the course teaches the fix, :func:`see`)."""
    verdict = "PASSED" if passed else "NO VERDICT" if no_verdict(passed, codes) else "FAILED"
    head = f"{subject}: {verdict}"
    if codes:
        head += f" ({', '.join(codes)})"
    out = [head]
    for line in lines:
        text, under = (line, "") if isinstance(line, str) else line
        first, *rest = text.split("\n")  # later lines (a traceback) are kept as they are
        out.append(textwrap.fill(first, width=100, initial_indent="  - ",
                                 subsequent_indent="    ", break_on_hyphens=False))
        out.extend("      " + x for x in rest)
        if under:
            out.append(textwrap.fill(under, width=100, initial_indent="    ",
                                     subsequent_indent="      ", break_on_hyphens=False))
    for table in tables:
        out.append("")
        out.append(textwrap.indent(table, "  "))
    return "\n".join(out)


@dataclass
class StudentReport:
    """What a student may see of a report (:meth:`Report.for_student`)."""

    subject: str
    passed: bool
    codes: list[str]
    findings: list[StudentFinding]
    details: dict
    tables: list[str]
    seconds: float

    def to_dict(self) -> dict:
        return {"subject": self.subject, "passed": self.passed, "codes": self.codes,
                "findings": [f.to_dict() for f in self.findings], "details": self.details,
                "seconds": round(self.seconds, 3)}

    def __str__(self) -> str:
        return render(self.subject, self.passed, self.codes,
                      [(str(f), f.see()) for f in self.findings], self.tables)


_TB_INTRO = "; the traceback ends with:"


def first_line(message: str) -> str:
    """A finding's first line, for the first look and a graded notebook's feedback (one line a
    finding).  One that introduces the traceback below it (which neither shows) names the
    exception's type instead (the traceback's last line up to its message: ``raise
    NotImplementedError`` has none), or drops the clause."""
    first, _, rest = message.partition("\n")
    if not first.endswith(_TB_INTRO):
        return first
    last = rest.strip().splitlines()[-1].strip() if rest.strip() else ""
    kind = last.split(":", 1)[0]
    if len(kind) <= 80 and kind and all(part.isidentifier() for part in kind.split(".")):
        return f"{first[:-1]} {kind}."
    return first[:-len(_TB_INTRO)] + "."


def brief(result: Mapping) -> str:
    """The student's first look at one check (``gpsaccel check FILE`` without ``-v``): the verdict
    and each finding's first line — where and what — with the lesson section under each; no
    table.  ``result`` is a report's student dictionary
    (:meth:`StudentReport.to_dict`, which ``gpsaccel check`` receives from each check's process),
    so it holds no expected value to print."""
    lines: list[str | tuple[str, str]] = []
    for f in result.get("findings", []):
        severity, code = str(f.get("severity", "error")), str(f.get("code", ""))
        first = first_line(str(f.get("message", "")))
        lines.append((f"[{severity}] {code}: {first}", see(code)))
    return render(str(result.get("subject", "")), result.get("passed") is True,
                  [str(c) for c in result.get("codes", [])], lines, [])


@dataclass
class Report:
    """The result of one check.

    subject : what was checked (a file name, "model matrices").
    findings : every finding, errors first.
    details : the numbers behind the findings (JSON-serialisable), e.g. distances in units of σ;
        never an expected value (students see them).
    tables : preformatted text blocks shown under the findings (comparison, consistency);
        students see them: never an expected value.
    seconds : wall-clock time of the check (s).
    """

    subject: str
    findings: list[Finding] = field(default_factory=list)
    details: dict = field(default_factory=dict)
    tables: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        """True when no finding is an error."""
        return not any(f.severity == "error" for f in self.findings)

    @property
    def codes(self) -> list[str]:
        """Codes of the error findings, in order, without repeats."""
        return list(dict.fromkeys(f.code for f in self.findings if f.severity == "error"))

    def failed_parts(self) -> set[str]:
        """The parts with an error ("" : an error about the whole question)."""
        return {f.part for f in self.findings if f.severity == "error"}

    def add(self, code: str, message: str = "", severity: str = "error", *, text: str = "",
            where: str = "", observed: Mapping[str, object] | None = None,
            expected: Mapping[str, object] | None = None, part: str = "") -> Finding:
        """Add a finding (module docstring): ``text`` is the student template (``where`` and
        ``observed`` fill it), ``message`` the instructor's prose, ``expected`` what the
        answer should have been (the instructor's only)."""
        finding = Finding(code, message, severity, text, where, dict(observed or {}),
                          dict(expected or {}), part)
        self.findings.append(finding)
        return finding

    def tag(self, part: str) -> Report:
        """Every finding without a part becomes ``part``'s (a sub-check of one part)."""
        self.findings = [f if f.part else Finding(f.code, f.detail, f.severity, f.text, f.where,
                                                  f.observed, f.expected, part)
                         for f in self.findings]
        return self

    def sort(self) -> None:
        """Errors first, then warnings, then notes (stable within each)."""
        self.findings.sort(key=lambda f: SEVERITIES.index(f.severity))

    def for_student(self) -> StudentReport:
        """The student's projection of the report (no expected value, no instructor prose)."""
        return StudentReport(self.subject, self.passed, self.codes,
                             [f.for_student() for f in self.findings], dict(self.details),
                             list(self.tables), self.seconds)

    def to_dict(self, instructor: bool = False) -> dict:
        """A JSON-serialisable summary: the student's (what ``gpsaccel check --json`` writes),
        or with ``instructor`` the expected values and the instructor's prose too."""
        out = self.for_student().to_dict()
        if instructor:
            for d, f in zip(out["findings"], self.findings, strict=True):
                d["instructor"] = f.for_instructor()
                d["expected"] = _jsonable(f.expected)
        return out

    def instructor_text(self) -> str:
        """The instructor's readable report (expected values shown)."""
        return render(self.subject, self.passed, self.codes,
                      [(f"[{f.severity}] {f.code}: {f.for_instructor()}", see(f.code))
                       for f in self.findings], self.tables)

    def __str__(self) -> str:
        """The student's readable report (what a test cell and ``gpsaccel check`` print)."""
        return str(self.for_student())


#: The wording of :func:`as_array`'s findings (code -> template); a caller rewords any entry.
#: Fields: name, type (of the value), error (why np.array failed), shape (the value's), want and
#: want_x (the shape asked for, as a tuple and as "3 x 3"), transposed (" (it looks transposed)"
#: or ""), values (the value as a list), and the caller's own.
ARRAY_TEXT: dict[str, str] = {
    "not-a-matrix": "{name} must be an array of numbers; np.array({name}, dtype=float) fails: "
                    "{error}",
    "shape": "{name} has shape {shape}; it must be {want}.",
    "not-finite": "{name} contains NaN or inf.",
}


def as_array(report: Report, name: str, value: object, shape: tuple[int, ...] | None = None,
             text: Mapping[str, str] | None = None, **fields: object) -> np.ndarray | None:
    """A student's ``value`` as a finite float array (of ``shape`` when given), or None with a
    finding ``not-a-matrix`` (not numbers), ``shape`` or ``not-finite`` (NaN or inf), worded by
    :data:`ARRAY_TEXT` with ``text``'s entries instead.  Every checker of a student's matrices
    and answers reads them through this."""
    words = {**ARRAY_TEXT, **(text or {})}
    fields = {"name": name, "type": type(value).__name__, **fields}
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        report.add("not-a-matrix", text=words["not-a-matrix"], where=name,
                   observed={"error": str(exc), **fields})
        return None
    if shape is not None and arr.shape != shape:
        # the shape asked for is the contract's, stated in the question: not an answer
        report.add("shape", text=words["shape"], where=name, observed={
            "shape": arr.shape, "want": shape, "want_x": " x ".join(map(str, shape)),
            "transposed": " (it looks transposed)" if arr.shape == shape[::-1] else "",
            **fields})
        return None
    if not np.isfinite(arr).all():
        report.add("not-finite", text=words["not-finite"], where=name,
                   observed={"values": arr.tolist(), **fields})
        return None
    return arr
