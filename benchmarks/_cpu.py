"""Shared by the start-up, per-file and suite benchmarks: a command's CPU (children included) and
wall, the machine's load, and a before/after table.

CPU is what a shared machine cannot inflate much (wall time was 8–20× CPU at load 10–20): the
user + system seconds of the command and of every descendant it waited for, read from
``getrusage(RUSAGE_CHILDREN)`` before and after.  A process that another one reaps (a daemon left
to init) is not counted; the checker reaps its boxes itself (it is their subreaper).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path


@dataclass
class Sample:
    cpu: float   # user + system seconds, children included
    wall: float  # seconds
    returncode: int
    stdout: str = ""


def run(cmd: Sequence[str], env: dict[str, str] | None = None, cwd: str | None = None,
        timeout: float | None = None) -> Sample:
    """Run ``cmd`` to its end; its CPU (children included) and wall time."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(list(cmd), env=env, cwd=cwd, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Sample(cpu, wall, proc.returncode, proc.stdout)


def load() -> str:
    """The 1, 5 and 15 minute load averages and the CPU count, as one phrase."""
    one, five, fifteen = os.getloadavg()
    return f"load {one:.1f} / {five:.1f} / {fifteen:.1f} (1/5/15 min) on {os.cpu_count()} CPUs"


def median(samples: Sequence[Sample]) -> tuple[float, float]:
    """(median CPU, median wall) of ``samples``."""
    return (statistics.median(s.cpu for s in samples), statistics.median(s.wall for s in samples))


def table(rows: Sequence[tuple[str, dict[str, tuple[float, float]]]], versions: Sequence[str]) -> str:
    """A Markdown table: one row per case, CPU and wall per version, and after/before CPU."""
    head = ["case"] + [f"{v} CPU s" for v in versions] + [f"{v} wall s" for v in versions]
    if len(versions) == 2:
        head.append(f"CPU {versions[1]}/{versions[0]}")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, by_version in rows:
        cpu = [by_version[v][0] if v in by_version else float("nan") for v in versions]
        wall = [by_version[v][1] if v in by_version else float("nan") for v in versions]
        cells = [name] + [f"{c:.2f}" for c in cpu] + [f"{w:.2f}" for w in wall]
        if len(versions) == 2:
            cells.append(f"{cpu[1] / cpu[0]:.2f}" if cpu[0] > 0 else "")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


# ------------------------------------------------------------------------------ side by side
def version_flags(parser: argparse.ArgumentParser, repeats: int) -> None:
    """``--before DIR`` (a checkout of an earlier version) and ``--repeats N``, the flags of every
    script that measures two versions side by side."""
    parser.add_argument("--before", metavar="DIR", default=None,
                        help="a checkout of an earlier version (its gpsaccel/ is imported)")
    parser.add_argument("--repeats", type=int, default=repeats)


def versions(before: str | None, now: Path) -> dict[str, Path]:
    """The checkouts to measure, by name: ``now`` alone, or ``before`` (``--before``) then it;
    each one's ``gpsaccel/`` is put first on ``PYTHONPATH`` (this environment's packages)."""
    return {"now": now} if before is None else {"before": Path(before).resolve(), "now": now}


def medians(cmd: Sequence[str], roots: dict[str, Path], repeats: int, cwd: str | None = None,
            ok: Sequence[int] | None = (0,)) -> dict[str, tuple[float, float]]:
    """``python *cmd`` run ``repeats`` times on each version, the versions alternating (so a
    change of the machine's load meets both); (median CPU, median wall) by version.  ``cwd``: the
    folder to run in (default: an empty one of its own per run); ``ok``: the exit codes that count
    as success (None: any)."""
    samples: dict[str, list[Sample]] = {v: [] for v in roots}
    for _ in range(repeats):
        for version, root in roots.items():
            env = dict(os.environ, PYTHONPATH=str(root), MPLBACKEND="Agg")
            with nullcontext(cwd) if cwd else tempfile.TemporaryDirectory() as folder:
                sample = run([sys.executable, *cmd], env=env, cwd=folder)
            if ok is not None and sample.returncode not in ok:
                raise SystemExit(f"{' '.join(cmd)} ({version}) failed with exit "
                                 f"{sample.returncode}:\n{sample.stdout}")
            samples[version].append(sample)
    return {v: median(s) for v, s in samples.items()}
