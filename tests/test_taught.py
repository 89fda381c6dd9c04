"""Every code a student can be shown points to a section of the released lessons that teaches it
(:mod:`gpsaccel._taught`).

The codes are read from every table that holds them — the student's wording
(:data:`gpsaccel.check.wording.STUDENT`), the linear checker's and the box's templates, the
sandbox's outcomes and its submission errors, each registered problem's catalogue and renames,
each system's message table (``code``, ``code.variant``, ``homework.code``, ``update.code``) —
and the self-checks' keys from the lessons' masters and the recorded answers.  A code missing from
the table is a gap in the lessons, and the test names it.
"""

from __future__ import annotations

import importlib
import json
import re
import unicodedata
from pathlib import Path

import pytest

from gpsaccel import _taught, registry
from gpsaccel.lessons import lessons_dir
from gpsaccel.lessons.release import masters

_SELF_CHECK = re.compile(r'self_check\("([^"]+)"')
_SUBMISSION_ERROR = re.compile(r'SubmissionError\("([a-z-]+)"')


def _code(key: str) -> str:
    """The code a message table's key words: ``homework.x.part`` and ``update.x`` -> ``x``."""
    for prefix in ("homework.", "update."):
        key = key.removeprefix(prefix)
    return key.split(".")[0]


def finding_codes() -> dict[str, set[str]]:
    """Every finding code -> the tables it was read from."""
    from gpsaccel.check import findings
    from gpsaccel.check.linear import FINDINGS
    from gpsaccel.check.wording import STUDENT
    from gpsaccel.sandbox.outcomes import OUTCOMES

    found: dict[str, set[str]] = {}

    def add(table: str, keys) -> None:
        for key in keys:
            code = _code(key)
            if code not in ("hint", "lost"):
                found.setdefault(code, set()).add(table)

    add("check.wording.STUDENT", STUDENT)
    add("check.linear.FINDINGS", FINDINGS)
    add("check.findings.MESSAGES", findings.MESSAGES)
    add("sandbox.outcomes.OUTCOMES", OUTCOMES)
    for name in registry.problems():
        problem = registry.problem(name)
        add(f"problem {name}: codes()", problem.codes())
        add(f"problem {name}: renames", getattr(problem, "renames", {}).values())
    for system in ("calibration", "kalman.linear", "ship", "coop"):
        module = importlib.import_module(f"gpsaccel.{system.replace('.linear', '.linear_messages')}"
                                         if "." in system else f"gpsaccel.{system}.mistakes")
        add(f"{module.__name__}.MESSAGES", getattr(module, "MESSAGES", {}))
    source = (Path(_taught.__file__).parent / "sandbox" / "submission.py").read_text()
    add("sandbox.submission: SubmissionError", _SUBMISSION_ERROR.findall(source))
    add("check.batch: checker_error", ["checker-error"])
    return found


def self_check_keys() -> set[str]:
    from gpsaccel.exercises.answers import ANSWERS

    keys = set(ANSWERS)
    for master in masters():
        for cell in json.loads(master.read_text(encoding="utf-8"))["cells"]:
            keys |= set(_SELF_CHECK.findall("".join(cell["source"])))
    return keys


def headings(path: Path) -> list[tuple[int, str]]:
    """(level, text) of every markdown heading of a notebook (none inside a code fence)."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    out = []
    for cell in nb["cells"]:
        if cell["cell_type"] != "markdown":
            continue
        fenced = False
        for line in "".join(cell["source"]).splitlines():
            if line.lstrip().startswith("```"):
                fenced = not fenced
            m = re.match(r"^(#{1,6}) +(.+?)\s*#*\s*$", line)
            if m and not fenced:
                out.append((len(m.group(1)), m.group(2)))
    return out


def test_the_tables_are_read():
    codes = finding_codes()
    # one of each kind of table, so that a renamed table cannot make this test vacuous
    for code in ("phi-sign", "timeout", "no-kalman-filter", "link-refused", "missing-as-zero",
                 "no-angle-wrap", "zeroed-gain", "nees-bounds", "checker-error", "returns-list"):
        assert code in codes, code
    assert len(codes) > 100 and {"00.1", "14.2"} <= self_check_keys()


def test_every_code_and_self_check_points_to_a_lesson_section():
    missing = sorted(set(finding_codes()) - set(_taught.TAUGHT))
    assert not missing, ("codes no lesson section teaches (a gap in the lessons: write the "
                         f"section, then add its row to gpsaccel/_taught.py): {missing}")
    assert sorted(self_check_keys() - set(_taught.TAUGHT)) == []


def test_no_row_is_stale():
    known = set(finding_codes()) | self_check_keys()
    assert sorted(set(_taught.TAUGHT) - known) == []


@pytest.mark.parametrize("version", ["student", "solutions"])
def test_every_section_is_a_heading_of_the_released_lesson(version):
    """Once, at a level the rendered site anchors (#, ##, ###), with an anchor no other heading
    of that lesson has; an exercise named is one the lesson sets."""
    folder = lessons_dir() if version == "student" else lessons_dir() / "solutions"
    for section in set(_taught.TAUGHT.values()):
        path = folder / section.notebook
        assert path.is_file(), f"{section}: no released lesson {path.name}"
        found = headings(path)
        levels = [level for level, text in found if text == section.heading]
        assert levels and len(levels) == 1 and levels[0] <= 3, (section, levels)
        anchors = [_taught.Section(section.lesson, text).anchor for _, text in found]
        assert anchors.count(section.anchor) == 1, (section, section.anchor)
        if section.exercise:
            text = "\n".join("".join(c["source"]) for c in json.loads(
                path.read_text(encoding="utf-8"))["cells"] if c["cell_type"] == "markdown")
            assert re.search(rf"(?m)^{section.exercise}\. |\*Exercise {section.exercise}[:* ]",
                             text), (section, "no such exercise")


def test_the_anchor_is_the_rendered_sites():
    """MyST's slug of the heading's text (its GitHub style), which the site writes as the
    section's anchor (``myst_heading_anchors``) and ``docs/checker.md`` links to."""
    slugs = pytest.importorskip("myst_parser.slugs")
    for section in set(_taught.TAUGHT.values()):
        text = re.sub(r"\$[^$]*\$", "", section.heading).replace("`", "")
        assert section.anchor == slugs.github_slugify(text), section
        assert section.anchor and unicodedata.normalize("NFC", section.anchor) == section.anchor


def test_the_student_text_of_a_section():
    s = _taught.taught("phi-sign")
    assert s.cite() == "lesson 02, 'The derivation' (exercise 5)"
    assert s.to_dict() == {"lesson": "02", "notebook": "02-error-model.ipynb",
                           "section": "The derivation", "anchor": "the-derivation",
                           "exercise": "5"}
    assert _taught.taught("no-such-code") is None
    assert _taught.Section(_taught.L09B, "A b: c (d, e) – f").number == "09b"
    assert _taught.Section(_taught.L04, "Report 000, figure 7: $P^{ave} - P$").anchor == \
        "report-000-figure-7-"


def test_the_class_summary_names_where_each_code_is_taught():
    lines = _taught.class_lines({"phi-sign": 9, "timeout": 1, "zz-new": 2})
    assert lines == [
        "9 students: `phi-sign` → lesson 02, 'The derivation' (exercise 5)",
        "2 students: `zz-new` (no lesson teaches it yet)",
        "1 student: `timeout` → lesson 08, 'Step 5: when the check cannot run your code'"]
