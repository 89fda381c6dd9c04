"""What more than one sub-command's flags share: ``--dask``, ``--boxes``, and choices read from
the registry."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterator
from pathlib import Path

#: ``--boxes`` as :func:`gpsaccel.classrun.running.warm_of` takes it.
BOXES = {"auto": None, "warm": True, "cold": False}


def add_boxes(p: argparse.ArgumentParser) -> None:
    """``--boxes auto|warm|cold`` of ``gpsaccel grade`` and ``gpsaccel check``."""
    p.add_argument("--boxes", choices=tuple(BOXES), default="auto",
                   help="warm: start each box from a process that has imported numpy, "
                        "scipy.stats and filterpy, confined as a cold one (as root on Linux, "
                        "without --dask; an error elsewhere); cold: a fresh Python per box; "
                        "auto (default): warm where boxes can start warm (docs/sandbox.md)")


def dask_spec(value: str | None) -> str | None:
    """``--dask local|tcp://host:port`` as an executor spec of :mod:`gpsaccel.executors`."""
    if value is None:
        return None
    if value != "local" and not value.startswith("tcp://"):
        raise ValueError(f"--dask must be 'local' or tcp://host:port, got {value!r}")
    return "dask-local" if value == "local" else value


class Registered:
    """argparse choices read from :mod:`gpsaccel.registry` when first needed (a parse or a
    help text) by a function that imports no homework module (:func:`registered_assignments`),
    so neither building the parser nor its help or errors wait for numpy."""

    def __init__(self, names: Callable[[], tuple[str, ...]]) -> None:
        self._names = names

    def __contains__(self, name: object) -> bool:  # or a folder of the instructor's own
        return name in self._names() or (isinstance(name, str) and Path(name).is_dir())

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())


def registered_assignments() -> tuple[str, ...]:
    import gpsaccel.assignments  # noqa: F401 - declares the homework modules (imports none)
    from gpsaccel import registry

    return registry.assignment_names()
