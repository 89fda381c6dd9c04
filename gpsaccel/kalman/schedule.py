"""Measurement schedules for multirate filtering: which fast steps carry which measurement components.

A filter that predicts at a fast rate (the accelerometer's 200 Hz, the ship's 10 Hz) and updates with
sensors that report more slowly needs to know, at every fast step, which components of z exist.  A
:class:`Schedule` holds exactly that: the fast steps at which *some* component arrives (the update
epochs) and, for each epoch, a mask of the components that arrive.  The calibration problem has one
sensor (GPS, both components every 40 steps); the ship has two (GPS positions every 10 steps, the
IMU every step).  NaN entries in a measurement array remove further components on top of this (an
outage), see :func:`gpsaccel.kalman.multirate.run_multirate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gpsaccel import _validation as _v


@dataclass(frozen=True, eq=False)
class Schedule:
    """Update epochs on a grid of fast steps 0..n_steps.

    Attributes
    ----------
    n_steps : number of fast steps (the grid has n_steps + 1 points, t_k = k·dt).
    steps : (n_epochs,) strictly increasing fast-step indices at which an update happens.
    mask : (n_epochs, dim_z) bool, True where that component is delivered at that epoch.
    """

    n_steps: int
    steps: np.ndarray
    mask: np.ndarray

    def __post_init__(self) -> None:
        n = _v.integer("n_steps", self.n_steps, minimum=0)
        steps = np.asarray(self.steps)
        mask = np.asarray(self.mask)
        if steps.ndim != 1 or not np.issubdtype(steps.dtype, np.integer):
            raise ValueError(f"steps must be a 1-D integer array, got {steps.dtype} {steps.shape}")
        if steps.size and (steps[0] < 0 or steps[-1] > n or np.any(np.diff(steps) <= 0)):
            raise ValueError(f"steps must increase strictly within 0..n_steps={n}")
        if mask.ndim != 2 or mask.shape[0] != steps.size or mask.dtype != bool:
            raise ValueError(
                f"mask must be a boolean array of shape ({steps.size}, dim_z), got "
                f"{mask.dtype} {mask.shape}"
            )
        object.__setattr__(self, "n_steps", n)
        object.__setattr__(self, "steps", steps.astype(np.int64))
        object.__setattr__(self, "mask", mask)

    @property
    def n_epochs(self) -> int:
        return int(self.steps.size)

    @property
    def dim_z(self) -> int:
        return int(self.mask.shape[1])

    @classmethod
    def from_periods(cls, n_steps: int, periods: Sequence[int],
                     offsets: Sequence[int] | None = None) -> Schedule:
        """Component c is delivered at every fast step k with k ≡ offsets[c] (mod periods[c]).

        ``Schedule.from_periods(6000, [40, 40])`` is the calibration GPS (both components at
        steps 0, 40, ..., 6000); ``from_periods(999, [10, 10, 1, ...])`` a 1 Hz GPS beside a
        10 Hz IMU on a 10 Hz grid.
        """
        n_steps = _v.integer("n_steps", n_steps, minimum=0)
        periods = [_v.integer(f"periods[{c}]", p, minimum=1) for c, p in enumerate(periods)]
        if not periods:
            raise ValueError("periods must name at least one measurement component")
        if offsets is None:
            offsets = [0] * len(periods)
        if len(offsets) != len(periods):
            raise ValueError(f"offsets must have {len(periods)} entries, got {len(offsets)}")
        offsets = [_v.integer(f"offsets[{c}]", o, minimum=0) for c, o in enumerate(offsets)]
        k = np.arange(n_steps + 1)[:, None]
        full = (k % np.array(periods)) == (np.array(offsets) % np.array(periods))
        return cls.from_mask(full)

    @classmethod
    def from_rates(cls, n_steps: int, dt: float, rates_hz: Sequence[float]) -> Schedule:
        """Components delivered at ``rates_hz`` (Hz) on a grid of step ``dt`` (s).

        Each rate must divide the grid rate 1/dt exactly (a 3 Hz sensor on a 10 Hz grid is refused).
        """
        dt = _v.positive_float("dt", dt)
        periods = []
        for c, rate in enumerate(rates_hz):
            rate = _v.positive_float(f"rates_hz[{c}]", rate)
            periods.append(_v.whole_multiple(f"1/rates_hz[{c}]", 1.0 / rate, dt, "dt"))
        return cls.from_periods(n_steps, periods)

    @classmethod
    def from_mask(cls, available: np.ndarray) -> Schedule:
        """From an (n_steps + 1, dim_z) availability mask on the fast grid (epochs: rows with any)."""
        available = np.asarray(available)
        if available.ndim != 2 or available.dtype != bool or available.shape[0] < 1:
            raise ValueError(
                f"available must be a boolean (n_steps + 1, dim_z) array, got "
                f"{available.dtype} {available.shape}"
            )
        steps = np.flatnonzero(available.any(axis=1))
        return cls(available.shape[0] - 1, steps, available[steps])
