"""One box, run: start the runner under its confinement and limits (cold or warm: :mod:`.launch`),
supervise it (pipes, deadline, process count), empty it, and name what went wrong (:func:`run`).
The deadline is the fair clock's (:mod:`.clock`): the box's own time, not its waits on a busy
machine."""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from gpsaccel._interrupt import stop_after_cleanup
from gpsaccel.sandbox import _boxuser, fence, warmbox, zygote
from gpsaccel.sandbox._removal import remove_tree
from gpsaccel.sandbox.channel import FrameReader, Refused
from gpsaccel.sandbox.clock import BACKSTOP_FACTOR, BACKSTOP_MARGIN, Clock, clock_detail
from gpsaccel.sandbox.confinement import (
    BOX_PREFIX,
    PACKAGE_DIR,
    _python,
    _site_dirs,
    _write_control,
    check_hide,
    hidden_dirs,
    resolve_backend,
    sweep_stale_boxes,
)
from gpsaccel.sandbox.launch import Prepared, extra_processes
from gpsaccel.sandbox.limits import _confine, _Confinement
from gpsaccel.sandbox.procs import (
    PR_GET_DUMPABLE,
    PR_SET_DUMPABLE,
    _get_subreaper,
    _kill_box,
    _my_children,
    _prctl,
    _proc_table,
    box_processes,
    bwrap_own,
    cpu_seconds,
    set_subreaper,
    start_time,
)
from gpsaccel.sandbox.spec import BoxResult, Call, Limits
from gpsaccel.sandbox.submission import Submission, SubmissionError

_POLL = 0.05  # s between looks at the pipes and the process
#: s between counts of the box's processes, done only where RLIMIT_NPROC does not bind (root): a
#: count scans all of /proc (about 10 ms for 100 processes)
COUNT_EVERY = 0.25


def run(sub: Submission, calls: Sequence[Call], limits: Limits | None = None,
        backend: str = "auto", allow_gpsaccel: bool = False, hide: Sequence[str] = ()
        ) -> BoxResult:
    """Run ``calls`` on the submission in a new box; return only once every process it started
    is dead, its cgroup removed and its folder deleted.  Never raises for anything the
    submission does (ValueError for bad arguments; :class:`~gpsaccel.sandbox.fence.NoFence`, an
    OSError, for a basic box as root that must hide folders where nothing can fence them).
    ``limits`` None is :class:`Limits`().

    ``allow_gpsaccel``: the box may import this package (a notebook using the course's models),
    except the folders ``hide`` (paths relative to the package, e.g. ``"check"``: the caller
    says what its box may not read), which no process of the box can read under either
    backend (bwrap binds empty folders over them; basic: :mod:`gpsaccel.sandbox.fence`)."""
    limits = Limits() if limits is None else limits
    backend = resolve_backend(backend)
    hide = check_hide(hide, allow_gpsaccel)
    with stop_after_cleanup():  # SIGTERM, SIGHUP: the box emptied, then the process ends
        return _run(sub, list(calls), limits, backend, allow_gpsaccel, hide)


def _run(sub: Submission, calls: list[Call], limits: Limits, backend: str, allow_gpsaccel: bool,
         hide: tuple[str, ...]) -> BoxResult:
    t0 = time.perf_counter()
    sweep_stale_boxes()
    tmp = Path(tempfile.mkdtemp(prefix=f"{BOX_PREFIX}{os.getpid()}-"))
    sys_path = _site_dirs()
    if allow_gpsaccel:
        sys_path.insert(0, str(PACKAGE_DIR.parent))
    needed = [sys.base_prefix, sys.prefix, sys.exec_prefix, *sys_path, str(tmp),
              os.path.dirname(_python()), os.path.dirname(os.path.realpath(_python()))]
    hidden = hidden_dirs(allow_gpsaccel, hide)
    z = zygote.serving(backend, allow_gpsaccel, sys_path, limits.memory, hidden)
    confinement = None
    owned: list[int] = []
    try:
        _write_control(tmp / "control", sub, calls, sys_path, allow_gpsaccel,
                       reaper=z is not None and backend == "bwrap")
        confinement = _confine(limits, backend, needed, extra_processes(backend))
        if backend == "basic":
            confinement.fence = fence.choose(
                hidden, confinement.uid is not None,
                str(tmp / "empty"), [p for _, ps in confinement.reveal for p in ps])
        if confinement.uid is not None:
            tmp.chmod(0o711)  # the box's user enters it, lists nothing
        res_r, res_w = os.pipe()
        out_r, out_w = os.pipe()
        go_r, go_w = os.pipe()
        owned += [res_r, res_w, out_r, out_w, go_r, go_w]  # closed once, here or by _Supervisor
        box = Prepared(backend, tmp, sub, limits, allow_gpsaccel, hide, confinement,
                        [res_w, out_w, go_r], owned)
        try:
            if z is not None:
                try:
                    return _Supervisor(box, calls, t0, z).run(res_r, out_r, go_w)
                except warmbox.NotServed:  # the zygote died, or bwrap's pid 1 did not start
                    box.cold_again()
            return _Supervisor(box, calls, t0).run(res_r, out_r, go_w)
        except SubmissionError as exc:  # a file changed into a link since it was loaded
            return BoxResult(backend, failure=exc.code, detail=str(exc),
                             seconds=time.perf_counter() - t0)
    finally:
        _release(owned, confinement)
        remove_tree(str(tmp))


