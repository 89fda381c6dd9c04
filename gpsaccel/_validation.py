"""Argument checks shared by every public entry point.

Each helper raises :class:`ValueError` whose message starts with the argument's name and says what
was expected, so a student reading a traceback knows which argument to fix.

numpy is imported by the three helpers that need it, not here: the command's parser uses the
``flag_*`` converters below, and its help and argument errors must not wait for numpy
(tests/test_lazy_imports.py).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from numbers import Integral, Real
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

#: Relative tolerance used when a duration must be a whole number of intervals (30 % 0.2 != 0 in
#: floating point, but 30 / 0.2 is 150 to within a few ulps).
MULTIPLE_RTOL = 1e-9


def probability(name: str, value: object) -> float:
    """A probability strictly between 0 and 1 (a test level α, a false-alarm rate)."""
    p = finite_float(name, value)
    if not 0.0 < p < 1.0:
        raise ValueError(f"{name} must be a probability strictly between 0 and 1, got {value!r}")
    return p


def positive_float(name: str, value: object) -> float:
    """``value`` as a finite float > 0."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{name} must be a positive number, got {value!r}")
    out = float(value)
    if not math.isfinite(out) or out <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return out


def finite_float(name: str, value: object) -> float:
    """``value`` as a finite float."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{name} must be a number, got {value!r}")
    out = float(value)
    if not math.isfinite(out):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return out


def integer(name: str, value: object, minimum: int | None = None) -> int:
    """``value`` as an int (a float with an integral value is refused: 40.0 is a slip, not a count)."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    out = int(value)
    if minimum is not None and out < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {out}")
    return out


def choice(name: str, value: object, choices: Iterable[str]) -> str:
    """``value`` if it is one of ``choices``."""
    options = tuple(choices)
    if value not in options:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, options))}; got {value!r}")
    return str(value)


def whole_multiple(name: str, total: float, step: float, step_name: str) -> int:
    """Number of ``step`` intervals in ``total``; ValueError unless it is whole (to MULTIPLE_RTOL)."""
    ratio = total / step
    n = round(ratio)
    if n < 1 or abs(ratio - n) > MULTIPLE_RTOL * max(1.0, abs(ratio)):
        raise ValueError(
            f"{name} = {total!r} must be a whole multiple of {step_name} = {step!r} "
            f"(got {ratio!r} intervals)"
        )
    return int(n)


def finite_array(name: str, value: object, shape: tuple[int | None, ...] | None = None,
                 allow_nan: bool = False) -> np.ndarray:
    """``value`` as a float array of ``shape`` (None entries match any length), all finite.

    With ``allow_nan`` a NaN is accepted (it means "not measured"); +-inf never is.
    """
    import numpy as np

    _real(name, value)
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            want is None or want == got for want, got in zip(shape, arr.shape, strict=False)
        )
        if not ok:
            want = " x ".join("n" if s is None else str(s) for s in shape)
            raise ValueError(f"{name} must have shape ({want}), got {arr.shape}")
    if np.isinf(arr).any():
        raise ValueError(f"{name} contains an infinite value; a finite number is required")
    if not allow_nan and np.isnan(arr).any():
        raise ValueError(f"{name} contains NaN; a finite number is required")
    return arr


def _real(name: str, value: object) -> None:
    """ValueError if ``value`` holds complex numbers (numpy would drop the imaginary part with
    only a warning)."""
    import numpy as np

    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        return  # not an array at all: the caller's conversion says so
    if np.iscomplexobj(arr) or (arr.dtype == object and any(
            isinstance(v, complex | np.complexfloating) for v in arr.flat)):
        raise ValueError(f"{name} must be real; got complex values")


