"""The truths a realization is simulated under (:mod:`~gpsaccel.calibration.simulation`): report
000's error model, or the closed-form kinematics of reports 001 and 003.

A module of its own, which imports nothing: the command's ``--truth`` choices are read before
numpy is (its help and argument errors must not wait for it).
"""

TRUTHS = ("error-model", "kinematic")
