"""The zygote of warm boxes: a clean Python that has imported what every box imports, and that forks
each box's first process on request.  It never runs a student's code itself.

Usage (by :mod:`gpsaccel.sandbox.zygote`, not by hand)::

    python -I -S -B ZDIR/_zygote.py ZDIR CONFIG_JSON

It is started by exec, with the box's interpreter flags and environment, from a folder ZDIR only
root can enter, which holds copies of this file, ``_runner.py`` and ``_enter.py``.  CONFIG_JSON
says which folders to put on ``sys.path`` (the box's) and which modules to import (public
libraries only: numpy, scipy.stats, ...; BLAS with one thread, as the runner sets it).  It then
writes one line of JSON on stdout (its pid, the files of its modules, its address space), points
stdout and stderr at ``/dev/null`` and waits for connections on ``ZDIR/socket``.

Each connection is one box.  The zygote forks and goes back to waiting: it never reads a request,
so nothing of any box passes through its memory.  The child, the box's *keeper* (its first
process), reads the request and the descriptors that come with it (the box's output and result
pipes; the Landlock ruleset, or bwrap's namespaces), then forks the runner:

basic
    The keeper becomes the box's subreaper (what the student's code orphans is re-parented to
    it, not to init) and stays out of the box's cgroup, as a cold box's supervisor does (the
    box's memory, CPU and process limits are the student's alone, and an out-of-memory kill in
    the box never picks the keeper); the runner child does what a cold box's first process does
    between fork and exec (:func:`_enter.enter`: the cgroup, the mounts that reveal the
    interpreter, the fence, the rlimits, the box's uid, no capability, no new privileges, the
    Landlock fence last), in its working folder, session and environment.
bwrap
    bwrap has made the box's namespaces and mounts around the box's pid 1 (:mod:`._reaper`, which
    stands in for bwrap's init); the keeper joins the box's cgroup, takes the box's rlimits and
    uid as bwrap did and joins the namespaces (:func:`_enter.join_namespaces`); the runner child
    is born in the box's PID namespace (forked by a helper born there, which leaves: the kernel
    gives an orphan to the reaper of its parent's namespace), drops every capability the
    namespaces gave it, and waits until the supervisor says the keeper has left (and is reaped:
    it counted in the box's cgroup); it is then the child of the box's pid 1, as a cold runner is
    of bwrap's init, and dies with it.

Either way the runner child then calls the runner's ``main`` in-process, with ``sys.argv``,
``__main__`` and the signal dispositions a cold runner would have, and leaves by ``os._exit``.
The keeper reports ``{"first": pid, "runner": pid}`` once the runner is ready (under bwrap the
runner's pid in the box's own numbering), or why it did not start (``{"error": text}``).  Under
bwrap it then leaves (the box's pid 1 reports how the runner ended).  Under basic it stays, the
runner's parent: it reports the runner's wait status (``{"exit": status}``), reaps what the box
leaves it, and when the connection closes (the supervisor emptied the box, or died) kills what
is left under it and exits.  The zygote dies with the process that started it
(``PR_SET_PDEATHSIG``); a keeper does not die with the zygote but lives as long as its
connection: the supervisor's death, which closes the connection and kills the zygote at once,
must leave the keeper alive to kill its box (with a death signal it died first, and what the
box had forked went to init, spinning on).
"""

from __future__ import annotations

import ctypes
import gc
import importlib
import importlib.util
import json
import os
import select
import signal
import socket
import struct
import sys
import traceback

#: Largest request (bytes of JSON) and most descriptors a request carries.
MAX_REQUEST = 1 << 20
MAX_FDS = 16

PR_SET_PDEATHSIG, PR_SET_CHILD_SUBREAPER = 1, 36