def spd_matrix(name: str, value: object, n: int | None = None, rtol: float = 1e-10) -> np.ndarray:
    """``value`` as an n x n symmetric positive definite float matrix.

    A scalar is accepted for n == 1.  Symmetry is checked to ``rtol`` of the largest element;
    positive definiteness by a Cholesky factorisation.
    """
    import numpy as np

    _real(name, value)
    arr = np.array(value, dtype=float)
    if arr.ndim == 0 and n in (None, 1):
        arr = arr.reshape(1, 1)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or (n is not None and arr.shape[0] != n):
        want = f"{n} x {n}" if n is not None else "square"
        raise ValueError(f"{name} must be a {want} matrix, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} contains NaN or inf; a finite matrix is required")
    scale = max(np.abs(arr).max(), np.finfo(float).tiny)
    asym = np.abs(arr - arr.T).max()
    if asym > rtol * scale:
        raise ValueError(f"{name} must be symmetric (largest |A - A^T| = {asym:.3g})")
    try:
        np.linalg.cholesky(arr)
    except np.linalg.LinAlgError:
        eig = np.linalg.eigvalsh(arr).min()
        raise ValueError(
            f"{name} must be positive definite (smallest eigenvalue {eig:.3g})"
        ) from None
    return arr


# ------------------------------------------------------------------------------ a model's fields
# A student-facing model (CalibrationModel, ShipModel, CoopModel) declares its checks as a table,
# field -> check(name, value), and its __post_init__ is one call:
#
#     FIELDS = {"dt": _v.positive_float, "V": _v.spd(2), "omega": _v.optional(_v.positive_float)}
#     def __post_init__(self):
#         _v.fields(self, FIELDS)
#
# Each check is one of the helpers above (the message names the field and what was expected), so the
# physics starts right after the table instead of after a wall of setattr calls.

#: A field's check: ``check(name, value)`` returns the normalised value or raises ValueError.
Check = Callable[[str, Any], Any]


def fields(obj: object, checks: Mapping[str, Check]) -> None:
    """Check and normalise the fields of ``obj`` (a frozen dataclass too) in the table's order."""
    for name, check in checks.items():
        object.__setattr__(obj, name, check(name, getattr(obj, name)))


def optional(check: Check) -> Check:
    """``check``, with None passing through (a field whose None means "not given")."""
    return lambda name, value: None if value is None else check(name, value)


def spd(n: int) -> Check:
    """An n x n symmetric positive definite matrix (:func:`spd_matrix`)."""
    return lambda name, value: spd_matrix(name, value, n)


def array(*shape: int) -> Check:
    """A finite float array of ``shape`` (:func:`finite_array`)."""
    return lambda name, value: finite_array(name, value, shape)


def count(minimum: int) -> Check:
    """An integer >= ``minimum`` (:func:`integer`)."""
    return lambda name, value: integer(name, value, minimum)


def flag(name: str, value: object) -> bool:
    """True or False, nothing else (1 or "yes" is a slip)."""
    if not isinstance(value, bool):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return value


def variance(unit: str) -> Check:
    """A finite float >= 0 in ``unit`` (a variance that may be zero)."""
    def check(name: str, value: object) -> float:
        out = finite_float(name, value)
        if out < 0:
            raise ValueError(f"{name} must be a variance >= 0 ({unit}), got {value!r}")
        return out
    return check


# ------------------------------------------------------------------------------ command-line flags
# The same checks as above, as argparse ``type=`` converters, so that every numeric flag of every
# sub-command is refused at parse time (exit 2, one line naming the flag) before any work starts:
#
#     p.add_argument("--runs", type=_v.flag_int(minimum=2), default=200)
#     p.add_argument("--out", type=_v.output_dir, default="out")   # a *string* default is checked too
#
# argparse prefixes the message with the flag ("argument --runs: must be an integer >= 2, got 0").


def _flag_error(exc: ValueError):
    import argparse

    return argparse.ArgumentTypeError(str(exc).strip())


