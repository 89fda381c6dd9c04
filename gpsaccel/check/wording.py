"""The student's wording of every finding code that has no template of its own, as data.

A finding made with prose only (``Report.add(code, message)``: the instructor's text, which may
quote expected values) is shown to a student through this table: the template of its code,
filled with the finding's ``where`` and observed fields only (:mod:`gpsaccel.check.report`).
The templates name no expected value and no number of the reference; the one field every
finding has is ``{where}`` (may be "").  A catalogue's diagnosis adds what the student's filter
was recognised as doing (its entry's variant) after the code's text.

Each system's own table (:data:`gpsaccel.calibration.mistakes.MESSAGES`,
:data:`gpsaccel.kalman.linear_messages.MESSAGES`, :data:`gpsaccel.ship.mistakes.MESSAGES`,
:data:`gpsaccel.coop.mistakes.MESSAGES`) and the sandbox's outcomes
(:data:`gpsaccel.sandbox.outcomes.OUTCOMES`) hold the instructor's templates, which a student
reads only filled with observed fields; this table is the fallback that never quotes a number.
A code missing here reads :data:`UNWORDED`.
"""

from __future__ import annotations

#: A code without wording: its name only (tests require every catalogue code to have wording).
UNWORDED = "{code}: see the question and the lesson on this point."

