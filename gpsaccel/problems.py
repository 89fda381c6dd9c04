"""The package's own problems and their titles, declared to :mod:`gpsaccel.registry`.

A unit of its own, outside ``gpsaccel.check`` and importing only the registry: the command reads
the problems' names and titles from here for its help and for an argument error without
importing the checker (its answer must not wait for ``gpsaccel.check``, let alone numpy), and
each problem module takes its title from here.  ``gpsaccel.check`` imports this module, so
whatever imports a module of ``check`` has declared the problems.  It names the problem modules
as strings: a declaration one floor above the registry, not on its ground floor.
"""

from __future__ import annotations

from gpsaccel import registry

#: The package's own problems, each defined and registered by ``gpsaccel.check.problems.NAME``,
#: and its title, written here once: the command's help and ``--problem`` choices list them before
#: any problem is imported (the help must not wait for numpy), and each problem's class takes its
#: title from here.  A new problem of the package: its module, and one line here.
PROBLEM_TITLES = {
    "calibration": "Report 000: GPS/accelerometer calibration filter (3 states, 200 Hz + 5 Hz GPS)",
    "coop": "Report 002: cooperative localization, EKF and LKF (6 states, 5 measurements)",
    "ship": "Report 004: the ship's multirate GPS/IMU filter (9 states)",
    "tracker": "Tracker: constant velocity, 10 Hz propagation, 2 Hz position fixes (2 states)",
}
registry.provide("problem", tuple(f"gpsaccel.check.problems.{name}" for name in PROBLEM_TITLES),
                 titles=PROBLEM_TITLES)
