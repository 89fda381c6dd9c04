"""Every number a lesson's text states, against what the lesson prints (``python -m
gpsaccel.lessons check``): a ``[[tagged]]`` result must be printed digit for digit by the measured
lesson; any other decimal must be a given constant (:data:`GIVEN`)."""

from __future__ import annotations

import re
from pathlib import Path

from gpsaccel.lessons.release import PRINTED, code_digest, masters, masters_dir, measured

#: A number as a lesson's text states a result: a decimal (0.687, 3.6, 2.6e-12, 1.25·10⁻⁵) or a
#: scientific one with a whole mantissa (4·10⁻⁵, 1e-13).  Plain whole numbers (counts, 40 steps,
#: 10⁻¹² as an order of magnitude) are not flagged: tag them where they are results.
STATED = re.compile(r"(?<![\w.])\d+(?:\.\d+(?:e[-+]?\d+|\s*[·×]\s*10[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)?"
                    r"|e[-+]?\d+|\s*[·×]\s*10[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)(?![\w.]*\d)")

#: What :data:`STATED` does not read: the tagged numbers, code (a span or a block: what a student
#: types) and the reports' section numbers.
_NOT_STATED = re.compile(r"\[\[[^\[\]]+\]\]|```.*?```|`[^`\n]*`|[Ss]ection \d+(?:\.\d+)+", re.S)

#: The numbers a lesson may state untagged: the problems' given constants (the reports' model
#: parameters, what an exercise sets, square roots of given variances) and numbers quoted from
#: the reports themselves.  Every other decimal in a master's text is a result: tag it.
GIVEN: dict[str, str] = {
    # calibration (reports 000, 001, 003)
    "0.005": "Δt, the accelerometer step (s)",
    "0.0004": "W, accelerometer noise variance ((m/s²)²)",
    "0.01": "M0₃₃ = σ_b² ((m/s²)²); the coop heading noise (rad²); 0.01 Hz, 0.01·δx0 (exercises)",
    "0.1": "σ_b (m/s²); ω = 0.1 (Hz, report 001; rad/s, report 000); T_s (s); δx0's 0.1 rad",
    "0.04": "σ of the GPS velocity (m/s); report 003 uses it as a variance",
    "0.0016": "V₂₂ = 0.04² ((m/s)²)",
    "1.0016": "M0₂₂ + V₂₂, the first velocity update's denominator",
    "0.2": "the GPS interval (s); V of the ship's velocities and heading",
    "0.63": "2π·0.1, report 001's angular frequency (rad/s)",
    "1.25·10⁻⁵": "Δt²/2 (s²)",
    "0.195": "39·Δt, the interval a loop of 39 predictions covers (s)",
    "0.4": "σ_v ten times larger (exercise, m/s)",
    "1.0": "M0₃₃ = 1.0 (exercise); 1.0 s",
    "0.001": "an example answer; the GPS variance of the ship's sweep (m²)",
    "1e-6": "the checker's tolerance (σ)",
    # the ship (report 004)
    "0.4462": "β_x, surge drag (1/s)",
    "0.0784": "β_y, sway drag (1/s)",
    "0.5": "σ of the random force (N); the wheelbase L (m); t = 0.5 s",
    "0.05": "σ of the random torque (N m); 1 − 0.95",
    "3.9": "√15, σ of the GPS position (m)",
    "0.45": "√0.2, σ of the ship's velocity and heading measurements",
    "0.007": "√4.9e-5, σ of the ship's accelerometers (m/s²)",
    # cooperative localization (report 002)
    "0.025": "P0's heading variances (rad²); α/2, the lower quantile of the 95 % χ² bounds",
    "0.975": "1 − α/2, the upper quantile of the two-sided 95 % χ² bounds",
    "0.95": "the 95 % level of the χ² bounds",
    # numbers the reports print (quoted, then measured against ours)
    "0.013": "report 000's max(P_ave − P)",
    "29.8": "report 000's r(30) r(29.8)ᵀ (s)",
    "0.0034": "report 000's r(30) r(29.8)ᵀ", "0.0005": "report 000's r(30) r(29.8)ᵀ",
    "0.0000": "report 000's r(30) r(29.8)ᵀ",
    "0.0486": "report 001's r(20) r(30)ᵀ", "0.0023": "report 001's r(20) r(30)ᵀ",
    "0.0002": "report 001's r(20) r(30)ᵀ",
    "5.8": "report 003's k = 30 (s)", "3.8": "report 003's k = 20 (s)",
    "0.0055": "report 003's r(k=30) r(k=20)ᵀ", "0.0077": "report 003's r(k=30) r(k=20)ᵀ",
    "0.0018": "report 003's r(k=30) r(k=20)ᵀ", "0.0006": "report 003's r(k=30) r(k=20)ᵀ",
}


def untagged_numbers(text: str) -> list[str]:
    """The results ``text`` (a master's markdown) states without a ``[[tag]]``: every
    :data:`STATED` number outside code and tags that is not a :data:`GIVEN` constant."""
    plain = _NOT_STATED.sub(lambda m: " " * len(m.group(0)), text)
    return [m.group(0) for m in STATED.finditer(plain)
            if re.sub(r"\s+", "", m.group(0)) not in GIVEN]


def _prints(text: str, number: str) -> bool:
    """Does ``text`` print ``number`` digit for digit (not as part of a longer number: 4 is not
    in 4.5 or 14, 0.5 not in 0.55)?"""
    return re.search(rf"(?<![\d.]){re.escape(number)}(?!\d|\.\d)", text) is not None


def number_problems(master: Path) -> list[str]:
    """What is wrong with the numbers a master's text states: each ``[[number]]`` must be printed,
    digit for digit, by the lesson (or the one ``@NN`` names) as measured at its full size on its
    current code; each other decimal must be :data:`GIVEN`.  Empty when all is well."""
    import nbformat

    problems, outputs = [], {}

    def printed(stem: str) -> str | None:
        if stem not in outputs:
            m = measured(stem)
            fresh = m is not None and m.get("runs") is None and \
                m.get("code_sha256") == code_digest(masters_dir() / f"{stem}.ipynb")
            outputs[stem] = "\n".join(m["printed"]) if m is not None and fresh else None
        return outputs[stem]

    for cell in nbformat.read(master, as_version=4).cells:
        if cell.cell_type != "markdown":
            continue
        where = f"{master.stem}, cell {cell.get('id', '?')}"
        for number in untagged_numbers(cell.source):
            problems.append(f"{where}: {number!r} is neither tagged [[{number}]] (a result the "
                            f"lesson prints) nor a given constant (gpsaccel.lessons.GIVEN)")
        for number, other in PRINTED.findall(cell.source):
            stem = master.stem
            if other:
                found = [p.stem for p in masters() if p.stem.split("-")[0] == other]
                if len(found) != 1:
                    problems.append(f"{where}: [[{number} @{other}]] names no single lesson")
                    continue
                stem = found[0]
            text = printed(stem)
            if text is None:
                problems.append(f"{where}: [[{number}]] quotes {stem}, which is not measured at "
                                f"its full size on its current code (python -m gpsaccel.lessons "
                                f"measure {stem.split('-')[0]})")
            elif not _prints(text, number.strip()):
                problems.append(f"{where}: the text quotes {number}, which {stem} does not print")
    return problems
