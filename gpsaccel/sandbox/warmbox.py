"""One warm box, as its supervisor (:mod:`gpsaccel.sandbox.box`) sees it: the request to a zygote
(:mod:`gpsaccel.sandbox.zygote`) that forks the box's first process, bwrap's box around a pid 1 of
ours for a warm box under bwrap, and :class:`WarmBox`, which stands where a cold box's ``Popen``
stands."""

from __future__ import annotations

import fcntl
import json
import os
import select
import signal
import socket
import struct
import subprocess
import time
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING

from gpsaccel.sandbox._enter import NAMESPACES
from gpsaccel.sandbox.procs import _proc_table

if TYPE_CHECKING:
    from gpsaccel.sandbox.zygote import Zygote

NS_GET_USERNS = 0xB701

#: The longest report line of a keeper or of a box's pid 1 (``{"exit": status}``, ``PID STATUS``):
#: anything longer is no report of ours, and the box ends as killed.
MAX_LINE = 256


class NotServed(Exception):
    """The zygote cannot start this box (it died; bwrap made no box around its pid 1): the box
    starts cold."""


class WarmBox:
    """A warm box's first process as the supervisor sees a cold box's ``Popen``: ``pid``,
    :meth:`poll` and :meth:`wait` (the runner's end), ``returncode`` (the runner's, as a cold box
    reports it), plus ``runner`` (its pid), ``roots`` (the process trees the box lives in) and
    ``own`` (the box's processes that are not the student's, besides bwrap's own:
    :func:`gpsaccel.sandbox.procs.bwrap_own`).

    basic: the first process is the box's keeper, which reports the runner's end over ``conn``
    (a signal as a negative number, as Popen gives it).  bwrap: it is bwrap, whose pid 1 (the
    reaper) reports on ``reaper`` the end of every process it reaps (bwrap's numbering: 128 +
    the signal)."""

    def __init__(self, backend: str, first: dict, conn: socket.socket | None = None,
                 bwrap: subprocess.Popen | None = None, reaper: int | None = None,
                 runner: int | None = None, buffered: bytes = b"") -> None:
        self.backend, self.conn, self.bwrap, self.reaper = backend, conn, bwrap, reaper
        self.keeper: int = first["first"]
        self.pid = bwrap.pid if bwrap is not None else self.keeper
        # bwrap: the keeper said the runner's pid in the box's numbering (the reaper's)
        self.inside: int | None = first["runner"] if bwrap is not None else None
        self.runner: int = first["runner"] if runner is None else runner
        self.returncode: int | None = None
        self.exited = False  # the runner's end was seen
        # what came with the first word (basic: the keeper's report of a runner that ended at
        # once, sent before the supervisor read the first word)
        self.buffer = buffered
        self.gone = False  # the reporting end closed: nothing more will come

    @property
    def roots(self) -> list[int]:
        return [self.pid]

    @property
    def own(self) -> set[int]:
        return {self.keeper}

    def _fd(self) -> int:
        if self.bwrap is not None:
            assert self.reaper is not None
            return self.reaper
        assert self.conn is not None
        return self.conn.fileno()

    def _ended(self, status: int) -> None:
        code = os.waitstatus_to_exitcode(status)
        self.returncode = 128 - code if self.backend == "bwrap" and code < 0 else code
        self.exited = True

    def _read(self, timeout: float | None) -> None:
        if not self.gone:
            ready, _, _ = select.select([self._fd()], [], [], timeout)
            if ready:
                data = os.read(self._fd(), 1 << 16)
                self.gone = not data
                self.buffer += data
        *lines, self.buffer = self.buffer.split(b"\n")  # one pass: linear in what came
        for line in lines:
            self._line(line)
        if len(self.buffer) > MAX_LINE:  # not our reporter's: the box's pid 1 runs as its uid
            self.buffer, self.gone = b"", True
        if self.exited:
            return
        if self.bwrap is not None and self.bwrap.poll() is not None:  # its pid 1 ended
            self.exited, self.returncode = True, self.bwrap.returncode
        elif self.gone:  # the keeper was killed before it reported the runner's end
            self._ended(signal.SIGKILL)

    def _line(self, line: bytes) -> None:
        if self.exited:
            return
        if self.bwrap is not None:
            pid, _, status = line.partition(b" ")
            if pid.isdigit() and int(pid) == self.inside and status.strip().isdigit():
                self._ended(int(status))
        else:
            message = json.loads(line)
            if "exit" in message:
                self._ended(int(message["exit"]))

    def poll(self) -> int | None:
        self._read(0)
        return self.returncode if self.exited else None

    def wait(self, timeout: float | None = None) -> int:
        """The runner's end; with a timeout, subprocess.TimeoutExpired."""
        give_up = None if timeout is None else time.monotonic() + timeout
        while not self.exited:
            left = None if give_up is None else give_up - time.monotonic()
            if left is not None and left <= 0:
                raise subprocess.TimeoutExpired("the warm box", timeout or 0.0)
            self._read(0.05 if left is None else min(left, 0.05))
        assert self.returncode is not None
        return self.returncode

    def close(self) -> None:
        """The box is empty: the keeper may go (it exits when the connection closes)."""
        if self.conn is not None:
            self.conn.close()
        if self.reaper is not None:
            os.close(self.reaper)
        if self.bwrap is not None:
            self.bwrap.wait()


