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
    "std-as-variance.sigma": "a standard deviation used where a variance belongs",
    "std-as-variance.squared": "a variance squared again, as if it were a standard deviation",
    "std-as-variance.whole": "Every diagonal element of your {name} is wrong the same way: "
                             "{label}. A covariance holds variances σ².",
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
    "update-every-step.next": "Your filter updates at every {step} ({every} per measurement "
                              "interval) with the measurement that arrives at the end of the "
                              "interval, before it has arrived; a measurement arrives every "
                              "{interval:g} s, so only those {step}s update (the others only "
                              "propagate).",
    "process-noise-interval": "Your filter steps once per measurement interval with Φ and Γ "
                              "written for the whole interval T = {interval:g} s. That is exact "
                              "for the mean, but the noise of {every} steps of {dt:g} s adds up "
                              "as Σ_(j<{every}) Φʲ Γ W Γᵀ Φʲᵀ, not as Γ(T) W Γ(T)ᵀ: propagate "
                              "{every} steps, or sum Q over them.",
    "process-noise.zero": "Your prediction adds no process noise (Q = 0): M = Φ P Φᵀ + Q with "
                          "Q = Γ W Γᵀ. Without it the filter grows overconfident and stops "
                          "listening to the measurements.",
    "process-noise.continuous": "Your Q is that of a continuous white noise of spectral density "
                                "W (∫₀^Δt e^(Aτ) G W Gᵀ e^(Aᵀτ) dτ, filterpy's "
                                "Q_continuous_white_noise: it grows like Δt), where the model's "
                                "noise is one value per step held over it: Q = Γ W Γᵀ (like "
                                "Δt²).",
    "process-noise.dt": "Your Q is Γ W Γᵀ multiplied by the step Δt = {dt:g} s, as if W were a "
                        "density; W is the variance of the noise of one step: Q = Γ W Γᵀ.",
    "gamma-order": "Your Γ's rows are written for the state order [{order}]; the state is "
                   "[{states}], and each row of Γ says how the noise enters that state.",
    "gamma-order.transposed": "Your filter uses Γᵀ where Γ belongs: Q = Γ W Γᵀ with Γ's rows the "
                              "states and its columns the noises.",
    "residual-covariance.none": "Your gain leaves V out of the residual covariance: K = M Hᵀ "
                                "(H M Hᵀ)⁻¹, where S = H M Hᵀ + V (the measurement's own noise is "
                                "part of the residual).",
    "residual-covariance.sqrt": "Your gain's residual covariance adds the standard deviations √V "
                                "where the variances belong: S = H M Hᵀ + V.",
    "joseph-sign.minus": "Your covariance update is Joseph's form with a minus: (I − K H) M "
                         "(I − K H)ᵀ − K V Kᵀ. The measurement's noise adds uncertainty: "
                         "+ K V Kᵀ.",
    "joseph-sign.plus": "Your covariance update writes I + K H where Joseph's form has I − K H: "
                        "P = (I − K H) M (I − K H)ᵀ + K V Kᵀ.",
    "prior-scale": "Your prior covariance is {factor:g} × M0: every variance of the prior is off "
                   "by a power of ten (a unit, or σ² against σ, slipped).",
    "fixes-skipped": "Your filter updates only at every other measurement ({which}) and only "
                     "propagates at the others (a counter or a % 2 test in the condition that "
                     "decides when to update): every measurement time updates.",
    "measurement-late": "Your update at each epoch uses the measurement of the epoch before "
                        "(z[k − 1] for z[k]{first}): the residual takes the measurement of the "
                        "time being updated, r = z_k − H x̄_k.",
    "measurement-late.first": ", z[0] at the first",
    "measurement-late.wrap": ", and z[−1], the last row, at the first: Python's negative index",
    "information-vector": "Your information filter's vector adds Hᵀ V z where Hᵀ V⁻¹ z belongs "
                          "(its matrix Y = M⁻¹ + Hᵀ V⁻¹ H is right, so P is): y = M⁻¹ x̄ + Hᵀ V⁻¹ "
                          "z, then solve Y x̂ = y.",
    "x0-wrong.zero": "Your filter starts from x̄₀ = 0; the prior mean of [{states}] is x0 = "
                     "[{x0}].",
    "x0-wrong.first": "Your filter starts from the first measurement (x̄₀ = H⁺ z₀) and then "
                      "updates with z₀ again, so z₀ counts twice. Start from the prior mean x0 = "
                      "[{x0}] and let the first update bring z₀ in.",
    "phi-sign": "Your Φ has {entries} with the wrong sign; the propagation is otherwise right. "
                "Check how each state enters the others.",
    "state-order": "Your H is written for the state order [{order}]; the problem's state is "
                   "[{states}], and Φ, M0 and your outputs follow it. Write H's columns in the "
                   "problem's order.",
    # ----------------------------------------------------------- the checker's findings
    "matches-optimal": "P and x̂ match the optimal filter to {tol:g} σ on all {n_runs} runs.",
    "nan-output": "{name} contains {what} in {bad_runs} of {n_runs} runs; in run {run} first at "
                  "t = {t:g} s (row {row}). {cause}",
    "nan-output.causes": "Likely causes: an array made with np.empty and never filled at that "
                         "row, a division by zero, or the inverse of a singular matrix.",
    "nan-output.runaway": "Before that it had grown to {top:.3g}: your filter runs away "
                          "(each step multiplies its error) until floating point overflows; "
                          "look at how x̂ is formed (the gain; in an information form, x̂ "
                          "solves Y x̂ = y).",
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
    "epoch-shift": "Your {what} shifted by one epoch, {where} (every row but the {end} "
                   "matches the optimal filter shifted{other}). Store x̂ and P of time t_k in "
                   "row k, right after the update with z[k].",
    "epoch-shift.other": "; your {right} is stored right",
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
                        "the prior mean x0 it starts from, K = M Hᵀ (H M Hᵀ + V)⁻¹, x̄ = Φ x̂ at "
                        "every {step}, the residual r = z − H x̄ and x̂ = x̄ + K r, with z at the "
                        "matching time.",
    "gain-or-residual.optimal": "Your P is the optimal one, so Φ, Q, H, V and M0 are right (P does "
                                "not depend on x0 or on z), but",
    "gain-or-residual.matched": "Your P matches {names}, and",
    "p-mismatch": "Your P does not match the optimal filter (it differs by up to {d:.3g} σσ)."
                  "{hint} {where}{depart} {matrices}",
    "p-mismatch.first": "P at t = 0 already differs: the first update uses only M0, H and V, so "
                        "one of them is wrong (or the update formula).",
    "p-mismatch.later": "P at t = 0 is right (so M0, H, V and the update are), but P differs "
                        "from t = {t:g} s on: the propagation between measurements is wrong "
                        "(Φ, Q = Γ W Γᵀ, or the number of steps).",
    "p-mismatch.matrices": "Check your Φ, Γ, W, H, V and M0 against the problem's.",
    "p-not-positive-definite.advice": "The Joseph form, with its signs as the lesson writes "
                                      "them, keeps it one (and P = (P + Pᵀ)/2 against "
                                      "rounding).",
    "p-not-positive-definite.joseph-sign": "That is what the sign slip in your covariance "
                                           "update (above) does: with its signs right, the "
                                           "Joseph form keeps P a covariance.",
    "hint.near": " The nearest known mistake is {names}: your P is within {d:.3g} σσ of it "
                 "({ratio:.2g}× the tolerance), so look there first.",
    "hint.none": " No catalogued mistake matches.",
}
