"""Warm boxes (gpsaccel.sandbox.zygote): the zygote holds nothing of the grader's, a box forked from
it is confined exactly as a cold one (compared field by field with a cold box, under each backend),
leaves nothing in it for the next box, cannot reach it, and a box the zygote cannot serve starts
cold.  Every other backend-parametrised test of tests/sandbox also runs warm (tests/_hostile.py).
"""

from __future__ import annotations

import json
import os
import re
import secrets
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import _cgroup, zygote
from gpsaccel.sandbox.confinement import hidden_dirs

from .._hostile import MARKER

pytestmark = pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on "
                                                            "Linux")

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=30)
INFO = 1 << 14  # bytes of JSON a box may send back here

#: A submission that describes the process it runs in: credentials, limits, namespaces, cgroup,
#: environment, what the runner's parent is, and what it may and may not do to the zygote.
DESCRIBE = '''
import ctypes, json, os, resource, signal, sys

import numpy as np


def _status():
    keep = ("Uid", "Gid", "Groups", "CapInh", "CapPrm", "CapEff", "CapBnd", "CapAmb",
            "NoNewPrivs", "Seccomp", "Threads")
    with open("/proc/self/status") as f:
        pairs = (line.split(":", 1) for line in f if ":" in line)
        return {k: " ".join(v.split()) for k, v in pairs if k in keep}


def _try(f):
    try:
        f()
        return "done"
    except OSError as exc:
        return exc.errno


def _read(path):
    try:
        with open(path) as f:
            return f.read().strip()
    except OSError as exc:
        return exc.errno


def describe(args):
    zygote_pid, = (int(a) for a in args)
    a = np.ones((300, 300))
    a @ a  # BLAS at work: still one thread
    info = {
        "status": _status(),
        "rlimits": {n: resource.getrlimit(getattr(resource, n)) for n in (
            "RLIMIT_AS", "RLIMIT_CPU", "RLIMIT_FSIZE", "RLIMIT_NPROC", "RLIMIT_NOFILE",
            "RLIMIT_CORE")},
        "ns": {n: os.readlink(f"/proc/self/ns/{n}") for n in (
            "user", "pid", "mnt", "net", "ipc", "uts", "cgroup")},
        "cgroup": open("/proc/self/cgroup").read(),
        "pid1": _read("/proc/1/comm"),  # basic as root: another uid's, not in its /proc
        "ppid_is_1": os.getppid() == 1,
        "sid_is_pid": os.getsid(0) == os.getpid(),
        "pgid_is_pid": os.getpgid(0) == os.getpid(),
        "cwd": os.getcwd(), "env": dict(os.environ), "umask": os.umask(0o22),
        "argv": sys.argv[:3], "path": sys.path, "main": sys.modules["__main__"].__name__,
        "main_file": os.path.basename(getattr(sys.modules["__main__"], "__file__", "")),
        "signals": {s: str(signal.getsignal(getattr(signal, s))) for s in (
            "SIGINT", "SIGTERM", "SIGHUP", "SIGPIPE", "SIGXFSZ", "SIGCHLD")},
        "gpsaccel": sorted(m for m in sys.modules if m.split(".")[0] == "gpsaccel"),
        "fds": len(os.listdir("/proc/self/fd")),
        "dumpable": ctypes.CDLL(None).prctl(3, 0, 0, 0, 0),
        "kill_zygote": _try(lambda: os.kill(zygote_pid, signal.SIGKILL)),
        "stop_parent": _try(lambda: os.kill(os.getppid(), signal.SIGSTOP)),
        "kill_pid1": _try(lambda: os.kill(1, signal.SIGKILL)),
        "planted_before": hasattr(np, "gpsacc_planted"),
        "random": float(np.random.random()),
    }
    np.gpsacc_planted = True  # the next box must not see it
    blob = json.dumps(info).encode()[:INFO]
    return np.frombuffer(blob.ljust(INFO, b"\\0"), dtype=np.uint8)
'''.replace("INFO", str(INFO))


