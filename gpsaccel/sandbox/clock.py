"""The box's fair clock: its time limit counts the time the box's code ran or waited for itself
(a sleep, a pipe, the disk), not the time its runner waited on a busy machine's run queue, which
Linux reports per task (/proc/<pid>/schedstat: ns on a CPU, ns waiting on a run queue,
timeslices).  A correct filter of 5.5 CPU s under a 20 s limit on 2 cores at load 15.7 was timed
out by a wall clock, and its feedback suggested an endless loop; an endless loop or a sleep is
still timed out.  A backstop bounds the wait: a box that reaches it with less than its limit of
its own time is ``machine-busy``, an outcome that is ours, not the student's
(:data:`gpsaccel.sandbox.outcomes.OUTCOMES`).  Where schedstat is missing (not Linux) the limit is
wall-clock, as it was.  :class:`gpsaccel.sandbox.box._Supervisor` reads it in its watch loop.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from gpsaccel.sandbox.procs import lowered_priority, runqueue_wait

#: The fair clock (module docstring); False keeps the wall clock (a knob for tests).
FAIR_CLOCK = True
#: The backstop of the fair clock: a box is stopped, however long it waited for a CPU, once its
#: wall-clock time reaches its limit times BACKSTOP_FACTOR, but never more than BACKSTOP_MARGIN s
#: beyond its limit: 80 s at ``--timeout 20``, 120 s at the check's default 60 s, 180 s at the
#: grader's 120 s, within the batch's slack (120 s beyond the limit) and the grader's, so the
#: box's own verdict comes before the pool's ``lost``.  The factor binds short limits only (tests:
#: an endless loop under a 3 s limit is still a timeout with a tenth of a CPU).
BACKSTOP_FACTOR = 10.0
BACKSTOP_MARGIN = 60.0


def clock_detail(hit: str, limit: float, clock: Clock | None) -> str:
    """The sandbox's account of a box stopped by its clock: its own time, and its wait."""
    if clock is None or not clock.fair:
        return f"still running after {limit:g} s"
    wall = clock.stopped - clock.start
    if hit == "machine-busy":
        return (f"in {wall:.0f} s it ran for {clock.own:.1f} s of its {limit:g} s and "
                f"waited {clock.waited:.0f} s for a processor")
    return (f"still running after {clock.own:.1f} s of its own time, {wall:.1f} s on the clock "
            f"of which {clock.waited:.1f} s waiting for a processor")


class Clock:
    """The box's fair deadline (module docstring): the limit plus what the runner has waited on
    a run queue so far, up to the backstop.

    The wait is the runner's main thread's (the student's functions run in it), plus, under
    bwrap, its first process's (bwrap's setup, before the runner exists).  Not the largest of the
    runner's threads: a thread the student starts, or a BLAS worker, waits for its siblings as
    much as for the machine, and the main thread's wait already covers the time the box's work
    stood still.  The main thread also waits for the box's own other threads and processes;
    RLIMIT_CPU (per process) and, at the backstop, the box's CPU (:meth:`verdict`) bound what
    that can buy: a box that kept itself busy is timed out, not reported as a busy machine."""

    def __init__(self, limit: float, first: int, find_runner: Callable[[], int | None]) -> None:
        self.start = time.monotonic()
        self.limit, self.first, self.find_runner = limit, first, find_runner
        self.backstop = self.start + limit + min((BACKSTOP_FACTOR - 1) * limit, BACKSTOP_MARGIN)
        self.fair = FAIR_CLOCK and runqueue_wait(first) is not None
        self.runner: int | None = None
        self.waits: dict[int, float] = {}
        self.stopped = self.start

    @property
    def waited(self) -> float:
        return sum(self.waits.values())

    @property
    def deadline(self) -> float:
        return min(self.start + self.limit + self.waited, self.backstop)

    @property
    def own(self) -> float:
        """The box's own time when it was stopped: wall-clock less the runner's wait."""
        return self.stopped - self.start - self.waited

    def update(self) -> None:
        """Read the waits again (a task gone keeps its last)."""
        if not self.fair:
            return
        if self.runner is None:
            self.runner = self.find_runner()
        for pid in {self.first, self.runner} - {None}:
            assert pid is not None
            w = runqueue_wait(pid)
            if w is not None:
                self.waits[pid] = max(w, self.waits.get(pid, 0.0))

    def expired(self, now: float) -> bool:
        """Past the deadline with the waits read again now."""
        self.update()
        self.stopped = now
        return now >= self.deadline

    def verdict(self, now: float, box_cpu: Callable[[], float]) -> str:
        """``timeout`` when the box had its limit of its own time, used as much CPU (its own
        processes kept it waiting) or lowered its runner's priority (os.nice: its waits are its
        own); else ``machine-busy``: the backstop, on a machine too busy to tell."""
        if now - self.start - self.waited >= self.limit or box_cpu() >= self.limit or \
                (self.runner is not None and lowered_priority(self.runner)):
            return "timeout"
        return "machine-busy"
