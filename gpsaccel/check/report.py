"""What a checker returns: findings with stable codes, a pass/fail verdict and a readable text.

A :class:`Finding` is one thing the checker noticed.  Its ``code`` is stable (tests, graders and
the instructor's table key on it); its ``message`` is written for the student: what is wrong, what
it should be, the likely cause.  ``severity`` is ``"error"`` (the check fails), ``"warning"``
(worth reading, the check still passes) or ``"note"`` (information, e.g. the statistics of a
correct filter).  A :class:`Report` passes when it holds no error.
"""

from __future__ import annotations

import textwrap
from dataclasses import asdict, dataclass, field

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
