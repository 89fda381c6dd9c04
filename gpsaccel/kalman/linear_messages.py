"""The generic linear problem's wording, as data in one place: its catalogue and its checker.

One table, code (or ``code.part``) -> template, read by the generic catalogue
(:class:`gpsaccel.kalman.linear_catalogue.LinearCatalogue`: what each entry says a filter does)
and by the checker of any linear filter (:mod:`gpsaccel.check.linear`: its findings, the parts
of a diagnosis).  A problem rewords any entry with its own table over this one
(``Problem.linear(..., messages=...)``; the calibration problem's is
:data:`gpsaccel.calibration.mistakes.MESSAGES`).  Where the catalogue and a finding share a code,
the catalogue's template is the ``.last`` part (``covariance-update-skipped.last``): the entry
names the last epoch, the finding the row where the output departs.

These are the instructor's texts (they may quote the problem's numbers); a student reads the
code's wording of :data:`gpsaccel.check.wording.STUDENT` filled with observed fields only.
"""

from __future__ import annotations

#: code (or code.part) -> template (fields named in each).
MESSAGES: dict[str, str] = {
    # ------------------------------------------------------------ the catalogue's entries
    "phi-transposed": "Your filter propagates with Φᵀ instead of Φ (x̄ = Φ x̂, M = Φ P Φᵀ + Q): "
                      "a transition matrix written by rows where columns belong, or "
                      "x @ Phi with x a row where Phi @ x is meant.",
    "q-without-gamma": "Your process noise is {used} instead of Q = Γ W Γᵀ: the noise enters "
                       "the state through Γ, so W (a {m}×{m} covariance of the input noise) is "
                       "not the state's process noise.",
    "std-as-variance": "{elem} = {value:.4g} in your filter; it should be {right:.4g}: {label}. "
                       "A covariance holds variances σ² (here σ = {sigma:.4g}, σ² = {right:.4g}).",
    "m0-order": "M0 has {a} and {b} swapped: the state is [{states}], so M0's diagonal is "
                "[{right}]; your filter starts with [{used}].",
    "returns-a-priori": "Your filter returns the a priori estimate and covariance (x̄, M: "
                        "before the update) at each epoch; the contract asks for the a "
                        "posteriori ones (x̂, P: after the update with z at that epoch). Likely "
                        "cause: the values are stored before the update.",
    "first-update-skipped": "Your filter does not use the measurement at t = 0: its first "
                            "estimate is the prior (x̂₀ = x̄₀, P₀ = M0). Update with z₀ before "
                            "the first propagation.",
    "first-update-skipped.covariance": "Your P at t = 0 is the prior M0: the covariance update "
                                       "with z₀ is missing, though your x̂ at t = 0 used z₀; "
                                       "every later gain follows from that P.",
    "last-update-missing.last": "Your filter is right except at the last epoch (t = {t_last:g} s), "
                           "where x̂ and P are the a priori x̄ and M: the update with the last "
                           "measurement is missing (a loop such as range(n - 1)).",
    "covariance-update-skipped.last": "Your P at the last epoch (t = {t_last:g} s) is the a priori "
                                 "M: the covariance update with the last measurement is "
                                 "missing, though your x̂ there used it (the propagation is "
                                 "right: every earlier P matches).",
    "predict-before-first-update": "Your filter propagates before its first update: the "
                                   "{measurement} at t = 0 updates a prior already carried "
                                   "{every} {step}(s) ahead (x̄₀ = Φ^{every} x0, M₀ = Φ^{every} "
                                   "M0 Φ^{every}ᵀ + Q) instead of x0 and M0 themselves, and "
                                   "every later row inherits it. The prior holds at t = 0, "
                                   "where z₀ is taken: update first, then propagate (in a "
                                   "predict-then-update loop, skip the prediction at k = 0).",
    "missing-propagation": "Your filter propagates {steps} step(s) between updates; there are "
                           "{every} (propagation every {dt:g} s, a measurement every "
                           "{interval:g} s).",
    "mean-not-propagated": "Your covariance is propagated between measurements but your "
                           "estimate is not: the residual uses x̂ₖ₋₁ where it should use "
                           "x̄ₖ = Φ^{every} x̂ₖ₋₁.",
    "covariance-update-skipped.never": "Your P is never updated: at every epoch it is the a "
                                       "priori M, though your x̂ is updated with the gain "
                                       "K = M Hᵀ (H M Hᵀ + V)⁻¹. The update of P is missing: "
                                       "P = (I − K H) M (I − K H)ᵀ + K V Kᵀ after each update "
                                       "of x̂.",
    "update-every-step": "Your filter updates at every {step} ({every} per measurement "
                         "interval), reusing the last measurement between arrivals; a "
                         "measurement arrives every {interval:g} s, so only those {step}s "
                         "update (the others only propagate).",
    "phi-sign": "Your Φ has {entries} with the wrong sign; the propagation is otherwise right. "
                "Check how each state enters the others.",
    "state-order": "Your H is written for the state order [{order}]; the problem's state is "
                   "[{states}], and Φ, M0 and your outputs follow it. Write H's columns in the "
                   "problem's order.",
    # ----------------------------------------------------------- the checker's findings
    "matches-optimal": "P and x̂ match the optimal filter to {tol:g} σ on all {n_runs} runs.",
    "nan-output": "{name} contains {what} in {bad_runs} of {n_runs} runs; in run {run} first at "
                  "t = {t:g} s (row {row}). Likely causes: an array made with np.empty and never "
                  "filled at that row, a division by zero, or the inverse of a singular matrix.",
    "p-depends-on-data": "Your P changes from run to run (by up to {spread:.3g} σσ). In a linear "
                         "Kalman filter P depends only on Φ, Q, H, V and M0, never on the "
                         "measurements: compute P without z.",
    "aliased-output": "Every row of your x_hat and P holds the same values, those of the last "
                      "time (t = {t_last:g} s): each row is the same array object, changed in "
                      "place at every step (e.g. x += K @ r or P[:] = ..., then appended to a "
                      "list). Store a copy: x_hat[k] = x (into a preallocated array) or "
                      "xs.append(x.copy()).",
    "state-between-calls": "Your filter is right on the first call but not on later ones: "
                           "{what} first differs on run {run} (by {by:.3g} σ), and {n_bad} of "
                           "{n_runs} runs differ. Something survives between calls: a "
                           "module-level list or array that keeps growing, a global M0 or x0 "
                           "changed in place (M = M0 then M -= ...). Copy globals before "
                           "changing them (M = M0.copy()).",
    "low-precision": "Your filter computes in single precision (float32): its output differs "
                     "from the optimal filter by up to {dP:.2g} σσ in P and {dx:.2g} σ in x̂, "
                     "what float32 rounding (about 6e-8 relative) builds up over {n_steps} "
                     "steps; the tolerance is {tol:g}. This is not a wrong M0, H or V: use "
                     "float64 throughout (no .astype(np.float32), z as given) and check again — "
                     "at float32 precision a small mistake could hide.",
    "p-scaled": "Your P is the optimal P multiplied by one same factor at every time{sym}. "
                "{x_note} M0, H and V are not the problem: look at the line that symmetrises or "
                "scales P.",
    "epoch-shift": "Your outputs are shifted by one epoch, {where} (every row but the {end} "
                   "matches the optimal filter shifted). Store x̂ and P of time t_k in row k, "
                   "right after the update with z[k].",
    "epoch-shift.late": "one time late: row k holds the estimate of time k − 1",
    "epoch-shift.early": "one time early: row k holds the estimate of time k + 1",
    "last-update-missing": "Your filter is right except at the last time (t = {t:g} s), where "
                           "x̂ and P are the a priori x̄ and M: the update with the last "
                           "measurement z[{row}] is missing (a loop such as range(n - 1), or the "
                           "update placed before the propagation).",
    "update-skipped": "Your filter is right up to t = {t_prev:g} s, but at t = {t:g} s (row "
                      "{row}) x̂ and P are the a priori x̄ and M: the update with z[{row}] is "
                      "missing there, and every later row follows from it. Look at the "
                      "condition that decides when to update.",
    "covariance-update-skipped": "At t = {t:g} s (row {row}) your P is the a priori M: the "
                                 "covariance update with z[{row}] is missing, though your x̂ "
                                 "there used it; every earlier row matches, so the propagation "
                                 "is right. Update P with the same gain: P = (I − K H) M "
                                 "(I − K H)ᵀ + K V Kᵀ.",
    "mean-update-skipped": "At t = {t:g} s (row {row}) your x̂ is the a priori x̄ while your P "
                           "was updated: the mean update x̂ = x̄ + K (z − H x̄) with z[{row}] is "
                           "missing there; every earlier row matches.",
    "gain-or-residual": "{lead} your x̂ differs from what that filter gives on the same z by up "
                        "to {dx:.3g} σ ({where}). The mistake is in how x̂ is formed: check "
                        "K = M Hᵀ (H M Hᵀ + V)⁻¹, x̄ = Φ x̂ at every {step}, the residual "
                        "r = z − H x̄ and x̂ = x̄ + K r, with z at the matching time.",
    "p-mismatch": "Your P does not match the optimal filter (it differs by up to {d:.3g} σσ)."
                  "{hint} {where}{depart} {matrices}",
    "p-mismatch.first": "P at t = 0 already differs: the first update uses only M0, H and V, so "
                        "one of them is wrong (or the update formula).",
    "p-mismatch.later": "P at t = 0 is right (so M0, H, V and the update are), but P differs "
                        "from t = {t:g} s on: the propagation between measurements is wrong "
                        "(Φ, Q = Γ W Γᵀ, or the number of steps).",
    "p-mismatch.matrices": "Check your Φ, Γ, W, H, V and M0 against the problem's.",
    "hint.near": " The nearest known mistake is {names}: your P is within {d:.3g} σσ of it "
                 "({ratio:.2g}× the tolerance), so look there first.",
    "hint.none": " No catalogued mistake matches.",
}
