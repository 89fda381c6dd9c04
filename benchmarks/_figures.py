"""The figures a benchmark publishes, machine-readable: ``publish({"key": value, ...})``.

``make bench`` (benchmarks/run.py) gives each script the path of its JSON in :data:`ENV`; the script
publishes its figures there, and run.py, once the script has succeeded, writes them beside the
script's table as ``docs/benchmarks/NAME.json`` with the table's sha256, so the table and its
figures are one measurement.  A page of docs/ quotes a figure with a marker right after it,
``49.5 MiB<!-- bench: montecarlo_memory peak_mib/now/30 -->``, and tests/test_published_figures.py
fails when the quoted number is more than 2x off the measured one.  Run alone (no :data:`ENV`), a
script publishes nothing.

Keys are ``/``-separated words (``cpu_s/grade/calibration/filled``); values are plain numbers in
the unit the key names (``_s``: CPU seconds unless ``wall``, ``_mib``, ``_ms``, ``x_``: a ratio).
"""

from __future__ import annotations

import json
import math
import os

ENV = "GPSACCEL_BENCH_FIGURES"


def publish(figures: dict[str, float]) -> None:
    """Write ``figures`` where :data:`ENV` says (nothing when it is unset); every value a finite
    number, every key a marker can name (no space)."""
    for key, value in figures.items():
        if not key or any(c.isspace() for c in key):
            raise ValueError(f"figure key {key!r}: a word (no space)")
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"figure {key!r}: a finite number, got {value!r}")
    path = os.environ.get(ENV)
    if path:
        with open(path, "w", encoding="utf-8") as f:
            json.dump({"figures": figures}, f, indent=1, sort_keys=True)