def outside_pid(inside: int, pidns: str, candidates: Iterable[int]) -> int | None:
    """The pid, in this process's numbering, of the process numbered ``inside`` in the PID
    namespace ``pidns`` (its /proc/<pid>/ns/pid link), among ``candidates`` (the box's)."""
    for pid in candidates:
        try:
            if os.readlink(f"/proc/{pid}/ns/pid") != pidns:
                continue
            with open(f"/proc/{pid}/status", encoding="ascii") as f:
                for line in f:
                    if line.startswith("NSpid:") and int(line.split()[-1]) == inside:
                        return pid
        except (OSError, ValueError):
            continue
    return None


#: Boxes this process started warm (for tests and benchmarks: a box's :attr:`BoxResult.started`
#: says it too).
SERVED = [0]


def request(z: Zygote, backend: str, req: dict, fds: dict[str, int], wait: float,
            bwrap: subprocess.Popen | None = None, reaper: int | None = None,
            box_pids: Callable[[], set[int]] | None = None) -> WarmBox:
    """Ask the zygote for a box: connect, send the request and its descriptors, and read the
    keeper's first word (its pid and the runner's).  Under bwrap, the runner's pid is found among
    ``box_pids()`` from its number in the box, and the runner is let go (``fds["start"]``'s
    other end, made here) once the keeper has left and been reaped.  NotServed when the zygote
    cannot be reached; subprocess.SubprocessError when the box's setup failed (as Popen raises
    when its preexec_fn did)."""
    start_r = start_w = None
    if bwrap is not None:
        start_r, start_w = os.pipe()
        fds = dict(fds, start=start_r)
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        folder = os.open(z.folder, os.O_PATH | os.O_DIRECTORY)  # a short path to the socket
        try:  # (AF_UNIX takes 108 bytes; the folder is in TMPDIR, which may be longer)
            conn.connect(f"/proc/self/fd/{folder}/socket")
        finally:
            os.close(folder)
        payload = json.dumps(dict(req, fds=list(fds))).encode()
        socket.send_fds(conn, [struct.pack(">I", len(payload)) + payload], list(fds.values()))
        if start_r is not None:
            os.close(start_r)
            start_r = None
        first, rest = _first_word(conn, wait)
        if "error" in first:
            raise subprocess.SubprocessError(f"the warm box did not start: {first['error']}")
        SERVED[0] += 1
        if bwrap is None:
            return WarmBox(backend, first, conn=conn, buffered=rest)
        conn.close()  # the keeper leaves: the box's pid 1 reports from here on
        pidns = os.readlink(f"/proc/self/fd/{fds['pid']}")
        runner = outside_pid(int(first["runner"]), pidns, box_pids() if box_pids else ())
        if runner is None:
            raise subprocess.SubprocessError("the warm box's runner is not in its PID namespace")
        _gone(int(first["first"]), wait)
        assert start_w is not None
        os.write(start_w, b"x")
        return WarmBox(backend, first, bwrap=bwrap, reaper=reaper, runner=runner)
    except ConnectionError as exc:
        conn.close()
        raise NotServed(f"the zygote cannot be reached: {exc}") from None
    except FileNotFoundError as exc:
        conn.close()
        raise NotServed(f"the zygote cannot be reached: {exc}") from None
    except BaseException:
        conn.close()
        raise
    finally:
        for fd in (start_r, start_w):
            if fd is not None:
                os.close(fd)


