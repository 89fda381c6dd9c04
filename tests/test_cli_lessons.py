"""``gpsaccel lessons``: executes the lessons and renders them as HTML with their figures."""

from __future__ import annotations

from gpsaccel.cli import main


def test_lessons_html_renders_a_lesson_with_its_figures(tmp_path, capsys):
    assert main(["lessons", "--html", str(tmp_path), "--only", "02", "--runs", "10"]) == 0
    html = (tmp_path / "02-error-model.html").read_text(encoding="utf-8")
    assert "image/png" in html and "Deriving" in html
    # the solutions version, as on the docs site: solutions there, collapsed
    assert "Solution (click to reveal)" in html and "exercise 02.3: right" in html
    assert "1 lessons executed" in capsys.readouterr().out


def test_lessons_refuses_an_unknown_lesson_and_a_tiny_ensemble(capsys):
    assert main(["lessons", "--only", "99"]) == 2
    assert "--only" in capsys.readouterr().err
    assert main(["lessons", "--only", "02", "--runs", "1"]) == 2
    assert "argument --runs: must be an integer >= 2" in capsys.readouterr().err


def test_lessons_kernel_does_not_warn_about_tcp(tmp_path, capfd):
    """The kernel talks over private Unix sockets: no "running over TCP without encryption"."""
    assert main(["lessons", "--only", "02", "--runs", "10"]) == 0
    out, err = capfd.readouterr()
    assert "without encryption" not in out + err
    assert "1 lessons executed" in out


def test_names_the_lessons_type_are_reachable_after_import_gpsaccel():
    """Exercise code is typed as given: ``import gpsaccel`` then ``gpsaccel.check.…`` and so on."""
    import gpsaccel

    assert callable(gpsaccel.check.model_matrices)
    assert callable(gpsaccel.calibration.compare.reference_filter)
    assert callable(gpsaccel.calibration.mistakes.mutant)
    assert callable(gpsaccel.lessons.sliders)
    assert callable(gpsaccel.kalman.update.epoch_transition)
    import pytest

    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        gpsaccel.nonsense  # noqa: B018
