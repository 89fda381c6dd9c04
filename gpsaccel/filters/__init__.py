"""Filters and the drivers that run them: the multirate driver, the hand-written information form."""

from gpsaccel.filters.information import InformationFilter
from gpsaccel.filters.multirate import MultirateResult, run_multirate
from gpsaccel.filters.schedule import Schedule

__all__ = ["InformationFilter", "MultirateResult", "Schedule", "run_multirate"]
