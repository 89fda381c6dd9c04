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
    report.add("shape", f"{name} has shape {arr.shape}; it must be {' x '.join(map(str, want))}: "
               f"{meaning}.")
    return None


def _wrong_elements(actual: np.ndarray, expected: np.ndarray) -> list[tuple[int, ...]]:
    scale = float(np.abs(expected).max()) or 1.0
    return [idx for idx in np.ndindex(expected.shape)
            if not _close(float(actual[idx]), float(expected[idx]), scale)]


def _same(actual: np.ndarray, expected: np.ndarray) -> bool:
    return not _wrong_elements(actual, expected)


def _element_finding(report: Report, code: str, name: str, actual: np.ndarray,
                     expected: np.ndarray, formulas: dict[tuple[int, ...], str], hint: str = ""
                     ) -> None:
    parts = []
    for idx in _wrong_elements(actual, expected):
        label = _elem(name, *idx) if len(idx) == 2 else _elem(name, idx[0])
        formula = formulas.get(idx, "")
        value = f"{expected[idx]:.6g}"
        want = f"{formula} = {value}" if formula and formula != value else value
        parts.append(f"{label} = {actual[idx]:.6g}, should be {want}")
    report.add(code, "; ".join(parts) + "." + (f" {hint}" if hint else ""))


def _check_phi(report: Report, Phi: np.ndarray, dt: float, model: CalibrationModel) -> None:
    want = phi(dt)
    if _same(Phi, want):
        return
    formulas: dict[tuple[int, ...], str] = {
        (0, 1): "Δt", (0, 2): "−Δt²/2", (1, 2): "−Δt", (0, 0): "1", (1, 1): "1", (2, 2): "1",
        (1, 0): "0", (2, 0): "0", (2, 1): "0"}
    if _same(Phi, phi(dt, +1.0)):
        report.add("phi-sign", f"Φ₁₃ = {Phi[0, 2]:.6g} has the wrong sign: the bias enters "
                   f"position as −Δt²/2 = {-dt**2 / 2:.6g}. Likely cause: the accelerometer reads "
                   f"a + b, so δp = p − p_c loses b·Δt²/2 per step (report 001 prints +½Δt²).")
        return
    if _close(Phi[1, 2], dt, dt) and all(
            _close(float(Phi[idx]), float(want[idx]), 1.0) for idx in np.ndindex(3, 3) if idx[1] != 2):
        flipped = "Φ₁₃ and Φ₂₃ have" if _close(Phi[0, 2], dt**2 / 2, dt**2) else "Φ₂₃ has"
        report.add("phi-sign", f"{flipped} the wrong sign: the bias enters velocity as −Δt = "
                   f"{-dt:.6g} and position as −Δt²/2 = {-dt**2 / 2:.6g}. Likely cause: "
                   f"a_c = a + b + w, so the integrated accelerometer runs ahead of the truth "
                   f"by the bias.")
        return
    other = float(Phi[0, 1])
    for step in (model.dt, model.gps_interval, model.gps_interval / 10):
        if not _close(step, dt, dt) and _close(other, step, step):
            for sign in (-1.0, 1.0):
                if _same(Phi, phi(step, sign)):
                    report.add("phi-interval", f"Your Φ is built with Δt = {step:g} s (Φ₁₂ = "
                               f"{other:g}) but is checked for Δt = {dt:g} s. The accelerometer "
                               f"step is {model.dt:g} s; a filter that steps only at GPS times "
                               f"uses Δt = {model.gps_interval:g} s (pass dt={model.gps_interval:g}"
                               f" to check it that way)."
                               + (" Φ₁₃ also has the wrong sign (phi-sign)." if sign > 0 else ""))
                    return
    _element_finding(report, "phi-element", "Φ", Phi, want, formulas,
                     f"(Δt = {dt:g} s; state [δp, δv, b].)")


