r"""Check a student's model matrices (Φ, Γ, H, V, W, M0, Q) against the report-000 problem.

The problem's matrices (state [δp, δv, b], Δt = 0.005 s)::

    Φ = [[1, Δt, −Δt²/2], [0, 1, −Δt], [0, 0, 1]]     Γ = −[Δt²/2, Δt, 0]ᵀ      H = [I₂ 0]
    V = diag(1 m², (0.04 m/s)²)     W = 0.0004 (m/s²)²     M0 = diag(100 m², 1 (m/s)², 0.01 (m/s²)²)
    Q = Γ W Γᵀ per accelerometer step

A filter that steps only at GPS times passes ``dt`` = the GPS interval (0.2 s): Φ(0.2 s) is then the
exact 40-step transition, and its process noise must be the 40-step sum Σ_{j<40} Φʲ ΓWΓᵀ Φʲᵀ (pass
it as ``Q``), not Γ(0.2 s) W Γ(0.2 s)ᵀ.

Each wrong element becomes a :class:`~gpsaccel.check.report.Finding` that names the element in the
course's 1-based notation (Φ₁₃), says what it should be and, for the mistakes of the catalogue
(:mod:`gpsaccel.calibration.mistakes`), the likely cause, under the catalogue's code.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from gpsaccel.calibration.model import STATE_UNITS, CalibrationModel, gamma, phi
from gpsaccel.check.report import Report, as_array
from gpsaccel.kalman.update import epoch_transition

#: Relative tolerance of an element against its expected value (students type numbers such as
#: 1.25e-5 by hand; 1e-6 accepts every correct rounding of 7 significant digits).
RTOL = 1e-6

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def _elem(name: str, i: int, j: int | None = None) -> str:
    """Course notation of an element, 1-based: Φ₁₃, V₂₂, Γ₂."""
    idx = f"{i + 1}" if j is None else f"{i + 1}{j + 1}"
    return name + idx.translate(_SUB)


def _close(a: float, b: float, scale: float) -> bool:
    return math.isclose(a, b, rel_tol=RTOL, abs_tol=RTOL * 1e-6 * scale)


#: A matrix with NaN shows the student's own values.
_VALUES_SHOWN = {"not-finite": "{name} contains NaN or inf: {values}"}


def _shape(report: Report, name: str, arr: np.ndarray, want: tuple[int, ...],
           meaning: str, also: tuple[tuple[int, ...], ...] = ()) -> np.ndarray | None:
    if arr.shape == want:
        return arr
    if arr.shape in also:
        return arr.reshape(want)
    # the shape asked for is the question's (public), not an answer
    report.add("shape", text="{name} has shape {shape}; it must be {want}: {meaning}.",
               where=name, observed={"name": name, "shape": arr.shape,
                                     "want": " x ".join(map(str, want)), "meaning": meaning})
    return None


def _wrong_elements(actual: np.ndarray, expected: np.ndarray) -> list[tuple[int, ...]]:
    scale = float(np.abs(expected).max()) or 1.0
    return [idx for idx in np.ndindex(expected.shape)
            if not _close(float(actual[idx]), float(expected[idx]), scale)]


def _same(actual: np.ndarray, expected: np.ndarray) -> bool:
    return not _wrong_elements(actual, expected)


def _add(report: Report, code: str, text: str, message: str, where: str = "",
         expected: dict | None = None, **observed: object) -> None:
    """A finding of this check: ``text`` (the student's, filled from ``observed``: their own
    elements) and ``message`` (the instructor's, which quotes the right values too)."""
    report.add(code, message, text=text, where=where, observed=observed, expected=expected)


#: matrix -> what the student reads about its wrong elements: what the matrix means, never
#: the right matrix, its structure or its formula (tests/check/test_findings_data.py).
_ELEMENT_ADVICE = {
    "Φ": "Compare each with its formula in terms of Δt (state [δp, δv, b]).",
    "Γ": "Γ carries one accelerometer sample's noise w into [δp, δv, b].",
    "H": "The GPS measures δp and δv, not the bias.",
    "V": "V holds the variances of the two GPS noises, position and velocity, which are "
         "independent.",
    "M0": "M0 holds the prior variances of δp, δv and b, which are independent a priori.",
    "Q": "Q is the noise the accelerometer adds over one step of your filter.",
}

#: The calibration's states, as the student's text names them.
_STATES = ("δp", "δv", "b")


def _measures(H: np.ndarray) -> str:
    """What the student's H measures, row by row, in the states' names (their own matrix)."""
    rows = []
    for i, row in enumerate(np.asarray(H, dtype=float), start=1):
        used = [s for s, h in zip(_STATES, row, strict=True) if h != 0.0]
        what = ("nothing" if not used else used[0] if len(used) == 1
                else "a mix of " + ", ".join(used[:-1]) + f" and {used[-1]}")
        rows.append(f"row {i} measures {what}")
    return f"Your H's {', '.join(rows)}; the GPS measures δp and δv, not the bias."


def _element_finding(report: Report, code: str, name: str, actual: np.ndarray,
                     expected: np.ndarray, formulas: dict[tuple[int, ...], str], hint: str = "",
                     advice: str | None = None) -> None:
    parts, labels, right, mine = [], [], {}, []
    for idx in _wrong_elements(actual, expected):
        label = _elem(name, *idx) if len(idx) == 2 else _elem(name, idx[0])
        formula = formulas.get(idx, "")
        value = f"{expected[idx]:.6g}"
        want = f"{formula} = {value}" if formula and formula != value else value
        parts.append(f"{label} = {actual[idx]:.6g}, should be {want}")
        labels.append(label)
        mine.append(f"{label} = {actual[idx]:.6g}")
        right[label] = want
    _add(report, code, "Wrong: {values}. {advice}",
         "; ".join(parts) + "." + (f" {hint}" if hint else ""), where=", ".join(labels),
         expected=right, values=", ".join(mine),
         advice=_ELEMENT_ADVICE.get(name, "") if advice is None else advice)


def _check_phi(report: Report, Phi: np.ndarray, dt: float, model: CalibrationModel) -> None:
    want = phi(dt)
    if _same(Phi, want):
        return
    formulas: dict[tuple[int, ...], str] = {
        (0, 1): "Δt", (0, 2): "−Δt²/2", (1, 2): "−Δt", (0, 0): "1", (1, 1): "1", (2, 2): "1",
        (1, 0): "0", (2, 0): "0", (2, 1): "0"}
    if _same(Phi, phi(dt, +1.0)):
        _add(report, "phi-sign", "Φ₁₃ = {phi13:.6g} has the wrong sign. Likely cause: the "
             "accelerometer reads a + b, so δp = p − p_c loses b·Δt²/2 per step (report 001 "
             "prints +½Δt²).", f"Φ₁₃ = {Phi[0, 2]:.6g} has the wrong sign: the bias enters "
             f"position as −Δt²/2 = {-dt**2 / 2:.6g}.", where="Φ₁₃",
             expected={"Φ₁₃": -dt**2 / 2}, phi13=float(Phi[0, 2]))
        return
    if _close(Phi[1, 2], dt, dt) and all(
            _close(float(Phi[idx]), float(want[idx]), 1.0) for idx in np.ndindex(3, 3) if idx[1] != 2):
        flipped = "Φ₁₃ and Φ₂₃ have" if _close(Phi[0, 2], dt**2 / 2, dt**2) else "Φ₂₃ has"
        _add(report, "phi-sign", "{flipped} the wrong sign. Likely cause: a_c = a + b + w, so "
             "the integrated accelerometer runs ahead of the truth by the bias.",
             f"{flipped} the wrong sign: the bias enters velocity as −Δt = {-dt:.6g} and "
             f"position as −Δt²/2 = {-dt**2 / 2:.6g}.", where=flipped.rsplit(" ", 1)[0],
             expected={"Φ₂₃": -dt, "Φ₁₃": -dt**2 / 2}, flipped=flipped)
        return
    other = float(Phi[0, 1])
    for step in (model.dt, model.gps_interval, model.gps_interval / 10):
        if not _close(step, dt, dt) and _close(other, step, step):
            for sign in (-1.0, 1.0):
                if _same(Phi, phi(step, sign)):
                    also = " Φ₁₃ also has the wrong sign (phi-sign)." if sign > 0 else ""
                    # the step the student used is theirs (Φ₁₂); the one checked is the answer
                    _add(report, "phi-interval", "Your Φ is built with Δt = {used:g} s (Φ₁₂ = "
                         "{used:g}), not the step it is checked for: the accelerometer step "
                         "(or, for a filter that steps only at GPS times, the GPS interval: "
                         "pass that dt to check it that way).{also}",
                         f"Your Φ is built with Δt = {step:g} s but is checked for Δt = "
                         f"{dt:g} s.{also}", where="Φ", expected={"Δt": dt}, used=step,
                         also=also)
                    return
    _element_finding(report, "phi-element", "Φ", Phi, want, formulas,
                     f"(Δt = {dt:g} s; state [δp, δv, b].)")


def _check_gamma(report: Report, G: np.ndarray, dt: float, model: CalibrationModel) -> None:
    want = gamma(dt)
    if _same(G, want):
        return
    if _same(G, -want):
        _add(report, "gamma-sign", "Your Γ has the wrong sign: the accelerometer noise w enters "
             "a_c = a + b + w, so δv = v − v_c decreases by w·Δt (report 001 drops the minus "
             "sign). The filter itself does not change (only Γ W Γᵀ enters it), but a truth "
             "simulated with this Γ does.", f"Γ has the wrong sign; it is "
             f"[{want[0, 0]:.6g}, {want[1, 0]:.6g}, 0]ᵀ.", where="Γ",
             expected={"Γ": want[:, 0].tolist()})
        return
    for step in (model.dt, model.gps_interval, model.gps_interval / 10):
        if not _close(step, dt, dt) and (_same(G, gamma(step)) or _same(G, -gamma(step))):
            _add(report, "gamma-interval", "Your Γ is built with Δt = {used:g} s (Γ₂ = "
                 "{g2:g}); Γ carries one accelerometer sample's noise.",
                 f"Your Γ is built with Δt = {step:g} s but is checked for Δt = {dt:g} s.",
                 where="Γ", expected={"Δt": model.dt}, used=step, g2=float(G[1, 0]))
            return
    _element_finding(report, "gamma-element", "Γ", G[:, 0], want[:, 0],
                     {(0,): "−Δt²/2", (1,): "−Δt", (2,): "0"}, f"(Δt = {dt:g} s.)")


def _variance_slip(report: Report, code: str, e: str, a: float, right: float, what: str,
                   message: str) -> None:
    """A variance element ``e`` = ``a`` recognised as the slip ``what`` (the student's value
    and the kind of slip; the right value goes to the instructor)."""
    _add(report, code, "{e} = {a:g}: {what}.", message, where=e, expected={e: right}, e=e, a=a,
         what=what)


_SIGMA = "this is the standard deviation; a covariance holds variances σ²"
_SQUARED = "the variance was squared again; a covariance holds σ²"


def _check_V(report: Report, V: np.ndarray, model: CalibrationModel) -> None:
    want = model.V
    if _same(V, want):
        return
    sd = np.sqrt(np.diag(want))
    findings_before = len(report.findings)
    for k, unit in ((0, "m"), (1, "m/s")):
        var = "m²" if k == 0 else "(m/s)²"
        a, right = float(V[k, k]), float(want[k, k])
        if _close(a, right, right):
            continue
        e = _elem("V", k, k)
        full = f"{e} = {a:g}; {e} = σ² = {right:g} {var} (σ = {sd[k]:g} {unit})."
        if _close(a, sd[k], sd[k]):
            _variance_slip(report, "std-as-variance", e, a, right, _SIGMA + " (report 003 uses "
                           "0.04 as the velocity-noise variance)", full)
        elif _close(a, right**2, right**2):
            _variance_slip(report, "std-as-variance", e, a, right, _SQUARED, full)
        elif k == 1 and _close(a, (10 * sd[k]) ** 2, (10 * sd[k]) ** 2):
            _variance_slip(report, "units", e, a, right, f"that is ({math.sqrt(a):g} m/s)², a "
                           f"slip of a factor 10 in the standard deviation: 4 cm/s in m/s (a "
                           f"comment of report 000 makes the same slip)", full)
        elif k == 1 and _close(a, (100 * sd[k]) ** 2, (100 * sd[k]) ** 2):
            _variance_slip(report, "units", e, a, right, "this is (4 cm/s)² in cm²/s²; the "
                           "state is in m and m/s", full)
    rest = V.copy()
    np.fill_diagonal(rest, np.diag(want))
    if len(report.findings) == findings_before or not _same(rest, want):
        fixed = V.copy() if len(report.findings) == findings_before else rest
        _element_finding(report, "v-element", "V", fixed, want,
                         {(0, 0): "(1 m)²", (1, 1): "(0.04 m/s)²", (0, 1): "0", (1, 0): "0"},
                         "V = diag(σ_p², σ_v²): the two GPS noises are independent.")


def _check_W(report: Report, W: np.ndarray, model: CalibrationModel) -> None:
    a, right = float(W.reshape(-1)[0]), float(model.W[0, 0])
    if _close(a, right, right):
        return
    sd = math.sqrt(right)
    full = f"W = {a:g}; W = σ_w² = {right:g} (m/s²)² (σ_w = {sd:g} m/s²)."
    if _close(a, sd, sd):
        _variance_slip(report, "std-as-variance", "W", a, right, _SIGMA, full)
    elif _close(a, right**2, right**2):
        _variance_slip(report, "std-as-variance", "W", a, right, _SQUARED, full)
    elif _close(a, float(model.V[1, 1]), float(model.V[1, 1])):
        _variance_slip(report, "w-value", "W", a, right, "this is the GPS velocity-noise "
                       "variance V₂₂, not the accelerometer's (report 001 writes 0.0016)", full)
    else:
        _variance_slip(report, "w-value", "W", a, right, "this is not the accelerometer's "
                       "white-noise variance", full)


def _check_M0(report: Report, M0: np.ndarray, model: CalibrationModel) -> None:
    want = model.M0
    if _same(M0, want):
        return
    swapped = want.copy()
    swapped[[0, 1], [0, 1]] = want[[1, 0], [1, 0]]
    if _same(M0, swapped):
        _add(report, "m0-order", "Your M0's diagonal ({d}) has position and velocity swapped: "
             "the state is [δp, δv, b] (report 001 writes it swapped).", f"M0 has position and velocity "
             f"swapped: M0 = diag({want[0, 0]:g} m², {want[1, 1]:g} (m/s)², {want[2, 2]:g} "
             f"(m/s²)²).", where="M0", expected={"M0": np.diag(want).tolist()},
             d=", ".join(f"{M0[k, k]:g}" for k in range(3)))
        return
    before = len(report.findings)
    var_units = tuple(u if "/" not in u else f"({u})" for u in STATE_UNITS)
    var_units = tuple(u + "²" for u in var_units)
    for k in range(3):
        a, right = float(M0[k, k]), float(want[k, k])
        if _close(a, right, right):
            continue
        e, sd = _elem("M0", k, k), math.sqrt(right)
        full = f"{e} = {a:g}; {e} = σ² = {right:g} {var_units[k]} (σ = {sd:g} {STATE_UNITS[k]})."
        if _close(a, sd, sd):
            _variance_slip(report, "std-as-variance", e, a, right, _SIGMA + (
                " (report 003 puts σ_p = 10 into M0)" if k == 0 else ""), full)
        elif _close(a, right**2, right**2):
            _variance_slip(report, "std-as-variance", e, a, right, _SQUARED, full)
        elif k == 1 and _close(a, model.v0_mean, model.v0_mean):
            _variance_slip(report, "m0-element", e, a, right, "this is the prior mean v̄0, not "
                           "a variance", full)
    rest = M0.copy()
    np.fill_diagonal(rest, np.diag(want))
    if len(report.findings) == before or not _same(rest, want):
        fixed = M0.copy() if len(report.findings) == before else rest
        _element_finding(report, "m0-element", "M0", fixed, want,
                         {(0, 0): "(10 m)²", (1, 1): "(1 m/s)²", (2, 2): "0.01 (m/s²)²"},
                         "M0 = diag(M_p, M_v, M_b): p0, v0 and b are independent a priori.")


def _check_Q(report: Report, Q: np.ndarray, dt: float, model: CalibrationModel) -> None:
    W = float(model.W[0, 0])
    one = gamma(model.dt) @ gamma(model.dt).T * W
    per_interval = gamma(model.gps_interval) @ gamma(model.gps_interval).T * W
    summed = epoch_transition(phi(model.dt), one, model.gps_every)[1]
    step_is_gps = _close(dt, model.gps_interval, dt)
    want = summed if step_is_gps else gamma(dt) @ gamma(dt).T * W
    if _same(Q, want):
        return
    n, T = model.gps_every, model.gps_interval
    if _same(Q, per_interval):
        _add(report, "process-noise-interval", "Your Q = Γ(T) W Γ(T)ᵀ with T the GPS interval. "
             "Stepping once over T with Φ(T) is exact for the mean, but the noise of every "
             "accelerometer sample in T adds up as Σ_(j<n) Φʲ Γ W Γᵀ Φʲᵀ (report 003 makes "
             "this mistake).", f"Q = Γ(T) W Γ(T)ᵀ with T = {T:g} s: Q₂₂ should be "
             f"{n}·Δt²·W = {summed[1, 1]:.4g}, not T²·W = {per_interval[1, 1]:.4g}.",
             where="Q", expected={"Q₂₂": float(summed[1, 1])})
        return
    if step_is_gps and _same(Q, one):
        _add(report, "q-element", "Your Q = Γ W Γᵀ of one accelerometer step, but your filter "
             "steps once per GPS interval: it must add the noise of every accelerometer step "
             "in it, Σ_(j<n) Φʲ Γ W Γᵀ Φʲᵀ.", f"Q is one accelerometer step's; it must add "
             f"{n} steps (Q₂₂ = {summed[1, 1]:.4g}).", where="Q",
             expected={"Q₂₂": float(summed[1, 1])})
        return
    if not step_is_gps and _same(Q, summed):
        _add(report, "q-element", "Your Q is the process noise of a GPS-rate filter; checked "
             "for the accelerometer step it should be Γ W Γᵀ. Pass the GPS interval as dt if "
             "your filter steps only at GPS times.", f"Q is the {n}-step process noise; "
             f"checked for Δt = {dt:g} s it should be Γ W Γᵀ.", where="Q")
        return
    _element_finding(report, "q-element", "Q", Q, want, {},
                     f"Q = {f'Σ_(j<{n}) Φʲ Γ W Γᵀ Φʲᵀ' if step_is_gps else 'Γ W Γᵀ'} with "
                     f"Δt = {model.dt:g} s and W = {W:g}.")


def model_matrices(Phi: object = None, Gamma: object = None, H: object = None, V: object = None,
                   W: object = None, M0: object = None, dt: float = 0.005, Q: object = None,
                   model: CalibrationModel | None = None) -> Report:
    """Check the matrices a student passes against the report-000 problem.

    Parameters
    ----------
    Phi, Gamma, H, V, W, M0 : the student's Φ (3x3), Γ (3x1 or 3), H (2x3), V (2x2, m², (m/s)²),
        W (scalar or 1x1, (m/s²)²), M0 (3x3); any left as None is not checked.
    dt : the step (s) the student's Φ, Γ and Q are for: 0.005 (the accelerometer) or the GPS
        interval 0.2 for a filter that steps only at GPS times.
    Q : the process-noise covariance per step (3x3), if the student forms it (filterpy's ``Q``).
    model : the problem (report 000's defaults when None).

    Returns a :class:`~gpsaccel.check.report.Report`; it never raises on a student's input.
    """
    t0 = time.perf_counter()
    model = CalibrationModel() if model is None else model
    report = Report("model matrices")
    given = {k: v for k, v in (("Phi", Phi), ("Gamma", Gamma), ("H", H), ("V", V), ("W", W),
                               ("M0", M0), ("Q", Q)) if v is not None}
    if not given:
        report.add("nothing-to-check", text="No matrix was passed: call model_matrices(Phi=..., "
                   "Gamma=..., H=..., V=..., W=..., M0=...) with the ones you use.")
    step = _step(report, dt, model)
    step_is_gps = math.isclose(step, model.gps_interval, rel_tol=1e-9)
    meaning = {
        "Phi": ((3, 3), "Φ maps the state [δp, δv, b] to the next step", ()),
        "Gamma": ((3, 1), "Γ maps the scalar accelerometer noise w into [δp, δv, b]",
                  ((3,),)),
        "H": ((2, 3), "GPS measures δp and δv (2 rows) of the 3-state [δp, δv, b]", ()),
        "V": ((2, 2), "one variance per GPS component, position and velocity", ()),
        "W": ((1, 1), "the accelerometer noise w is a scalar", ((), (1,))),
        "M0": ((3, 3), "the prior covariance of [δp, δv, b]", ()),
        "Q": ((3, 3), "the process-noise covariance of [δp, δv, b]", ()),
    }
    arrays: dict[str, np.ndarray] = {}
    for name, value in given.items():
        arr = as_array(report, name, value, text=_VALUES_SHOWN)
        if arr is None:
            continue
        want, text, also = meaning[name]
        arr = _shape(report, name, arr, want, text, also)
        if arr is not None:
            arrays[name] = arr
    _check_arrays(report, arrays, step, step_is_gps, model)
    report.details = {"dt": step, "checked": sorted(arrays)}
    if report.passed:
        report.add("ok", f"{', '.join(sorted(arrays))}: every element matches the problem "
                   f"(Δt = {step:g} s, relative tolerance {RTOL:g}).", "note",
                   text="{names}: every element matches the problem (relative tolerance "
                   "{rtol:g}).", observed={"names": ", ".join(sorted(arrays)), "rtol": RTOL})
    report.sort()
    report.seconds = time.perf_counter() - t0
    return report


def _step(report: Report, dt: float, model: CalibrationModel) -> float:
    """The step the student's matrices are for: ``dt`` when it is Δt or the GPS interval, else
    Δt with a finding."""
    try:
        step = float(dt)
    except (TypeError, ValueError):
        step = float("nan")
    valid = (model.dt, model.gps_interval)
    if not any(math.isclose(step, s, rel_tol=1e-9) for s in valid):
        _add(report, "dt", "dt = {dt}: it must be the accelerometer interval Δt, or the GPS "
             "interval for a filter that steps only at GPS times (report 001 writes 0.02 s for "
             "0.2 s). Checking against the accelerometer interval.", f"dt = {dt!r}: the "
             f"accelerometer interval is Δt = {model.dt:g} s ({1 / model.dt:g} Hz); the GPS "
             f"interval {model.gps_interval:g} s.", where="dt",
             expected={"dt": (model.dt, model.gps_interval)}, dt=repr(dt)[:40])
        step = model.dt
    return step


def _check_arrays(report: Report, arrays: dict[str, np.ndarray], step: float, step_is_gps: bool,
                  model: CalibrationModel) -> None:
    """Each matrix that has the right shape, against the problem's."""
    if "Phi" in arrays:
        _check_phi(report, arrays["Phi"], step, model)
    if "Gamma" in arrays:
        _check_gamma(report, arrays["Gamma"], step, model)
        if step_is_gps and "Q" not in arrays and _same(arrays["Gamma"], gamma(step)):
            _add(report, "process-noise-interval", "Γ is built with the GPS interval {step:g} s: "
                 "Γ W Γᵀ is then not the noise of the accelerometer samples in that interval "
                 "(their sum Σ_(j<n) Φʲ Γ W Γᵀ Φʲᵀ is). Pass the Q you use to check it.",
                 f"Γ is built with the GPS interval {step:g} s; Q is the sum over "
                 f"{model.gps_every} samples.", where="Γ", expected={"n": model.gps_every},
                 step=step)
    if "H" in arrays and not _same(arrays["H"], model.H):
        _element_finding(report, "h-element", "H", arrays["H"], model.H, {},
                         "GPS measures δp and δv, not the bias.", _measures(arrays["H"]))
    for name, check in (("V", _check_V), ("W", _check_W), ("M0", _check_M0)):
        if name in arrays:
            if name in ("V", "M0"):
                a = arrays[name]
                if not np.allclose(a, a.T, rtol=RTOL, atol=0):
                    report.add("not-symmetric", text="{name} is not symmetric: {values}.",
                               where=name, observed={"name": name, "values": a.tolist()})
            check(report, arrays[name], model)
    if "Q" in arrays:
        _check_Q(report, arrays["Q"], step, model)


def assert_model_matrices(**kwargs: Any) -> Report:
    """:func:`model_matrices` for a grader cell: raise AssertionError with the findings if it fails."""
    report = model_matrices(**kwargs)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