def flag_int(minimum: int | None = None, maximum: int | None = None):
    """argparse ``type=`` for an integer flag in [minimum, maximum] (checked by :func:`integer`)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise _flag_error(ValueError(f"must be an integer, got {text!r}")) from None
        try:
            value = integer("", value, minimum)
        except ValueError as exc:
            raise _flag_error(exc) from None
        if maximum is not None and value > maximum:
            raise _flag_error(ValueError(f"must be an integer <= {maximum}, got {value}"))
        return value

    parse.__name__ = "integer"
    return parse


def flag_float(minimum: float | None = None, maximum: float | None = None, *,
               open_min: bool = False, open_max: bool = False):
    """argparse ``type=`` for a finite float flag in the interval [minimum, maximum] (``open_min``,
    ``open_max`` exclude the end points); NaN and inf are refused (:func:`finite_float`)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise _flag_error(ValueError(f"must be a number, got {text!r}")) from None
        try:
            value = finite_float("", value)
        except ValueError as exc:
            raise _flag_error(exc) from None
        low_bad = minimum is not None and (value <= minimum if open_min else value < minimum)
        high_bad = maximum is not None and (value >= maximum if open_max else value > maximum)
        if low_bad or high_bad:
            lo = "" if minimum is None else f"{'(' if open_min else '['}{minimum:g}"
            hi = "" if maximum is None else f"{maximum:g}{')' if open_max else ']'}"
            if minimum is not None and maximum is not None:
                want = f"in {lo}, {hi}"
            elif minimum is not None:
                want = f"{'>' if open_min else '>='} {minimum:g}"
            else:
                want = f"{'<' if open_max else '<='} {maximum:g}"
            raise _flag_error(ValueError(f"must be a number {want}, got {text}"))
        return value

    parse.__name__ = "number"
    return parse


#: ``--seed``: a non-negative integer (numpy's SeedSequence refuses negative entropy).
flag_seed = flag_int(minimum=0)
#: ``--alpha`` and other probabilities: strictly between 0 and 1.
flag_probability = flag_float(0.0, 1.0, open_min=True, open_max=True)


def _probe_directory(directory, what: str) -> None:
    """Create and delete a temporary file in the existing ``directory``; ValueError if impossible."""
    import os
    import tempfile

    try:
        fd, name = tempfile.mkstemp(dir=directory, prefix=".gpsaccel-probe-")
    except OSError as exc:
        raise _flag_error(ValueError(f"{what} is not writable (cannot create a file in "
                                     f"{directory}: {exc.strerror or exc})")) from None
    os.close(fd)
    os.unlink(name)


def _existing_ancestor(path):
    """The nearest existing ancestor of ``path`` (itself included); error if it is not a folder."""
    from pathlib import Path

    path = Path(path)
    for candidate in (path, *path.absolute().parents):
        if candidate.exists():
            if not candidate.is_dir():
                raise _flag_error(ValueError(f"{candidate} exists and is not a folder"))
            return candidate
    raise _flag_error(ValueError(f"no existing parent folder for {path}"))  # pragma: no cover


def output_dir(text: str):
    """argparse ``type=`` for an output folder: it may not exist yet, but it must be creatable and
    writable, which is tested now by writing (and removing) a temporary file in its nearest
    existing ancestor.  Nothing is created."""
    from pathlib import Path

    path = Path(text)
    if path.exists() and not path.is_dir():
        raise _flag_error(ValueError(f"{text} exists and is not a folder"))
    _probe_directory(_existing_ancestor(path), f"folder {text}")
    return path


def output_file(text: str):
    """argparse ``type=`` for an output file: not a folder, its folder creatable and writable
    (probed as in :func:`output_dir`), and the file itself writable if it exists."""
    import os
    from pathlib import Path

    path = Path(text)
    if path.is_dir():
        raise _flag_error(ValueError(f"{text} is a folder; a file name is required"))
    if path.exists() and not os.access(path, os.W_OK):
        raise _flag_error(ValueError(f"{text} is not writable"))
    _probe_directory(_existing_ancestor(path.parent), f"the folder of {text}")
    return path
