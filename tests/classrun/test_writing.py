"""gpsaccel/classrun/writing.py: the class's files."""

from __future__ import annotations

from gpsaccel import _atomic
from gpsaccel.classrun import writing


def test_the_summary_figure_counts_students_in_whole_numbers(tmp_path, monkeypatch):
    """summary.png's mistake codes are counts of students: a class where each code was made by
    one or two students had its axis ticked 0, 0.25, ..., 2 (tried from the wheel)."""
    drawn = []
    monkeypatch.setattr(_atomic, "savefig", lambda fig, path, **kw: drawn.append(fig))
    rows = [{"question": "q1", "mean": 2.3, "possible": 3.0, "students": 9,
             "codes": {"not-defined": 2, "std-as-variance": 1}},
            {"question": "q2", "mean": 2.2, "possible": 4.0, "students": 9,
             "codes": {"phi-sign": 1}}]
    writing._figure(rows, tmp_path / "summary.png")
    counts = drawn[0].axes[1]
    ticks = [t for t in counts.get_xticks() if counts.get_xlim()[0] <= t <= counts.get_xlim()[1]]
    assert len(ticks) >= 2 and all(float(t).is_integer() for t in ticks), ticks