def _describe(tmp_path: Path, backend: str, z: zygote.Zygote, allow: bool = False) -> dict:
    f = tmp_path / "describe.py"
    f.write_text(DESCRIBE)
    sub = sb.load_submission(f, "describe")
    call = sb.Call("describe", (np.array([z.pid]),), (sb.Output("info", (INFO,), "uint8"),))
    box = sb.run(sub, [call], LIMITS, backend=backend, allow_gpsaccel=allow)
    assert box.failure is None, (box.failure, box.detail, box.output[-2000:])
    text = bytes(box.results[0]["info"]).rstrip(b"\0").decode()
    info = json.loads(re.sub(r"gpsaccel-box-\d+-\w+", "gpsaccel-box-N-X", text))  # its own folder
    info["started"] = box.started
    return info


def _backends():
    return ["basic", pytest.param("bwrap", marks=pytest.mark.skipif(
        sb.bwrap_path() is None, reason="bubblewrap does not work here"))]


@pytest.mark.parametrize("kind", _backends())
def test_a_warm_box_is_confined_as_a_cold_one(tmp_path, kind, zygotes):
    """Field by field: what a cold box's runner is, the warm one is, but for what the module
    docstring of gpsaccel.sandbox.zygote names (its pid's number, the file of __main__)."""
    cold = _describe(tmp_path, kind, zygotes[0])
    with zygote.serve(*zygotes):
        warm = _describe(tmp_path, kind, zygotes[0])
    assert (cold["started"], warm["started"]) == ("cold", "warm")
    same = ["status", "rlimits", "pid1", "ppid_is_1", "umask", "argv", "path", "main",
            "main_file", "signals", "gpsaccel", "fds", "dumpable", "kill_zygote", "stop_parent",
            "kill_pid1", "cwd", "env"]
    if kind == "basic":  # under bwrap a cold runner is in its pid 1's session and group
        same += ["sid_is_pid", "pgid_is_pid"]
    for key in same:
        assert warm[key] == cold[key], key
    assert warm["sid_is_pid"] and warm["pgid_is_pid"]  # kill(0, ...) reaches its own only
    assert warm["status"]["Threads"] == "1"
    assert warm["status"]["CapEff"] == warm["status"]["CapBnd"] == "0000000000000000"
    assert warm["status"]["NoNewPrivs"] == "1" and warm["dumpable"] == 0
    assert warm["gpsaccel"] == []  # a box that may not import it finds none of it
    assert warm["kill_zygote"] in (1, 3)  # EPERM (another uid) or ESRCH (not in its PID ns)
    assert os.path.exists(f"/proc/{zygotes[0].pid}")
    if kind == "bwrap":  # namespaces of its own (bwrap's, made for this box)
        host = {n: os.readlink(f"/proc/self/ns/{n}") for n in warm["ns"]}
        assert all(warm["ns"][n] != host[n] for n in warm["ns"]), warm["ns"]
        assert warm["pid1"] == "bwrap" and warm["ppid_is_1"]
        assert warm["cgroup"] == cold["cgroup"]  # the root of its cgroup namespace
    elif _cgroup.available():  # the box's cgroup, whose name is the folder's
        assert "gpsaccel-box-" in warm["cgroup"] and "gpsaccel-box-" in cold["cgroup"]


@pytest.mark.parametrize("kind", _backends())
def test_a_box_leaves_nothing_in_the_zygote(tmp_path, kind, zygotes):
    """The first box plants an attribute on numpy and draws from numpy's global generator;
    the next box forked from the same zygote sees no attribute and draws another number."""
    with zygote.serve(*zygotes):
        first = _describe(tmp_path, kind, zygotes[0])
        second = _describe(tmp_path, kind, zygotes[0])
    assert not first["planted_before"] and not second["planted_before"]
    assert first["random"] != second["random"]