def _check_gamma(report: Report, G: np.ndarray, dt: float, model: CalibrationModel) -> None:
    want = gamma(dt)
    if _same(G, want):
        return
    if _same(G, -want):
        report.add("gamma-sign", f"Γ = +[Δt²/2, Δt, 0]ᵀ; it is −[Δt²/2, Δt, 0]ᵀ = "
                   f"[{want[0, 0]:.6g}, {want[1, 0]:.6g}, 0]ᵀ: the accelerometer noise w enters "
                   f"a_c = a + b + w, so δv = v − v_c decreases by w·Δt (report 001 drops the "
                   f"minus sign). The filter itself does not change (only Γ W Γᵀ enters it), "
                   f"but a truth simulated with this Γ does.")
        return
    for step in (model.dt, model.gps_interval, model.gps_interval / 10):
        if not _close(step, dt, dt) and (_same(G, gamma(step)) or _same(G, -gamma(step))):
            report.add("gamma-interval", f"Your Γ is built with Δt = {step:g} s (Γ₂ = "
                       f"{G[1, 0]:g}) but is checked for Δt = {dt:g} s. Γ carries one "
                       f"accelerometer sample's noise: Δt = {model.dt:g} s.")
            return
    _element_finding(report, "gamma-element", "Γ", G[:, 0], want[:, 0],
                     {(0,): "−Δt²/2", (1,): "−Δt", (2,): "0"}, f"(Δt = {dt:g} s.)")


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
        if _close(a, sd[k], sd[k]):
            report.add("std-as-variance", f"{e} = {a:g} is the standard deviation σ = "
                       f"{sd[k]:g} {unit}; V holds variances: {e} = σ² = {right:g} {var}. "
                       f"(Report 003 uses 0.04 as the velocity-noise variance.)")
        elif _close(a, right**2, right**2):
            report.add("std-as-variance", f"{e} = {a:g} = ({right:g})²: the variance was squared "
                       f"again; {e} = σ² = ({sd[k]:g} {unit})² = {right:g} {var}.")
        elif k == 1 and _close(a, (10 * sd[k]) ** 2, (10 * sd[k]) ** 2):
            report.add("units", f"{e} = {a:g} = ({10 * sd[k]:g} m/s)²: 4 cm/s is {sd[k]:g} m/s, "
                       f"not {10 * sd[k]:g} (a comment of report 000 makes the same slip). "
                       f"{e} = {right:g} (m/s)².")
        elif k == 1 and _close(a, (100 * sd[k]) ** 2, (100 * sd[k]) ** 2):
            report.add("units", f"{e} = {a:g} is (4 cm/s)² in cm²/s²; the state is in m and m/s, "
                       f"so {e} = ({sd[k]:g} m/s)² = {right:g} (m/s)².")
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
    if _close(a, sd, sd):
        report.add("std-as-variance", f"W = {a:g} is the standard deviation σ_w = {sd:g} m/s²; "
                   f"W is the variance σ_w² = {right:g} (m/s²)².")
    elif _close(a, right**2, right**2):
        report.add("std-as-variance", f"W = {a:g} = ({right:g})²: the variance was squared again; "
                   f"W = σ_w² = ({sd:g} m/s²)² = {right:g} (m/s²)².")
    elif _close(a, float(model.V[1, 1]), float(model.V[1, 1])):
        report.add("w-value", f"W = {a:g} is the GPS velocity-noise variance V₂₂; the "
                   f"accelerometer noise variance is W = {right:g} (m/s²)² (report 001 writes "
                   f"0.0016).")
    else:
        report.add("w-value", f"W = {a:g}; the accelerometer white-noise variance is "
                   f"W = {right:g} (m/s²)² (σ_w = {sd:g} m/s²).")


