"""The exercise self-check and the slider helper the lessons use."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel.lessons import HEADLESS_VARIABLE, check_answer, sliders


def test_check_answer_says_right_wrong_and_why(capsys):
    assert check_answer(None, 1.0, name="ex 1") is None
    assert "not answered yet" in capsys.readouterr().out
    assert check_answer(2.0000001, 2.0, rtol=1e-6) is True
    assert "✓" in capsys.readouterr().out
    assert check_answer([[1, 2], [3, 5]], np.array([[1, 2], [3, 4]]), why="look at (1, 1)") is False
    out = capsys.readouterr().out
    assert "✗" in out and "at (1, 1)" in out and "expected 4" in out and "Hint: look at (1, 1)" in out
    assert check_answer([1, 2, 3], np.zeros(2)) is False
    assert "shape (3,), expected (2,)" in capsys.readouterr().out
    assert check_answer([np.nan], [1.0]) is False
    assert "NaN" in capsys.readouterr().out
    assert check_answer("seven", 7.0) is False
    assert "expected a number" in capsys.readouterr().out


def test_sliders_draw_the_default_once_without_a_front_end(monkeypatch, capsys):
    widgets = pytest.importorskip("ipywidgets")
    monkeypatch.setenv(HEADLESS_VARIABLE, "1")
    calls = []
    sliders(lambda a, b: calls.append((a, b)),
            a=widgets.FloatSlider(value=0.5, min=0, max=1), b=widgets.IntSlider(value=3))
    assert calls == [(0.5, 3)]
    assert "drawn once with a = 0.5, b = 3" in capsys.readouterr().out


def test_sliders_make_widgets_with_a_front_end(monkeypatch):
    widgets = pytest.importorskip("ipywidgets")
    monkeypatch.delenv(HEADLESS_VARIABLE, raising=False)
    calls = []
    sliders(lambda a: calls.append(a), a=widgets.FloatSlider(value=0.25, min=0, max=1))
    assert calls == [0.25]          # interact runs the callback once with the default as well