def _load(path: str, name: str):  # noqa: ANN202 - a module
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def main(argv: list[str]) -> None:
    zdir, config = argv[0], json.loads(argv[1])
    sys.path.extend(p for p in config["sys_path"] if p not in sys.path)
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):  # as the runner
        os.environ[var] = "1"
    os.environ["MPLBACKEND"] = "Agg"
    runner = _load(os.path.join(zdir, "_runner.py"), "_gpsaccel_runner")
    enter = _load(os.path.join(zdir, "_enter.py"), "_gpsaccel_enter")
    base = _status("VmSize")
    for name in config["imports"]:
        importlib.import_module(name)
        if name == "numpy":  # what a cold runner holds when the student's code starts
            base = _status("VmSize")
    libc = ctypes.CDLL(None, use_errno=True)
    enter.prctl(libc, PR_SET_PDEATHSIG, signal.SIGKILL)  # dies with its starter
    if os.getppid() != config["parent"]:
        return
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    folder = os.open(zdir, os.O_PATH | os.O_DIRECTORY)  # a short path to it: AF_UNIX takes
    sock.bind(f"/proc/self/fd/{folder}/socket")  # 108 bytes, a long TMPDIR more
    os.close(folder)
    sock.listen(64)
    line = json.dumps({"pid": os.getpid(), "modules": _module_files(),
                       "vmsize": _status("VmSize"), "base_vmsize": base,
                       "threads": _status("Threads")}) + "\n"
    sys.stdout.flush()
    sys.stderr.flush()
    ready = os.dup(1)  # the starter's pipe: said ready only once stdout and stderr are /dev/null
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (1, 2):
        os.dup2(null, fd)
    os.close(null)
    data = line.encode()
    while data:
        data = data[os.write(ready, data):]
    os.close(ready)
    gc.freeze()  # what it imported is never collected in a box: the collector leaves those pages
    _serve(sock, _Box(runner, enter, libc))  # shared, not copied into every box on first touch


def _module_files() -> list[str]:
    out = set()
    for m in list(sys.modules.values()):
        f = getattr(m, "__file__", None)
        if isinstance(f, str):
            out.add(os.path.realpath(f))
    return sorted(out)


def _status(key: str) -> int:
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    return -1


def _serve(sock: socket.socket, box: _Box) -> None:
    """Fork a keeper per connection; reap the keepers as they end (at once: a bwrap box's keeper
    counts in its box's cgroup until it is reaped)."""
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    signal.set_wakeup_fd(wake_w)
    while True:
        ready = select.select([sock.fileno(), wake_r], [], [])[0]
        if wake_r in ready:
            os.read(wake_r, 4096)
        if sock.fileno() in ready:
            conn, _ = sock.accept()
            pid = os.fork()
            if pid == 0:
                signal.set_wakeup_fd(-1)
                signal.signal(signal.SIGCHLD, signal.SIG_DFL)
                sock.close()
                box.keep(conn)  # never returns
            conn.close()
        while True:
            try:
                pid, _ = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if pid == 0:
                break


def _fds_open() -> list[int]:
    return [int(n) for n in os.listdir("/proc/self/fd") if n.isdigit()]


def _close_all_but(keep: set[int]) -> None:
    for fd in _fds_open():
        if fd not in keep:
            try:
                os.close(fd)
            except OSError:
                pass


def _send(conn: socket.socket, message: dict) -> None:
    try:
        conn.sendall(json.dumps(message).encode() + b"\n")
    except OSError:
        pass


def _receive(conn: socket.socket) -> tuple[dict, list[int]]:
    """The request: a 4-byte length, then that many bytes of JSON; the descriptors come with
    the first bytes."""
    data, fds = b"", []
    while len(data) < 4 or len(data) < 4 + struct.unpack(">I", data[:4])[0]:
        chunk, got, _, _ = socket.recv_fds(conn, 1 << 16, MAX_FDS)
        fds += got
        if not chunk:
            raise EOFError("the request ended early")
        data += chunk
        if len(data) > MAX_REQUEST:
            raise ValueError("the request is too large")
    return json.loads(data[4:]), fds