def test_the_zygote_holds_no_descriptor_nor_byte_of_its_starter(tmp_path):
    """Started by exec, with its own folder: its descriptors are /dev/null and its socket, and
    a secret this process holds (in memory, in an open file) is nowhere in its memory."""
    token = secrets.token_hex(16)
    secret = tmp_path / "secret"
    secret.write_text(token)
    held = open(secret, encoding="ascii")  # noqa: SIM115 - open while the zygote starts
    in_memory = ("gpsacc" + token[::-1]).encode()  # a byte string this process holds
    try:
        z = zygote.start(zygote.Warm(("numpy",)))
    finally:
        held.close()
    try:
        fds, mine = _fds(z.pid), set(_fds(os.getpid()).values())
        assert [fds[i] for i in (0, 1, 2)] == ["/dev/null"] * 3
        # its listening socket and its own wake-up pipe: nothing of this process's
        assert all(v.startswith(("socket:", "pipe:")) for k, v in fds.items() if k > 2), fds
        assert not set(fds.values()) & mine - {"/dev/null"}, fds
        with open(f"/proc/{z.pid}/environ", "rb") as f:
            env = dict(e.split(b"=", 1) for e in f.read().split(b"\0") if e)
        assert set(env) == {b"PATH", b"HOME", b"LANG"}
        cmd = open(f"/proc/{z.pid}/cmdline", "rb").read().split(b"\0")
        assert cmd[1:4] == [b"-I", b"-S", b"-B"]
        assert os.stat(z.folder).st_mode & 0o777 == 0o700
        assert in_memory not in _memory(z.pid) and token.encode() not in _memory(z.pid)
        assert in_memory[::-1]  # (held until here)
    finally:
        zygote.stop(z)
    assert not os.path.exists(z.folder) and not os.path.exists(f"/proc/{z.pid}")


def _fds(pid: int) -> dict[int, str]:
    out = {}
    for f in os.listdir(f"/proc/{pid}/fd"):
        try:
            out[int(f)] = os.readlink(f"/proc/{pid}/fd/{f}")
        except FileNotFoundError:  # the listing's own descriptor
            continue
    return out


def _memory(pid: int) -> bytes:
    """Every readable mapping of process ``pid`` (root reads any process's memory)."""
    out = bytearray()
    with open(f"/proc/{pid}/maps", encoding="ascii") as maps, \
            open(f"/proc/{pid}/mem", "rb", buffering=0) as mem:
        for line in maps:
            span, perms = line.split()[:2]
            if not perms.startswith("r") or line.rstrip().endswith("[vvar]"):
                continue
            lo, hi = (int(x, 16) for x in span.split("-"))
            try:
                mem.seek(lo)
                out += mem.read(hi - lo)
            except (OSError, ValueError, OverflowError):
                continue
    return bytes(out)


def test_a_box_the_zygote_cannot_serve_starts_cold(tmp_path, zygotes):
    """Another kind of box (it may import gpsaccel, the zygote's boxes may not), a memory limit
    under three times the zygote's address space, a hidden folder holding one of its modules,
    and a dead zygote: each box starts cold, and runs."""
    no_gpsaccel = zygotes[0]
    with zygote.serve(no_gpsaccel):
        assert _describe(tmp_path, "basic", no_gpsaccel, allow=True)["started"] == "cold"
        assert _describe(tmp_path, "basic", no_gpsaccel)["started"] == "warm"
    small = zygote.MEMORY_SHARE * no_gpsaccel.vmsize - (1 << 20)
    assert zygote.serving("basic", False, list(no_gpsaccel.sys_path), small, []) is None
    with zygote.serve(no_gpsaccel):
        assert zygote.serving("basic", False, list(no_gpsaccel.sys_path), small + (2 << 20),
                              []) is no_gpsaccel
        numpy_dir = os.path.dirname(next(m for m in no_gpsaccel.modules
                                         if m.endswith("numpy/__init__.py")))
        assert zygote.serving("basic", False, list(no_gpsaccel.sys_path), 1 << 30,
                              [numpy_dir]) is None
    dead = zygote.start(zygote.Warm(("numpy",)))
    os.kill(dead.pid, signal.SIGKILL)
    dead.proc.wait()
    with zygote.serve(dead):
        assert _describe(tmp_path, "basic", dead)["started"] == "cold"
    zygote.stop(dead)