def _check_M0(report: Report, M0: np.ndarray, model: CalibrationModel) -> None:
    want = model.M0
    if _same(M0, want):
        return
    swapped = want.copy()
    swapped[[0, 1], [0, 1]] = want[[1, 0], [1, 0]]
    if _same(M0, swapped):
        report.add("m0-order", f"M0 = diag({M0[0, 0]:g}, {M0[1, 1]:g}, {M0[2, 2]:g}) has position "
                   f"and velocity swapped: the state is [δp, δv, b], so M0 = diag({want[0, 0]:g} "
                   f"m², {want[1, 1]:g} (m/s)², {want[2, 2]:g} (m/s²)²) (report 001 writes it "
                   f"swapped).")
        return
    before = len(report.findings)
    units = STATE_UNITS
    var_units = tuple(u if "/" not in u else f"({u})" for u in STATE_UNITS)
    var_units = tuple(u + "²" for u in var_units)
    for k in range(3):
        a, right = float(M0[k, k]), float(want[k, k])
        if _close(a, right, right):
            continue
        e, sd = _elem("M0", k, k), math.sqrt(right)
        if _close(a, sd, sd):
            report.add("std-as-variance", f"{e} = {a:g} is the standard deviation σ = {sd:g} "
                       f"{units[k]}; M0 holds variances: {e} = σ² = {right:g} {var_units[k]}"
                       + (" (report 003 puts σ_p = 10 into M0)." if k == 0 else "."))
        elif _close(a, right**2, right**2):
            report.add("std-as-variance", f"{e} = {a:g} = ({right:g})²: the variance was squared "
                       f"again; {e} = σ² = {right:g} {var_units[k]}.")
        elif k == 1 and _close(a, model.v0_mean, model.v0_mean):
            report.add("m0-element", f"{e} = {a:g} is the prior mean v̄0 = {model.v0_mean:g} m/s, "
                       f"not a variance; {e} = {right:g} (m/s)².")
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
        report.add("process-noise-interval", f"Q = Γ(T) W Γ(T)ᵀ with T = {T:g} s. Stepping once "
                   f"over T with Φ(T) is exact for the mean, but the noise of {n} accelerometer "
                   f"samples adds up as Σ_(j<{n}) Φʲ Γ W Γᵀ Φʲᵀ: Q₂₂ should be "
                   f"{n}·Δt²·W = {summed[1, 1]:.4g}, not T²·W = {per_interval[1, 1]:.4g} "
                   f"(report 003 makes this mistake).")
        return
    if step_is_gps and _same(Q, one):
        report.add("q-element", f"Q = Γ W Γᵀ of one accelerometer step ({model.dt:g} s), but your "
                   f"filter steps once per GPS interval: it must add the noise of {n} steps, "
                   f"Σ_(j<{n}) Φʲ Γ W Γᵀ Φʲᵀ (Q₂₂ = {summed[1, 1]:.4g}).")
        return
    if not step_is_gps and _same(Q, summed):
        report.add("q-element", f"Q is the {n}-step process noise of a GPS-rate filter; checked "
                   f"for Δt = {dt:g} s it should be Γ W Γᵀ. Pass dt={T:g} if your filter steps "
                   f"only at GPS times.")
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
        report.add("nothing-to-check", "No matrix was passed: call model_matrices(Phi=..., "
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
                   f"(Δt = {step:g} s, relative tolerance {RTOL:g}).", "note")
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
        report.add("dt", f"dt = {dt!r}: the accelerometer interval is Δt = {model.dt:g} s "
                   f"({1 / model.dt:g} Hz); a filter that steps only at GPS times uses the GPS "
                   f"interval {model.gps_interval:g} s (report 001 writes 0.02 s). Checking "
                   f"against Δt = {model.dt:g} s.")
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
            report.add("process-noise-interval", f"Γ is built with the GPS interval "
                       f"{step:g} s: Γ W Γᵀ is then not the noise of the {model.gps_every} "
                       f"accelerometer samples in that interval (their sum Σ_(j<"
                       f"{model.gps_every}) Φʲ Γ W Γᵀ Φʲᵀ is). Pass the Q you use to check it.")
    if "H" in arrays and not _same(arrays["H"], model.H):
        _element_finding(report, "h-element", "H", arrays["H"], model.H, {},
                         "H = [I₂ 0]: GPS measures δp and δv, not the bias.")
    for name, check in (("V", _check_V), ("W", _check_W), ("M0", _check_M0)):
        if name in arrays:
            if name in ("V", "M0"):
                a = arrays[name]
                if not np.allclose(a, a.T, rtol=RTOL, atol=0):
                    report.add("not-symmetric", f"{name} is not symmetric: {a.tolist()}.")
            check(report, arrays[name], model)
    if "Q" in arrays:
        _check_Q(report, arrays["Q"], step, model)


def assert_model_matrices(**kwargs: Any) -> Report:
    """:func:`model_matrices` for a grader cell: raise AssertionError with the findings if it fails."""
    report = model_matrices(**kwargs)
    if not report.passed:
        raise AssertionError("\n" + str(report))
    return report
