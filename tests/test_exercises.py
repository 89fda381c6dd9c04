"""The lessons' self-check: right or wrong, the direction and rough size of a miss, a hint; never
the expected value; the rounding a lesson prints (3 significant digits) is accepted."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gpsaccel import exercises
from gpsaccel._taught import taught
from gpsaccel.exercises import RECORD_VARIABLE, WIDTH, _verdict, describe_miss, self_check, tolerance, wrapped


def verdict(answer, expected, hint="", digits=3):
    return _verdict("exercise 1", answer, expected, hint, digits)


def test_the_printed_rounding_is_accepted_and_one_digit_off_is_not():
    e = 0.00203612015600418                       # lesson 03's σ_b with a noisy GPS
    assert verdict(2.04e-3, e).startswith("✓")     # as its solution prints it (.2e)
    assert verdict(0.002036, e).startswith("✓")
    assert verdict(2.03e-3, e).startswith("✗")
    assert verdict(2.05e-3, e).startswith("✗")
    assert tolerance(e) == pytest.approx(5e-6 * (1 + 1e-9))
    assert verdict(6.28, 6.283180272841792, digits=3).startswith("✓")
    assert verdict(6.3, 6.283180272841792, digits=2).startswith("✓")
    assert verdict(6.3, 6.283180272841792).startswith("✗")


def test_a_miss_says_direction_and_rough_size_never_the_value():
    e = 7.779839051954151
    cases = {e / 4: "about 4× too small", e * 4: "about 4× too large", -e: "has the wrong sign",
             e * 1.05: "a few per cent too large", e * 0.8: "10–50 % too small",
             e * 1000: "about 10^3× too large", e * 1.004: "slightly (under 1 %) too large",
             0.0: "is zero"}
    for answer, phrase in cases.items():
        out = verdict(answer, e, hint="solve |b| t²/2 = 1 m for t")
        assert out.startswith("✗") and phrase in out and "Hint: solve" in out, (answer, out)
        for shown in (f"{e:.3g}", f"{e:.2g}", f"{e:.4f}", "7.78", "7.8"):
            assert shown not in out, f"{out!r} gives away the answer"
    assert describe_miss(1.0, 0.0) == "should be zero"


def test_counts_are_exact_and_arrays_name_the_first_wrong_entry():
    assert verdict(100, 100).startswith("✓")
    assert verdict(100.4, 100) == "✗ exercise 1: not this count (too many)."
    assert "too few" in verdict(92, 100)
    out = verdict([1.0, 2.0, 30.0], np.array([1.0, 2.0, 3.0]))
    assert "1 of 3 entries wrong; the first, at (2,), about 10^1× too large" in out
    assert "your answer has shape (2,); the exercise asks for a single number" in verdict([1, 2], 3.0)


def test_not_answered_bad_type_and_nan():
    assert verdict(None, 1.0).startswith("… exercise 1: not answered yet")
    assert "got str" in verdict("seven", 7.0)
    assert "NaN" in verdict(float("nan"), 1.0)


def test_self_check_prints_one_line_and_returns_nothing(capsys, monkeypatch):
    monkeypatch.setattr("gpsaccel.exercises.answers.ANSWERS", {"99.1": 0.5})
    assert self_check("99.1", 0.5) is None                 # no True/False repr under the cell
    assert capsys.readouterr().out == "✓ exercise 99.1: right\n"
    with pytest.raises(KeyError, match="no recorded answer for exercise '99.2'"):
        self_check("99.2", 1.0)


def test_a_miss_names_the_lesson_section_to_read_again(capsys, monkeypatch):
    monkeypatch.setattr("gpsaccel.exercises.answers.ANSWERS", {"00.2": 0.5, "99.5": 0.5})
    self_check("00.2", 2.0, hint="h")
    assert capsys.readouterr().out == ("✗ exercise 00.2: about 4× too large. Hint: h. Read again: "
                                       "lesson 00, 'Forty predictions\n  to the next fix'.\n")
    self_check("00.2", 0.5)
    assert capsys.readouterr().out == "✓ exercise 00.2: right\n"
    self_check("99.5", 2.0)                       # a key the table does not know: no pointer
    assert capsys.readouterr().out == "✗ exercise 99.5: about 4× too large.\n"


def test_a_long_verdict_is_wrapped_to_fit_the_output_area(capsys, monkeypatch):
    """Lesson 09's hint, on one line, made JupyterLab's output scroll sideways at 1400 px: the
    verdict is broken at spaces into lines of at most WIDTH characters, nothing lost or reordered."""
    monkeypatch.setattr("gpsaccel.exercises.answers.ANSWERS", {"09.1": 0.5})
    hint = ("the multirate σ of x is the square root of P[0, 0] at the first measurement time at "
            "or after 50 s; P needs no data")
    self_check("09.1", 2.0, hint=hint)
    out = capsys.readouterr().out
    lines = out.rstrip("\n").split("\n")
    assert len(lines) >= 2 and max(len(s) for s in lines) <= WIDTH
    assert all(s.startswith("  ") and not s.startswith("   ") for s in lines[1:])
    assert " ".join(s.strip() for s in lines) == _verdict("exercise 09.1", 2.0, 0.5, hint, 3) + (
        ". Read again: " + taught("09.1").cite() + ".")
    assert wrapped("a " + "x" * 120 + " b", 20) == "a\n  " + "x" * 120 + "\n  b"   # a word stays whole


def test_record_mode_writes_the_answer_instead_of_checking(tmp_path, monkeypatch, capsys):
    record = tmp_path / "a.jsonl"
    monkeypatch.setenv(RECORD_VARIABLE, str(record))
    self_check("99.3", np.int64(7))
    self_check("99.4", np.array([1.5, 2.5]))
    lines = [json.loads(x) for x in record.read_text().splitlines()]
    assert [(x["key"], x["value"]) for x in lines] == [("99.3", 7), ("99.4", [1.5, 2.5])]
    assert isinstance(lines[0]["value"], int)             # a count stays a count (exact match)
    assert "recorded" in capsys.readouterr().out


def test_every_recorded_answer_belongs_to_a_lesson_with_that_self_check():
    from gpsaccel.lessons import masters

    text = "\n".join(p.read_text(encoding="utf-8") for p in masters())
    for key in exercises.answers.ANSWERS:
        assert f'self_check(\\"{key}\\"' in text, f"{key}: recorded, but no lesson checks it"
