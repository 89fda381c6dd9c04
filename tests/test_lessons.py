"""Every lesson executes top to bottom with a small ensemble (GPSACCEL_LESSON_RUNS)."""

from __future__ import annotations

import json

import pytest

from gpsaccel.lessons import execute, lessons_dir

LESSONS = sorted(lessons_dir().glob("*.ipynb"))
SMALL_RUNS = 40


def test_lessons_exist():
    assert LESSONS, "lessons/ holds no notebook"


@pytest.mark.parametrize("path", LESSONS, ids=[p.stem for p in LESSONS])
def test_lesson_is_committed_without_outputs(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            assert not cell.get("outputs"), f"{path.name}: a code cell carries stored output"
            assert cell.get("execution_count") is None, f"{path.name}: stale execution count"


@pytest.mark.parametrize("path", LESSONS, ids=[p.stem for p in LESSONS])
def test_lesson_executes(path):
    execute(path, timeout=300, runs=SMALL_RUNS)