def _release(owned: list[int], confinement: _Confinement | None) -> None:
    """Close what is left of the box's pipes; kill what its uid runs, remove its cgroup, give
    its uid back."""
    for fd in owned:
        try:
            os.close(fd)
        except OSError:
            pass
    if confinement is None:
        return
    if confinement.fence is not None:
        confinement.fence.close()
    if confinement.uid is not None:
        _boxuser.kill_uid(confinement.uid)
        _boxuser.remove_files(confinement.uid)
    if confinement.cgroup is not None:
        confinement.cgroup.remove()
    if confinement.lock is not None:
        _boxuser.release(confinement.lock)


def _runner_pid(pids: set[int]) -> int | None:
    """The runner among a box's processes besides bwrap's own: the first started."""
    started = [(t, pid) for pid in pids for t in [start_time(pid)] if t is not None]
    return min(started)[1] if started else None


class _Supervisor:
    """Supervise one box from its start to its emptying: read both pipes (output tail and limit,
    result frames), watch the deadline and (where nothing else binds them) the process count,
    count what the student left running once the runner has said its last word, then kill
    everything and drain the pipes.  The checker is a subreaper and not dumpable meanwhile.

    The box's first process is the runner (basic) or bwrap around it, started by exec; or, for a
    runner forked from the zygote ``z`` (:class:`gpsaccel.sandbox.warmbox.WarmBox`), the box's
    keeper (basic) or bwrap around the box's pid 1 (bwrap)."""

    KEEP = 1 << 16  # bytes of the student's output kept

    def __init__(self, box: Prepared, calls: list[Call], t0: float,
                 z: zygote.Zygote | None = None) -> None:
        self.box, self.z = box, z
        self.c = c = box.c
        self.backend, self.limits, self.owned, self.t0 = box.backend, box.limits, box.owned, t0
        self.result = BoxResult(self.backend, limit_backend=c.limit_backend, box_user=c.uid,
                                started="cold" if z is None else "warm")
        self.reader = FrameReader(calls)
        self.tail = bytearray()
        self.hit: str | None = None
        self.refused: str | None = None
        self.proc: subprocess.Popen | warmbox.WarmBox | None = None
        self.sel: selectors.BaseSelector | None = None
        self.left: int | None = None
        self.go_w: int | None = None
        self.open_pipes = 2
        self.exited_at: float | None = None
        self.before: set[int] = set()
        self.clock: Clock | None = None
        self.extra = extra_processes(self.backend)
        # a count of the box's processes is needed only where nothing else binds them: root's
        # processes are not counted by RLIMIT_NPROC, and there is neither a cgroup nor a box uid
        self.count = (os.getuid() == 0 or not sys.platform.startswith("linux")) and \
            c.cgroup is None and c.uid is None

    def run(self, res_r: int, out_r: int, go_w: int) -> BoxResult:
        self.go_w = go_w
        was_dumpable = _prctl(PR_GET_DUMPABLE)
        was_subreaper = _get_subreaper()
        set_subreaper(True)
        _prctl(PR_SET_DUMPABLE, 0)  # /proc/<checker>/mem, environ: closed to the student
        self.before = _my_children()
        emptied = False
        try:
            self._start(res_r, out_r)
            self._watch()
            self._empty()
            emptied = True
            self._drain(res_r, out_r)
            self._cgroup_verdict()
        finally:
            if self.proc is not None and not emptied:  # Ctrl-C or an error of ours: the box too
                _kill_box(self.proc, self.before, self.c, self._roots(), self._own(),
                          self.backend == "bwrap")
            if isinstance(self.proc, warmbox.WarmBox):
                self.proc.close()
            if self.sel is not None:
                self.sel.close()
            set_subreaper(bool(was_subreaper))
            if was_dumpable > 0:
                _prctl(PR_SET_DUMPABLE, was_dumpable)
        return self._finish()

    def _start(self, res_r: int, out_r: int) -> None:
        if self.z is None:
            self.proc = self.box.cold(self.extra)
        else:  # the keeper's first word within the box's backstop (a busy machine)
            wait = self.limits.time + min((BACKSTOP_FACTOR - 1) * self.limits.time,
                                          BACKSTOP_MARGIN)
            self.proc = self.box.warm(self.z, self.extra, wait)
            self.box._close_child_fds(self.box.child_fds)
        self.sel = selectors.DefaultSelector()
        self.sel.register(res_r, selectors.EVENT_READ, "res")
        self.sel.register(out_r, selectors.EVENT_READ, "out")

    def _roots(self) -> list[int]:
        """The process trees of the box (bwrap's holds its namespace's)."""
        assert self.proc is not None
        return self.proc.roots if isinstance(self.proc, warmbox.WarmBox) else [self.proc.pid]

    def _own(self) -> set[int]:
        """The box's processes that are not the student's, besides bwrap's (a basic warm box's
        keeper)."""
        return self.proc.own if isinstance(self.proc, warmbox.WarmBox) else set()

    def _not_students(self, table: dict[int, tuple[int, str, str]]) -> set[int]:
        """Every process of the box that is not the student's: :meth:`_own`, and under bwrap
        bwrap's own, known by pid (:func:`~gpsaccel.sandbox.procs.bwrap_own`), never by name."""
        assert self.proc is not None
        own = self._own()
        return (own | bwrap_own(self.proc.pid, table)) if self.backend == "bwrap" else own

    def _runner_exited(self) -> bool:
        assert self.proc is not None
        return self.proc.poll() is not None

    def _watch(self) -> None:
        """Until the deadline, a limit, or the runner's end (its pipes closed, or 0.2 s after
        it exited while a child of the student's holds them)."""
        assert self.proc is not None
        clock = self.clock = Clock(self.limits.time, self.proc.pid, self._find_runner)
        next_count = time.monotonic() + COUNT_EVERY
        while True:
            now = time.monotonic()
            if now >= clock.deadline and clock.expired(now):
                self.hit = clock.verdict(now, self._box_cpu)
                return
            self._read(max(0.0, min(_POLL, clock.deadline - now)))
            if self.hit:
                return
            self._runner_done()
            now = time.monotonic()
            if self._runner_gone(now):
                return
            if now >= next_count:
                next_count = now + COUNT_EVERY
                clock.update()
                if self.count and self._too_many():
                    self.hit = "process-limit"
                    return

    def _find_runner(self) -> int | None:
        """The runner's pid: the keeper's child (warm), the box's first process (basic), else the
        first of its processes that is not bwrap's (None until it has started)."""
        assert self.proc is not None
        if isinstance(self.proc, warmbox.WarmBox):
            return self.proc.runner
        if self.backend != "bwrap":
            return self.proc.pid
        pids = set(box_processes(self.proc.pid, self.before))
        return _runner_pid(pids - self._not_students(_proc_table()))

    def _box_cpu(self) -> float:
        """CPU seconds the box's live processes have used (with the children they waited for)."""
        return cpu_seconds(set(box_processes(self._roots(), self.before)) | self.c.pids())

    def _left_behind(self) -> int:
        """Processes of the box besides the runner and the box's own (bwrap's, a warm box's
        keeper), while the runner waits to exit."""
        pids = set(box_processes(self._roots(), self.before)) | self.c.pids()
        return len(pids - self._not_students(_proc_table()) - {self._find_runner()})

    def _read(self, timeout: float) -> None:
        assert self.sel is not None
        for key, _ in self.sel.select(timeout=timeout):
            data = os.read(key.fd, 1 << 16)
            if not data:
                self.sel.unregister(key.fd)
                self.open_pipes -= 1
            elif key.data == "out":
                self._output(data)
                if self.result.output_bytes > self.limits.output:
                    self.hit = "output-limit"
            elif not self.hit:
                self._feed(data)

    def _output(self, data: bytes) -> None:
        self.result.output_bytes += len(data)
        self.tail += data
        del self.tail[:-self.KEEP]

    def _feed(self, data: bytes) -> None:
        try:
            self.reader.feed(data)
        except Refused as exc:
            self.refused = str(exc)
            self.hit = self.hit or "result-refused"

    def _runner_done(self) -> None:
        """Once the runner said its last word and waits: what else runs, the student left."""
        if self.left is not None or self.go_w is None or not (
                self.reader.done or self.reader.problem is not None):
            return
        assert self.proc is not None
        self.left = self._left_behind()
        os.close(self.go_w)
        self.owned.remove(self.go_w)
        self.go_w = None

    def _runner_gone(self, now: float) -> bool:
        """The runner is gone: its pipes close unless a child of the student's holds them."""
        assert self.proc is not None
        if self.proc.poll() is None:
            return False
        self.exited_at = self.exited_at or now
        return self.open_pipes == 0 or now - self.exited_at > 0.2

    def _too_many(self) -> bool:
        n = len(box_processes(self._roots(), self.before))
        return n - self.extra > self.limits.processes  # under bwrap two bwrap processes stand
        # above the student's

    def _empty(self) -> None:
        """Kill every process of the box; count what the student left.  The runner is still
        alive when its end has not been seen (a warm box's keeper reports it), when the box's
        first process is (basic) or when anything is (bwrap: the PID namespace ends with the
        runner)."""
        assert self.proc is not None
        runner_alive = self.proc.poll() is None
        found = _kill_box(self.proc, self.before, self.c, self._roots(), self._own(),
                          self.backend == "bwrap")
        if self.left is not None:
            self.result.killed = self.left
            return
        warm = isinstance(self.proc, warmbox.WarmBox)
        runner = runner_alive if self.backend == "basic" or warm else bool(found)
        self.result.killed = max(0, found - (1 if runner else 0))

    def _drain(self, res_r: int, out_r: int) -> None:
        """Every writer is dead: what is left in the pipes is all there will be."""
        for fd in (res_r, out_r):
            os.set_blocking(fd, False)
            while True:
                try:
                    data = os.read(fd, 1 << 16)
                except BlockingIOError:
                    break
                if not data:
                    break
                if fd == out_r:
                    self._output(data)
                elif self.refused:
                    break  # refused already: the rest is not read
                else:
                    self._feed(data)
        assert self.proc is not None
        self.result.returncode = self.proc.returncode

    def _cgroup_verdict(self) -> None:
        cg = self.c.cgroup
        if cg is None:
            return
        self.result.memory_peak = cg.memory_peak()
        if not self.hit and cg.memory_killed():
            self.hit = "memory-limit"
        elif not self.hit and cg.fork_refused():
            self.hit = "process-limit"

    def _finish(self) -> BoxResult:
        result, reader = self.result, self.reader
        result.output = self.tail.decode("utf-8", errors="replace")
        result.results = reader.results
        result.problem = reader.problem
        result.forked = reader.forked
        result.seconds = time.perf_counter() - self.t0
        for ev in reader.events:
            if ev.get("t") == "uses-checker":
                result.uses_checker = True
            elif ev.get("t") == "done":
                result.import_seconds = ev.get("import_seconds")
                result.run_seconds = ev.get("run_seconds")
            elif ev.get("t") == "result" and result.returned is None:
                result.returned = ev.get("returned")
        clock = self.clock
        if clock is not None and clock.fair:
            result.waited = clock.waited
        result.failure, result.detail = _failure(result, self.hit, self.refused, reader,
                                                 self.limits, clock)
        return result


