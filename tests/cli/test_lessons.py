"""``gpsaccel lessons``: executes the lessons and renders them as HTML with their figures.

One real run renders lesson 02 (conftest's ``lesson_02_html``, shared with the browser test);
the run without ``--html`` is recorded, not executed (tests/lessons/test_lessons.py runs the lessons)."""

from __future__ import annotations

import pytest

from gpsaccel.cli import main


def test_lessons_html_renders_a_lesson_with_its_figures(lesson_02_html):
    out_dir, returncode, out, err = lesson_02_html
    assert returncode == 0, err
    html = (out_dir / "02-error-model.html").read_text(encoding="utf-8")
    assert "image/png" in html and "Deriving" in html
    # the solutions version, as on the docs site: solutions there, collapsed
    assert "Solution to exercise 02.3 (open once you have tried)" in html and "exercise 02.3: right" in html
    assert "1 lessons executed" in out


def test_lessons_refuses_an_unknown_lesson_and_a_tiny_ensemble(capsys):
    assert main(["lessons", "--only", "99"]) == 2
    assert "--only" in capsys.readouterr().err
    assert main(["lessons", "--only", "02", "--runs", "1"]) == 2
    assert "argument --runs: must be an integer >= 2" in capsys.readouterr().err


def test_lessons_kernel_does_not_warn_about_tcp(lesson_02_html):
    """The kernel talks over private Unix sockets: no "running over TCP without encryption"."""
    _, returncode, out, err = lesson_02_html
    assert returncode == 0, err
    assert "without encryption" not in out + err
    assert "1 lessons executed" in out


def test_lessons_without_html_executes_the_student_version(monkeypatch, capsys):
    """Without --html the student version is executed, at the ensemble --runs asks for (that it
    runs at that ensemble is tests/lessons/test_lessons.py's, from its solutions version's run)."""
    from gpsaccel import lessons
    from gpsaccel.lessons import kernel

    calls = []

    def execute(path, timeout=600, runs=None):
        calls.append((path, runs))

    monkeypatch.setattr(kernel, "execute", execute)  # what the command runs
    assert main(["lessons", "--only", "02", "--runs", "20"]) == 0  # test_lessons.py's ensemble
    assert calls == [(lessons.lessons_dir() / "02-error-model.ipynb", 20)]
    assert "1 lessons executed" in capsys.readouterr().out


def test_names_the_lessons_type_are_reachable_after_import_gpsaccel():
    """Exercise code is typed as given: ``import gpsaccel`` then ``gpsaccel.check.…`` and so on."""
    import gpsaccel

    assert callable(gpsaccel.check.model_matrices)
    assert callable(gpsaccel.calibration.compare.reference_filter)
    assert callable(gpsaccel.calibration.mistakes.mutant)
    assert callable(gpsaccel.lessons.sliders)
    assert callable(gpsaccel.kalman.update.epoch_transition)

    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        gpsaccel.nonsense  # noqa: B018