class _Box:
    """What a keeper does for one box (module docstring)."""

    def __init__(self, runner, enter, libc: ctypes.CDLL) -> None:  # noqa: ANN001 - modules
        self.runner, self.enter, self.libc = runner, enter, libc

    def keep(self, conn: socket.socket) -> None:
        try:
            _close_all_but({0, 1, 2, conn.fileno()})
            creds = conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED,
                                    struct.calcsize("3i"))
            if struct.unpack("3i", creds)[1] != os.geteuid():
                os._exit(1)  # only the zygote's own user (root) asks for a box
            req, fds = _receive(conn)
            named = dict(zip(req["fds"], fds, strict=True))
            runner = self._start(req, named, conn)
        except BaseException:  # noqa: BLE001 - a keeper that cannot start the box says why
            _send(conn, {"error": traceback.format_exc(limit=4)})
            os._exit(1)
        if req["backend"] == "bwrap":
            os._exit(0)  # the runner goes on as the child of the box's pid 1
        self._watch(conn, runner)

    def _start(self, req: dict, fds: dict[str, int], conn: socket.socket) -> int:
        """Prepare the keeper, fork the runner (under bwrap through a helper born in the box's
        PID namespace, so that the runner is re-parented to the box's pid 1 when the helper
        leaves: an orphan goes to the reaper of its parent's namespace); report the keeper's pid
        and the runner's (bwrap: in the box's numbering) once the runner is ready, or why it is
        not."""
        plan, enter, libc = req["plan"], self.enter, self.libc
        bwrap = req["backend"] == "bwrap"
        if bwrap:  # the box's cgroup, limits and uid as bwrap took them, then its namespaces
            enter.join_cgroup(plan["cgroup"], plan.get("cgroup_kill", []))
            enter.enter(libc, dict(plan, reveal=[], fence=None), cgroup=False)
            enter.join_namespaces(libc, fds["owner"], [fds[n] for n in enter.NAMESPACES],
                                  fds["user"])
        else:  # the box's orphans come to the keeper, not to init
            enter.prctl(libc, PR_SET_CHILD_SUBREAPER, 1)
        err_r, err_w = os.pipe()
        pid_r, pid_w = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(err_r)
            os.close(pid_r)
            if bwrap:
                self._helper(req, fds, err_w, pid_w, conn)  # never returns
            os.close(pid_w)
            self._run(req, fds, err_w, conn)  # never returns
        for fd in (err_w, pid_w, *fds.values()):  # the box's ends: only the runner holds them
            os.close(fd)
        runner = pid
        if bwrap:
            os.waitpid(pid, 0)
            said = os.read(pid_r, 64)
            runner = int(said) if said.isdigit() else -1
        os.close(pid_r)
        error = b""
        while chunk := os.read(err_r, 1 << 16):
            error += chunk
        os.close(err_r)
        _send(conn, {"error": error.decode(errors="replace")} if error or runner < 0 else
              {"first": os.getpid(), "runner": runner})
        return runner

    def _helper(self, req: dict, fds: dict[str, int], err_w: int, pid_w: int,
                conn: socket.socket) -> None:
        """Under bwrap, the keeper's child, born in the box's PID namespace: it forks the runner,
        says its pid, and leaves."""
        try:
            pid = os.fork()
        except BaseException:  # noqa: BLE001
            os._exit(1)
        if pid == 0:
            os.close(pid_w)
            self._run(req, fds, err_w, conn)  # never returns
        os.write(pid_w, str(pid).encode())
        os._exit(0)

    def _run(self, req: dict, fds: dict[str, int], err_w: int, conn: socket.socket) -> None:
        """The runner child: what a cold box's first process does before exec, then the runner's
        main (module docstring)."""
        enter, libc = self.enter, self.libc
        bwrap = req["backend"] == "bwrap"
        try:
            conn.close()
            if bwrap:  # the uid and limits are the keeper's; the namespaces' capabilities go
                enter.drop_all_caps(libc, req["plan"]["cap_last"])
            null = os.open(os.devnull, os.O_RDWR)
            os.dup2(null, 0)
            os.dup2(fds["out"], 1)
            os.dup2(fds["out"], 2)
            os.chdir(req["cwd"])
            os.umask(req["umask"])
            _signals(req["ignored"])
            os.setsid()
            if not bwrap:
                enter.enter(libc, req["plan"], fds.get("ruleset"))
            _close_all_but({0, 1, 2, fds["res"], fds["go"], err_w, *_start_fd(fds)})
            os.environ.clear()
            os.environ.update(req["env"])
            argv = [*req["argv"], str(fds["res"]), str(fds["go"])]
            _fresh(req["argv0"], argv, self.runner)
        except BaseException:  # noqa: BLE001 - reported by the keeper, as Popen reports preexec_fn
            os.write(err_w, traceback.format_exc(limit=4).encode())
            os._exit(255)
        os.close(err_w)
        if bwrap:  # the supervisor says when the keeper is gone (and no longer counts in the
            # box's cgroup); the helper is, so the box's pid 1 is the parent, as bwrap's init is a
            # cold runner's, and the runner dies with it
            os.read(fds["start"], 1)
            os.close(fds["start"])
            if os.getppid() != 1:
                os._exit(255)
            enter.prctl(libc, PR_SET_PDEATHSIG, signal.SIGKILL)
        code = 1
        try:
            code = self.runner.main(argv)
        except BaseException:  # noqa: BLE001 - as Python reports an uncaught exception
            traceback.print_exc()
        finally:
            try:
                sys.stdout.flush()
                sys.stderr.flush()
            finally:
                os._exit(code)

    def _watch(self, conn: socket.socket, runner: int) -> None:
        """Report the runner's end; reap what the box leaves; when the connection closes, kill
        what is left under the keeper and exit."""
        try:
            pidfd: int | None = os.pidfd_open(runner)
        except (AttributeError, OSError):
            pidfd = None
        done = False
        while True:
            watched = [conn.fileno()] + ([pidfd] if pidfd is not None and not done else [])
            ready = select.select(watched, [], [], None if pidfd is not None else 0.05)[0]
            if conn.fileno() in ready:
                try:
                    if not conn.recv(64):
                        break
                except OSError:
                    break
            done = self._reap(conn, runner, done)
        _kill_descendants()
        os._exit(0)

    @staticmethod
    def _reap(conn: socket.socket, runner: int, done: bool) -> bool:
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return done
            if pid == 0:
                return done
            if pid == runner:
                _send(conn, {"exit": status})
                done = True