def _failure(result: BoxResult, hit: str | None, refused: str | None, reader: FrameReader,
             limits: Limits, clock: Clock | None = None) -> tuple[str | None, str]:
    """The failure code of a box, most telling first."""
    if hit == "result-refused":
        return hit, f"the result channel carried {refused}"
    if hit == "output-limit":
        return hit, f"more than {limits.output} bytes printed"
    if hit == "process-limit":
        return hit, f"more than {limits.processes} processes at once"
    if hit == "memory-limit":
        return hit, (f"the box's processes together used more than {limits.memory:,} bytes "
                     f"(memory, tmpfs files and memfds, counted by its {result.limit_backend})")
    if result.uses_checker and not reader.done:
        return "uses-checker", "an import of the checker's package was attempted"
    problem = reader.problem
    if problem is not None:
        limit = problem.get("limit")
        if limit in ("memory", "file", "process"):
            return f"{limit}-limit", f"{problem.get('exception')} in the student's code"
        return problem["kind"], ""
    if hit in ("timeout", "machine-busy"):
        return hit, clock_detail(hit, limits.time, clock)
    if reader.done:
        return ("uses-checker", "") if result.uses_checker else (None, "")
    # the runner ended without a last frame: which limit, if any, killed it
    rc = result.returncode
    text = result.output[-4000:]
    if rc == -signal.SIGXFSZ:
        return "file-limit", "killed by SIGXFSZ (file size limit)"
    if rc == -signal.SIGXCPU:
        return "timeout", "killed at the CPU-time limit"
    if "MemoryError" in text or "Cannot allocate memory" in text or "std::bad_alloc" in text \
            or "failed to allocate" in text.lower():
        return "memory-limit", "the process ran out of its address space"
    if "Resource temporarily unavailable" in text:
        return "process-limit", "fork() refused"
    return "crashed", f"exit status {rc}"