@pytest.mark.parametrize("kind", _backends())
def test_a_box_that_may_not_import_gpsaccel_is_never_served_by_one_that_may(tmp_path, kind,
                                                                           zygotes):
    """The leak a wrong match would be: a student's filter forked from the zygote of notebook
    boxes (allow_gpsaccel) would import the package.  Offered only that zygote, the filter's box
    starts cold; offered both (that one first), it starts from its own kind; either way its
    import of gpsaccel is refused and reported (uses-checker), as in a cold box."""
    f = tmp_path / "uses.py"
    f.write_text("import numpy as np\n\n\ndef f(x):\n    import gpsaccel\n"
                 "    return np.asarray(x, dtype=float)\n")
    sub = sb.load_submission(f, "f")
    call = sb.Call("f", (np.zeros(3),), (sb.Output("y", (3,)),))
    no_gpsaccel, allowed = zygotes
    got = []
    for offered in ((allowed,), (allowed, no_gpsaccel)):
        with zygote.serve(*offered):
            box = sb.run(sub, [call], LIMITS, backend=kind)
        got.append((box.started, box.failure, box.uses_checker))
    assert got == [("cold", "uses-checker", True), ("warm", "uses-checker", True)]


def test_a_zygote_imports_nothing_its_boxes_may_not_read():
    """By name before it starts, and by the files of every module it holds once it has: here a
    module that imports one of a folder to hide (the calibration model imports gpsaccel.kalman,
    named here as hidden)."""
    with pytest.raises(ValueError, match="may not read"):
        zygote.Warm(("gpsaccel.check",), allow_gpsaccel=True, hide=("check",))
    with pytest.raises(ValueError, match="may not read"):
        zygote.Warm(("gpsaccel",), allow_gpsaccel=False)
    with pytest.raises(ValueError, match="module name"):
        zygote.Warm(("numpy; import os",))
    def ours() -> set[str]:
        return {p for p in os.listdir(tempfile.gettempdir())
                if p.startswith(f"{zygote.ZYGOTE_PREFIX}{os.getpid()}-")}

    before = ours()  # other tests' zygotes (the session's) may be running
    with pytest.raises(ValueError, match="would hold .*/kalman/"):
        zygote.start(zygote.Warm(("gpsaccel.calibration.model",), allow_gpsaccel=True,
                                 hide=("kalman",)))
    assert ours() == before  # the refused zygote's folder is gone with it
    assert hidden_dirs(False, ())  # the package is hidden from a box that may not import it


@pytest.mark.parametrize("kind", _backends())
def test_a_warm_box_dies_with_its_supervisor(tmp_path, kind, hostile, watch):
    """The process running a warm box is SIGKILLed mid-box: nothing of the box is left (basic:
    the keeper sees its connection close and kills the box; bwrap: the box dies with bwrap, which
    dies with its parent); then the zygote is stopped and nothing of it is left."""
    spin = tmp_path / "spin.py"
    spin.write_text("import ctypes, os\n\nctypes.CDLL(None).prctl(15, b'" + MARKER + "', 0, 0, 0)"
                    "\n\n\ndef kalman_filter(z):\n    if os.fork() == 0:\n        os.setsid()\n"
                    "    while True:\n        pass\n")
    code = ("import numpy as np\nfrom gpsaccel import sandbox as sb\n"
            "from gpsaccel.sandbox import zygote\n"
            f"sub = sb.load_submission({str(spin)!r}, 'kalman_filter')\n"
            "with zygote.warm_boxes(zygote.Warm(('numpy',))) as (z,):\n"
            "    print(z.pid, flush=True)\n"
            "    sb.run(sub, [sb.Call('kalman_filter', (np.zeros((3, 2)),), "
            f"(sb.Output('x', (3, 3)),))], sb.Limits(time=600), {kind!r})\n")
    proc = subprocess.Popen([sys.executable, "-c", code], env=hostile.env(),
                            stdout=subprocess.PIPE)
    try:
        assert proc.stdout is not None
        zpid = int(proc.stdout.readline())
        deadline = time.monotonic() + hostile.HANG
        while len(watch.seen) < 2 and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert len(watch.seen) == 2, "the warm box's two processes never ran"
    finally:
        proc.kill()
        proc.wait()
    left = hostile.wait_gone(watch.seen)
    assert not left, f"alive after their supervisor died: {left}"
    give_up = time.monotonic() + hostile.HANG
    while os.path.exists(f"/proc/{zpid}") and time.monotonic() < give_up:
        time.sleep(0.05)
    assert not os.path.exists(f"/proc/{zpid}"), "the zygote outlived the process that started it"