#: code -> the student's template (fields: ``where`` and the finding's observed fields).
STUDENT: dict[str, str] = {
    # ----------------------------------------------------------------- answers and matrices
    "not-defined": "{where} is not defined (or still `...`) after the notebook has run.",
    "not-callable": "{where} must be a function.",
    "not-a-matrix": "{where} must be an array of numbers.",
    "not-a-number": "{where} must be one finite number.",
    "not-finite": "{where} contains NaN or inf.",
    "shape": "{where} does not have the shape the question asks for.",
    "returns-none": "{where} returned None: end it with a return statement.",
    "exception": "{where} raised an exception.",
    "nothing-to-check": "No matrix was passed to the check.",
    "dt": "The step dt passed to the check is neither the accelerometer interval nor the GPS "
          "interval of the problem.",
    "not-symmetric": "{where} is not symmetric: a covariance matrix always is.",
    "phi-sign": "A sign of Φ is wrong: look at how each state enters the others.",
    "update-every-step": "Your filter updates at every propagation step, between the arrivals "
                         "too: only the steps where a measurement arrives update, the others "
                         "only propagate.",
    "state-order": "Your H is written for another order of the state than the problem's: its "
                   "columns must follow the problem's state order, as Φ and M0 do.",
    "phi-interval": "Your Φ is built with another time step than the one it is checked for.",
    "phi-element": "Some elements of Φ are wrong ({where}): compare each with its formula in "
                   "terms of Δt.",
    "gamma-sign": "Γ has the wrong sign: the accelerometer noise enters a_c = a + b + w.",
    "gamma-interval": "Your Γ is built with another time step than one accelerometer sample.",
    "gamma-element": "Some elements of Γ are wrong ({where}).",
    "h-element": "Some elements of H are wrong ({where}): which state components does GPS "
                 "measure?",
    "v-element": "Some elements of V are wrong ({where}): V holds the variances of the GPS "
                 "noises, which are independent.",
    "m0-element": "Some elements of M0 are wrong ({where}): M0 holds the prior variances of "
                  "the state's components.",
    "q-element": "Your process noise Q is wrong ({where}): it is the noise the accelerometer "
                 "adds over one step of your filter.",
    "w-value": "Your W is not the accelerometer's white-noise variance.",
    "units": "A unit slip in {where}: the state is in m and m/s.",
    "std-as-variance": "A standard deviation is used where a variance belongs (or a variance "
                       "is squared again): a covariance holds variances σ².",
    "m0-order": "M0 has two state components swapped: its diagonal follows the order of the "
                "state vector.",
    "process-noise-interval": "The process noise between two measurements is not the noise of "
                              "one long step: the noise of every propagation step adds up "
                              "(sum Q over the steps).",
    "matrix-value": "{where} is wrong.",
    "sigma-value": "{where} is wrong.",
    "jacobian-A": "Some elements of your A = ∂f/∂x are wrong.",
    "jacobian-B": "Some elements of your B = ∂f/∂u are wrong.",
    "jacobian-C": "Some elements of your C = ∂h/∂x are wrong.",
    "omega-dt-gamma": "{where} is wrong: check how the turn rate and the step enter it.",
    "zero-order-hold": "{where} is not the zero-order-hold discretisation.",
    # ------------------------------------------------------------------------ the NEES
    "nees-sum": "Your NEES is the sum over the runs; the question asks for the ensemble average.",
    "nees-not-inverted": "Your NEES weighs the error by P; the NEES weighs it by the inverse "
                         "covariance, eᵀ P⁻¹ e (np.linalg.solve(P, e)).",
    "nees-diagonal": "Your NEES uses only the variances (Σ eᵢ²/Pᵢᵢ); the NEES is eᵀ P⁻¹ e with "
                     "the whole P (its correlations).",
    "nees-per-state": "Your NEES is divided by the number of states; the NEES is eᵀ P⁻¹ e.",
    "nees-value": "Your average NEES is not the ensemble average at the last time: use the "
                  "errors and covariances of the last GPS time, over every run.",
    "nees-bounds": "Your NEES bounds are not the two-sided 95 % bounds of the average of N runs: "
                   "work out the distribution of the sum of the runs' NEES.",
    "nees-bounds-one-run": "Your NEES bounds are those of a single run's NEES; the average of N "
                           "runs is much tighter: work out the distribution of the sum of the "
                           "runs' NEES.",
    # ---------------------------------------------------------------- a whole filter
    "p-depends-on-data": "Your P changes from run to run. In a linear Kalman filter P depends "
                         "only on Φ, Q, H, V and M0, never on the measurements.",
    "aliased-output": "Every row of your output holds the same values: each row is the same "
                      "array object, changed in place. Store a copy at each time.",
    "state-between-calls": "Your filter is right on the first call but not on later ones: "
                           "something survives between calls (a module-level list, a global "
                           "changed in place). Copy globals before changing them.",
    "low-precision": "Your filter computes in single precision (float32): use float64 "
                     "throughout.",
    "p-scaled": "Your P is a multiple of the right one at every time: look at the line that "
                "symmetrises or scales P.",
    "epoch-shift": "Your outputs (x̂, P or both) are stored one epoch off: store x̂ and P of "
                   "time t_k in row k, right after the update with z[k].",
    "last-update-missing": "Your filter is right except at the last time: the update with the "
                           "last measurement is missing.",
    "update-skipped": "At {where} your x̂ and P are the a priori ones: the update there is "
                      "missing, and every later row follows from it.",
    "covariance-update-skipped": "At {where} your P is the a priori M: the covariance update is "
                                 "missing though x̂ used the measurement.",
    "mean-update-skipped": "At {where} your x̂ is the a priori x̄ while P was updated: the mean "
                           "update is missing there.",
    "gain-or-residual": "Your P is recognised but your x̂ is not ({where}): the mistake is in how "
                        "x̂ is formed (gain, residual, the propagated mean, the measurement "
                        "time).",
    "p-mismatch": "Your P does not match the optimal filter; it first departs at {where}.",
    "nan-output": "Your output contains NaN or inf ({where}).",
    "filter-mismatch": "Your x̂ and P differ from the reference filter's ({where}).",
    "ekf-mismatch": "Your EKF's output differs from the reference EKF's ({where}).",
    "update-mismatch": "Your update differs from the optimal one ({where}).",
    "claimed-not-actual": "The covariance your filter reports is not the covariance of its "
                          "actual error.",
    "p-not-positive-definite": "Your P is not symmetric positive definite at some times.",
    "p-not-symmetric": "Your P is not symmetric: the Joseph form keeps it symmetric and "
                       "positive definite.",
    "phi-transposed": "Your filter propagates with Φᵀ instead of Φ.",
    "q-without-gamma": "Your process noise leaves out Γ: the noise enters the state through Γ.",
    "returns-a-priori": "Your filter returns the a priori estimate and covariance (before the "
                        "update); the contract asks for the a posteriori ones.",
    "first-update-skipped": "Your filter does not update with the measurement at t = 0.",
    "predict-before-first-update": "Your filter propagates before its first update: the prior "
                                   "holds at t = 0, where z₀ is taken. Update first, then "
                                   "propagate.",
    "missing-propagation": "Your filter propagates the wrong number of steps between updates.",
    "mean-not-propagated": "Your covariance is propagated between measurements but your "
                           "estimate is not.",
    "x0-total-state": "Your error-state estimate does not start at the prior mean of the error.",
    "no-angle-wrap": "The bearing residuals are not wrapped to [−π, π).",
    "no-state-wrap": "Your heading estimates leave [−π, π): wrap them after each update and "
                     "prediction.",
    "dt-linearization": "{where} is not the course's DT linearization of the model.",
    "process-noise": "Your prediction's process noise is not the Q of one step (M = Φ P Φᵀ + "
                     "Q): it is left out, or grows with the step in another way than the "
                     "model's.",
    "gamma-order": "Your Γ's rows are in another order than the state's: each row of Γ says how "
                   "the noise enters that state.",
    "residual-covariance": "Your gain's residual covariance S leaves out the measurement's "
                           "noise, or puts its standard deviations where its variances belong.",
    "joseph-sign": "Your covariance update (the Joseph form) has a sign wrong: compare each sign "
                   "with the lesson's; the measurement's noise adds uncertainty.",
    "prior-scale": "Your prior covariance M0 is off by a power of ten.",
    "fixes-skipped": "Your filter skips the update at some measurement times (every other "
                     "one): every time a measurement arrives, the filter updates.",
    "measurement-late": "Your update uses the measurement of the time before: the residual "
                        "takes the measurement of the time being updated.",
    "information-vector": "Your information vector weighs z by V where V⁻¹ belongs (your P is "
                          "right, your x̂ is not).",
    "x0-wrong": "Your filter does not start from the prior mean x0 the problem gives.",
    "input-shift": "The known input u is used one step off: u[k] drives the step from t_k to "
                   "t_(k+1).",
    "missing-as-zero": "A measurement that did not arrive (NaN) is used as a measurement of 0: "
                       "leave the components that did not arrive out of the update.",
    "euler-propagation": "Your mean is propagated with one Euler step per sample; integrate the "
                         "motion exactly over each step.",
    "jacobian-point": "A Jacobian is evaluated at the wrong state.",
    "jacobian-sign": "A Jacobian your filter uses has a sign wrong (∂f/∂x: how each heading "
                     "moves the positions).",
    "jacobian-blocks": "A Jacobian your filter uses has its columns for the two vehicles "
                       "swapped (∂h/∂x: the relative position is the UAV's minus the UGV's).",
    "zeroed-gain": "Your update zeroes the gain's columns of the sensors that did not report; "
                   "use only the rows that arrived.",
    "report-covariance": "Your P is (I − K H) M, the covariance of the optimal gain only; use "
                         "the Joseph form.",
    "monorate-gain": "At the GPS fixes your filter applies the monorate filter's gain instead "
                     "of its own.",
    "no-input": "Your prediction leaves out the known input.",
    "inconsistent": "Your errors and your P do not agree over the runs ({where}).",
    # ------------------------------------------------------------------ the sandbox
    "runner": "The check could not run your file.",
    "no-function": "Your file does not define the function the question asks for.",
    "no-file": "The notebook has no `%%writefile` cell for the file the question asks for "
               "(keep the cell's first line as it is).",
    "import-error": "Your file raises an error when it is imported.",
    "return-value": "{where} must return a tuple of the declared outputs.",
    "wrong-shape": "{where} returned arrays of the wrong shape.",
    "not-run": "Not graded: the notebook stopped before this question (see above).",
    "grader-error": "The grader failed on this question; tell your instructor.",
    "uses-checker": "Your file imports gpsaccel, the package that checks it: remove the import.",
    # ------------------------------------------------------------------- information
    "ok": "Right.",
    "matches-optimal": "Your filter matches the optimal filter.",
    "matches-reference": "Your filter matches the reference.",
    "jacobians-right": "Your Jacobians are right.",
    "dt-model-right": "Your DT model is right.",
    "consistent": "Your errors average to zero and match your P.",
    "nees": "Information on your filter's consistency (not part of the verdict).",
    "nees-nis": "Information on the Q passed to your filter (not part of the verdict).",
    "uses-own-jacobian": "Your F, G, H were checked against your own Jacobians.",
}
