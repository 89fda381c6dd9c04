"""The units a figure labels the calibration states with: of each state, of a product of two
(elements of P, of E[e x̂ᵀ]) and of a ratio (a gain)."""

from __future__ import annotations

from gpsaccel.calibration.model import STATE_NAMES, STATE_UNITS

#: Names and units of the calibration error state, used in labels.
CALIBRATION_STATES = tuple(zip(STATE_NAMES, STATE_UNITS, strict=True))

_UNIT_POWERS = {"m": (1, 0), "m/s": (1, -1), "m/s²": (1, -2), "s": (0, 1), "": (0, 0)}
_SUPERSCRIPT = {1: "", 2: "²", 3: "³", 4: "⁴"}


def product_unit(u1: str, u2: str) -> str:
    """The unit of the product of two calibration quantities, e.g. ("m", "m/s²") -> "m²/s²"."""
    m = _UNIT_POWERS[u1][0] + _UNIT_POWERS[u2][0]
    s = _UNIT_POWERS[u1][1] + _UNIT_POWERS[u2][1]
    num = "1" if m == 0 else "m" + _SUPERSCRIPT[m]
    return num if s == 0 else f"{num}/s{_SUPERSCRIPT[-s]}"


def _ratio_unit(u1: str, u2: str) -> str:
    """Unit of quantity u1 per quantity u2 (a gain), e.g. ("m/s²", "m") -> "1/s²"."""
    m = _UNIT_POWERS[u1][0] - _UNIT_POWERS[u2][0]
    s = _UNIT_POWERS[u1][1] - _UNIT_POWERS[u2][1]
    num = "1" if m == 0 else "m" + _SUPERSCRIPT[m]
    if s == 0:
        return "1" if m == 0 else num
    if s > 0:
        return f"s{_SUPERSCRIPT[s]}" if m == 0 else f"{num}·s{_SUPERSCRIPT[s]}"
    return f"{num}/s{_SUPERSCRIPT[-s]}"


def _state_label(i: int, prefix: str = "") -> tuple[str, str]:
    name, unit = CALIBRATION_STATES[i]
    return f"{prefix}{name}", unit