def _start_fd(fds: dict[str, int]) -> list[int]:
    return [fds["start"]] if "start" in fds else []


def _signals(ignored: list[int]) -> None:
    """SIGINT, SIGTERM and SIGHUP as a cold runner has them: ignored where its supervisor
    ignores them (exec keeps an ignored signal ignored), else Python's defaults."""
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        if sig in ignored:
            signal.signal(sig, signal.SIG_IGN)
        else:
            signal.signal(sig, signal.default_int_handler if sig == signal.SIGINT
                          else signal.SIG_DFL)


def _fresh(argv0: str, argv: list[str], runner) -> None:  # noqa: ANN001 - a module
    """What a fresh interpreter would have: ``sys.argv``, the runner as ``__main__``, numpy's
    global random state seeded anew (Python's own reseeds at fork)."""
    sys.argv = [argv0, *argv]
    runner.__name__ = "__main__"
    sys.modules["__main__"] = runner
    for name in ("_gpsaccel_runner", "_gpsaccel_enter"):
        sys.modules.pop(name, None)
    np_random = sys.modules.get("numpy.random")
    if np_random is not None:
        np_random.seed()


def _kill_descendants() -> None:
    """SIGKILL every process under this one until none is left (a basic box's processes are its
    descendants and the orphans it adopted as the box's subreaper)."""
    me = os.getpid()
    for _ in range(200):
        children: dict[int, list[int]] = {}
        for name in os.listdir("/proc"):
            if not name.isdigit():
                continue
            try:
                with open(f"/proc/{name}/stat", "rb") as f:
                    raw = f.read()
            except OSError:
                continue
            rest = raw[raw.rfind(b")") + 2:].split()
            if len(rest) > 1 and rest[0] not in (b"Z", b"X"):
                children.setdefault(int(rest[1]), []).append(int(name))
        stack, found = list(children.get(me, [])), []
        while stack:
            pid = stack.pop()
            found.append(pid)
            stack.extend(children.get(pid, []))
        if not found:
            return
        for pid in found:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        while True:
            try:
                if os.waitpid(-1, os.WNOHANG)[0] == 0:
                    break
            except ChildProcessError:
                break


if __name__ == "__main__":
    main(sys.argv[1:])