#: A submission that tries to trace its box's pid 1 (then lets it go at once) and to open its
#: memory: (ptrace's return, its errno, the errno of opening /proc/1/mem or 0).
TRACE_PID1 = '''
import ctypes, os

import numpy as np


def trace(args):
    libc = ctypes.CDLL(None, use_errno=True)
    libc.ptrace.restype = ctypes.c_long
    libc.ptrace.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
    got = libc.ptrace(16, 1, None, None)  # PTRACE_ATTACH
    err = ctypes.get_errno() if got else 0
    if got == 0:
        os.waitpid(1, 0x40000000)  # __WALL: its stop
        libc.ptrace(17, 1, None, None)  # PTRACE_DETACH
    try:
        os.close(os.open("/proc/1/mem", os.O_RDWR))
        mem = 0
    except OSError as exc:
        mem = exc.errno
    return np.array([got, err, mem], dtype=float)
'''


@pytest.mark.skipif(sb.bwrap_path() is None, reason="bubblewrap does not work here")
def test_a_warm_bwrap_box_cannot_trace_its_pid_1(tmp_path, zygotes):
    """A warm bwrap box's pid 1 (_reaper.py) runs as the box's uid and writes the runner's end
    down a pipe the supervisor reads: traced, it wrote whatever the student wanted there (an
    endless line the supervisor buffered, outside the box's limits, with quadratic CPU; a forged
    end of the runner).  It is not dumpable, so the box can neither attach to it nor open its
    memory.  (A cold box can trace bwrap's own init, which holds only the box's output and bwrap's
    event descriptor.)"""
    f = tmp_path / "trace.py"
    f.write_text(TRACE_PID1)
    sub = sb.load_submission(f, "trace")
    call = sb.Call("trace", (np.zeros(1),), (sb.Output("r", (3,)),))
    with zygote.serve(*zygotes):
        box = sb.run(sub, [call], LIMITS, backend="bwrap")
    assert box.started == "warm" and box.failure is None, (box.failure, box.output[-2000:])
    got, err, mem = box.results[0]["r"]
    assert (got, err) == (-1, 1), "the box attached to its pid 1"  # EPERM
    assert mem in (1, 13), "the box opened its pid 1's memory"  # EPERM, EACCES


#: A submission that imports numpy alone and finds, by bisection, the largest array (MiB) its
#: address-space limit lets it reserve (np.empty: nothing is touched, no memory is used).
LARGEST = '''
import numpy as np


def largest(args):
    lo, hi = 0, 4096
    while lo < hi:
        mid = (lo + hi + 1) // 2
        try:
            a = np.empty(mid << 20, dtype=np.uint8)
            del a
            lo = mid
        except MemoryError:
            hi = mid - 1
    return np.array([lo], dtype=float)
'''


@pytest.mark.parametrize("kind", _backends())
def test_a_numpy_only_box_has_the_same_room_warm_as_cold(tmp_path, kind):
    """The course's zygote (COURSE_IMPORTS) and a 1 GiB box: the largest array a box that
    imports numpy alone can reserve is the same, within 16 MiB, warm as cold."""
    f = tmp_path / "largest.py"
    f.write_text(LARGEST)
    sub = sb.load_submission(f, "largest")
    call = sb.Call("largest", (np.zeros(1),), (sb.Output("mib", (1,)),))
    limits = sb.Limits(memory=1 << 30, time=30)
    cold = sb.run(sub, [call], limits, backend=kind)
    with zygote.warm_boxes(zygote.Warm()):
        warm = sb.run(sub, [call], limits, backend=kind)
    assert (cold.started, warm.started) == ("cold", "warm")
    got = {b.started: float(b.results[0]["mib"][0]) for b in (cold, warm)}
    assert abs(got["warm"] - got["cold"]) <= 16, got
