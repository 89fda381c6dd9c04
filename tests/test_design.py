"""docs/design.md names every module of the package, each in the row of its layer, with why.

A module added without a line there fails here, named with the row it belongs in.  Packages'
``__init__.py`` and ``__main__.py`` are their faces (the row names the package); what ships as data
(the homework's masters and student notebooks, the instructor's example, the lessons' copies) is
no module of the design.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "gpsaccel"
DATA = ("masters", "student", "example", "_lessons", "templates", "data")


def _modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py")
                  if p.name not in ("__init__.py", "__main__.py")
                  and not set(p.relative_to(PACKAGE).parts[:-1]) & set(DATA))


def _rows() -> list[tuple[str, str]]:
    """(first cell, whole row) of each row of the layers' table."""
    text = (ROOT / "docs" / "design.md").read_text(encoding="utf-8")
    layers = text.split("## The layers", 1)[1].split("\n## ", 1)[0]
    return [(line.split("|")[1], line) for line in layers.splitlines()
            if line.startswith("| ") and not line.startswith("| ---")]


def _named(row: str, name: str) -> bool:
    return re.search(rf"(?<![\w./])(?:gpsaccel/)?{re.escape(name)}(?![\w])", row) is not None


def missing() -> list[str]:
    """The modules no row names, each with where its line goes."""
    rows = _rows()
    out = []
    for path in _modules():
        rel = path.relative_to(PACKAGE)
        if len(rel.parts) == 1:  # a module of the ground floor: named anywhere in the table
            if not any(_named(row, rel.name) for _, row in rows):
                out.append(f"gpsaccel/{rel.as_posix()} (add it to a row of the ground floor)")
            continue
        layer = f"gpsaccel/{rel.parts[0]}/"
        mine = [row for first, row in rows if layer in first]
        if not any(_named(row, rel.name) for row in mine):
            where = f"the row of {layer}" if mine else f"a row of its own for {layer}"
            out.append(f"gpsaccel/{rel.as_posix()} (add `{rel.name}` and why to {where})")
    return out


def test_design_md_names_every_module_of_the_package():
    gaps = missing()
    assert not gaps, "docs/design.md does not name:\n  " + "\n  ".join(gaps)


def test_the_rule_sees_a_module_that_is_not_named():
    rows = _rows()
    assert any(_named(row, "update.py") for first, row in rows if "gpsaccel/kalman/" in first)
    assert not any(_named(row, "no_such_module.py") for _, row in rows)
    assert not _named("`_update.py`", "update.py") and _named("(`update.py`)", "update.py")
