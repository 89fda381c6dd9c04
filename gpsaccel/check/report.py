"""What a checker returns: findings with stable codes, a pass/fail verdict and a readable text.

A :class:`Finding` is one thing the checker noticed.  Its ``code`` is stable (tests, graders and
the instructor's table key on it); its ``message`` is written for the student: what is wrong, what
it should be, the likely cause.  ``severity`` is ``"error"`` (the check fails), ``"warning"``
(worth reading, the check still passes) or ``"note"`` (information, e.g. the statistics of a
correct filter).  A :class:`Report` passes when it holds no error.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field

import numpy as np

SEVERITIES = ("error", "warning", "note")


@dataclass(frozen=True)
class Finding:
    """One observation of a checker.

    code : stable identifier, e.g. ``"phi-sign"``, ``"timeout"``, ``"nees"``.
    message : for the student: which element or result is wrong, what it should be, the likely
        cause.
    severity : ``"error"`` fails the check, ``"warning"`` and ``"note"`` do not.
    """

    code: str
    message: str
    severity: str = "error"

    def __post_init__(self) -> None:
        if self.severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, got {self.severity!r}")

    def __str__(self) -> str:
        return f"[{self.severity}] {self.code}: {self.message}"


@dataclass
class Report:
    """The result of one check.

    subject : what was checked (a file name, "model matrices").
    findings : every finding, errors first.
    details : the numbers behind the findings (JSON-serialisable), e.g. distances in units of σ.
    tables : preformatted text blocks shown under the findings (comparison, consistency).
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

    def add(self, code: str, message: str, severity: str = "error") -> Finding:
        finding = Finding(code, message, severity)
        self.findings.append(finding)
        return finding

    def sort(self) -> None:
        """Errors first, then warnings, then notes (stable within each)."""
        self.findings.sort(key=lambda f: SEVERITIES.index(f.severity))

    def to_dict(self) -> dict:
        """A JSON-serialisable summary (what ``gpsaccel check --json`` writes)."""
        return {"subject": self.subject, "passed": self.passed, "codes": self.codes,
                "findings": [asdict(f) for f in self.findings], "details": self.details,
                "seconds": round(self.seconds, 3)}

    def __str__(self) -> str:
        head = f"{self.subject}: {'PASSED' if self.passed else 'FAILED'}"
        if self.codes:
            head += f" ({', '.join(self.codes)})"
        lines = [head]
        for f in self.findings:
            first, *rest = str(f).split("\n")  # later lines (a traceback) are kept as they are
            lines.append(textwrap.fill(first, width=100, initial_indent="  - ",
                                       subsequent_indent="    ", break_on_hyphens=False))
            lines.extend("      " + line for line in rest)
        for table in self.tables:
            lines.append("")
            lines.append(textwrap.indent(table, "  "))
        return "\n".join(lines)


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
        report.add("not-a-matrix", words["not-a-matrix"].format(error=exc, **fields))
        return None
    if shape is not None and arr.shape != shape:
        report.add("shape", words["shape"].format(
            shape=arr.shape, want=shape, want_x=" x ".join(map(str, shape)),
            transposed=" (it looks transposed)" if arr.shape == shape[::-1] else "", **fields))
        return None
    if not np.isfinite(arr).all():
        report.add("not-finite", words["not-finite"].format(values=arr.tolist(), **fields))
        return None
    return arr