def _gone(pid: int, wait: float) -> None:
    """Wait until process ``pid`` is reaped (its number is free), at most ``wait`` s."""
    give_up = time.monotonic() + wait
    delay = 0.0005
    while os.path.exists(f"/proc/{pid}"):
        if time.monotonic() > give_up:
            raise OSError(f"the zygote's keeper {pid} did not leave within {wait:g} s")
        time.sleep(delay)
        delay = min(2 * delay, 0.02)


def _first_word(conn: socket.socket, wait: float) -> tuple[dict, bytes]:
    """The keeper's first line, and what came after it in the same reads: under basic the
    keeper's next line, the runner's end, follows at once when the runner ends at once (a
    supervisor that read late had it dropped here, and its box ran to its deadline: "timeout"
    instead of how the runner ended)."""
    data = b""
    give_up = time.monotonic() + wait
    while b"\n" not in data:
        left = give_up - time.monotonic()
        ready, _, _ = select.select([conn], [], [], max(left, 0.0))
        if not ready:
            raise OSError(f"the zygote's box did not start within {wait:g} s")
        chunk = conn.recv(1 << 16)
        if not chunk:
            raise NotServed("the zygote's keeper ended before the box started")
        data += chunk
    line, rest = data.split(b"\n", 1)
    return json.loads(line), rest


def start_reaper(cmd: list[str], cwd: str, env: dict, pass_fds: Sequence[int],
                 preexec: Callable[[], None], wait: float
                 ) -> tuple[subprocess.Popen, int, dict[str, int]]:
    """bwrap around the box's pid 1 (``cmd`` runs :mod:`._reaper`): wait until it runs (the
    namespaces and mounts are made); (bwrap, the reading end of the reaper's reports, the
    descriptors of its namespaces: ``owner`` (the user namespace that owns them), one per
    :data:`._enter.NAMESPACES`, and ``user``).  NotServed when bwrap ends first (the cold box
    then says why)."""
    ready_r, ready_w = os.pipe()
    try:
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=ready_w,
                                stderr=subprocess.DEVNULL, cwd=cwd, env=env, pass_fds=pass_fds,
                                close_fds=True, start_new_session=True, preexec_fn=preexec)
    except BaseException:
        os.close(ready_r)
        raise
    finally:
        os.close(ready_w)
    said = b""
    give_up = time.monotonic() + wait
    while not said.startswith(b"ready\n") and time.monotonic() < give_up:
        ready, _, _ = select.select([ready_r], [], [], 0.5)
        chunk = os.read(ready_r, 6 - len(said)) if ready else b""
        if ready and not chunk:
            break
        said += chunk
    reaper = _child(proc.pid) if said == b"ready\n" else None
    if reaper is None:
        os.close(ready_r)
        proc.kill()
        proc.wait()
        raise NotServed("bwrap made no box around its pid 1")
    try:
        return proc, ready_r, _namespaces(reaper)
    except BaseException:
        os.close(ready_r)
        proc.kill()
        proc.wait()
        raise


def _child(parent: int) -> int | None:
    """The one live child of ``parent``, or None."""
    kids = [p for p, (pp, st, _) in _proc_table().items() if pp == parent
            and st not in ("Z", "X")]
    return kids[0] if len(kids) == 1 else None


def _namespaces(pid: int) -> dict[str, int]:
    fds: dict[str, int] = {}
    try:
        for name in (*NAMESPACES, "user"):
            fds[name] = os.open(f"/proc/{pid}/ns/{name}", os.O_RDONLY | os.O_CLOEXEC)
        fds["owner"] = fcntl.ioctl(fds["ipc"], NS_GET_USERNS)
    except BaseException:
        for fd in fds.values():
            os.close(fd)
        raise
    return fds
