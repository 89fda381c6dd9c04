"""The attacks of issue 20 on the sandbox, each a bounded hostile submission under every backend:
it ends in a finding and the right verdict, nothing it started is alive afterwards, and no file
outside its box changed.

Bounds (a broken sandbox costs seconds, never the shared machine): at most 720 MB of memory, 150
sleeping children, every background process ends by itself within 20 s; ``kill_all.py`` sends
kill(-1) only as a box's own uid or inside a PID namespace.  The box limits here are smaller than
a check's (``LIMITS``).
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import psutil
import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel.sandbox import _boxuser, _cgroup
from gpsaccel.sandbox.confinement import _blocked_dirs, _site_dirs

from .._hostile import MARKER

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=20, processes=16)

#: Whole-box limits need a cgroup (root here, or a delegated cgroup2); a box user needs root.
CGROUP = _cgroup.available()
needs_cgroup = pytest.mark.skipif(CGROUP is None, reason="no writable cgroup: the per-process "
                                                         "rlimits are the fallback here")
needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="a box user needs root")


def _cgroup_bases() -> list:
    """Where boxes' cgroups are made here: the cgroup2 base, or the v1 ones and (for
    ``cgroup.kill``) the unified hierarchy's."""
    if CGROUP == "cgroup2":
        return [_cgroup._v2_base()]
    unified = _cgroup._v2_kill_base()
    return [*_cgroup._v1_bases().values(), *([unified] if unified is not None else [])]


def _forged_files() -> list[str]:
    """Files the hostile submissions try to leave outside their box."""
    found = []
    for d in _site_dirs() + _blocked_dirs():
        found += glob.glob(os.path.join(d, "gpsacc_hostile_forged*"))
    for d in _boxuser.SHARED_TMP:
        found += glob.glob(os.path.join(d, f"{MARKER}-file"))
    return found


@pytest.fixture
def outside():
    """Asserts that nothing was written outside the box; removes it if it was (a failed test
    must not leave a .pth in the environment)."""
    before = set(_forged_files())
    assert not before, f"left by an earlier run: {before}"
    yield
    after = _forged_files()
    for f in after:
        os.unlink(f)
    assert not after, f"written outside the box: {after}"


def _check(hostile, name, backend, **kw):
    return check.submission(hostile.DIR / name, n_runs=2, timeout=LIMITS.time, sandbox=backend,
                            limits=kw.pop("limits", LIMITS), **kw)


def _message(report, code):
    return next(f.message for f in report.findings if f.code == code)


# ------------------------------------------------------------------- a forged, lasting pass
def test_a_pth_into_site_packages_or_the_package_is_refused(backend, hostile, watch, outside):
    """The .pth writes fail (a box user owns nothing; bwrap binds site-packages read-only); the
    write into the package is also an attempt to use it."""
    if backend == "basic" and os.geteuid() != 0:
        pytest.skip("basic as the environment's owner cannot be made safe (docs/sandbox.md)")
    report = _check(hostile, "pth_writer.py", backend)
    assert report.codes == ["uses-checker"], report
    assert not hostile.alive(watch.seen)


def test_the_double_slash_alias_of_the_package_is_the_package(backend, hostile, watch,
                                                              outside):
    report = _check(hostile, "double_slash.py", backend)
    assert report.codes == ["uses-checker"], report
    assert not hostile.alive(watch.seen)


@needs_root
def test_a_process_started_through_a_tmux_server_dies_with_the_box(backend, hostile, watch,
                                                                   tmp_path):
    """The instructor runs a tmux server (as root); the box cannot reach its socket, and the
    server the student starts for itself runs as the box's uid: killed, and reported."""
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed")
    _start_tmux_server(hostile.HANG)
    try:
        before = _windows()
        report = _check(hostile, "tmux_escape.py", backend)
        assert not report.passed, report
        assert "left-processes" in [f.code for f in report.findings], report
        assert _windows() == before  # nothing was started in the instructor's server
        assert watch.seen and not hostile.alive(watch.seen)
    finally:
        subprocess.run(["tmux", "-L", MARKER, "kill-server"],
                       env={"PATH": "/usr/bin:/bin", "TMUX_TMPDIR": "/tmp"}, timeout=10)


def _start_tmux_server(limit: float) -> None:
    """The instructor's tmux server, with one session; tried again while the previous case's
    server, killed (``kill-server`` returns before it has exited), still holds its socket: on a
    loaded machine the new session failed there.  At most ``limit`` s."""
    env = {"PATH": "/usr/bin:/bin", "TMUX_TMPDIR": "/tmp"}
    give_up = time.monotonic() + limit
    while subprocess.run(["tmux", "-L", MARKER, "new-session", "-d", "sleep 60"],
                         env=env, capture_output=True, timeout=10).returncode != 0:
        assert time.monotonic() < give_up, "the instructor's tmux server never started"
        subprocess.run(["tmux", "-L", MARKER, "kill-server"], env=env,
                       capture_output=True, timeout=10)
        time.sleep(0.1)


def _windows() -> str:
    return subprocess.run(["tmux", "-L", MARKER, "list-windows", "-a"],
                          env={"PATH": "/usr/bin:/bin", "TMUX_TMPDIR": "/tmp"},
                          capture_output=True, text=True, timeout=10).stdout


@needs_root
def test_kill_all_and_sigstop_of_the_parent_reach_only_the_box(backend, hostile, watch):
    report = _check(hostile, "kill_all.py", backend)
    # the runner survives its own kill(-1); its parent is out of its reach (another uid under
    # basic, the PID namespace's init under bwrap)
    assert report.codes == ["exception"], report
    assert "SIGSTOP of the parent refused" in _message(report, "exception") or backend == "bwrap"
    assert not hostile.alive(watch.seen)


# --------------------------------------------------------------------- whole-box limits
@needs_cgroup
def test_a_fork_burst_stops_at_the_process_limit(backend, hostile, watch):
    report = _check(hostile, "fork_burst.py", backend)
    assert report.codes == ["process-limit"], report
    # the runner and at most LIMITS.processes children (pids.max binds at fork time)
    assert len(watch.seen) <= LIMITS.processes + 1, len(watch.seen)
    assert not hostile.alive(watch.seen)


@needs_cgroup
@pytest.mark.parametrize("name", ["memory_children.py", "memfd_hog.py"])
def test_memory_is_counted_for_the_whole_box(name, backend, hostile, watch):
    report = _check(hostile, name, backend)
    assert report.codes == ["memory-limit"], report
    assert not hostile.alive(watch.seen)


def test_every_writable_mount_is_bounded(backend, hostile, watch, outside):
    if backend == "basic" and os.geteuid() != 0:
        pytest.skip("basic as the checker's own user writes where that user may (docs/sandbox.md)")
    report = _check(hostile, "writes_everywhere.py", backend)
    assert report.codes == ["exception"], report
    assert report.details["sandbox_limits"] == (CGROUP or "rlimit")
    line = [x for x in _message(report, "exception").splitlines() if "Error: writes: " in x][-1]
    got = dict(item.split("=", 1) for item in line.split("writes: ", 1)[1].split(", "))
    # bwrap: read-only mounts; basic as root: the box user owns none of them (and /root, where
    # this machine's interpreter lives, is a read-only tmpfs revealing it)
    refused = {"Read-only file system"} if backend == "bwrap" else \
        {"Permission denied", "Read-only file system"}
    for d in ("/", "/root", "/etc", "/dev"):
        assert got.get(d) in refused, (d, got)
    if backend == "bwrap":  # the writable ones are the box's sized tmpfs
        for d in ("/dev/shm", "/tmp", "/box"):
            assert got.get(d) == "written", (d, got)
    assert not hostile.alive(watch.seen)


@needs_cgroup
def test_the_report_says_which_limits_applied(tmp_path, backend):
    f = tmp_path / "s.py"
    f.write_text("def f(z):\n    return z\n")
    box = sb.run(sb.load_submission(f, "f"), [sb.Call("f", (np.zeros(2),),
                                                       (sb.Output("a", (2,)),))], LIMITS, backend)
    assert box.failure is None and box.limit_backend == CGROUP
    assert box.memory_peak is not None and 0 < box.memory_peak < LIMITS.memory
    assert (box.box_user is not None) == (os.geteuid() == 0)
    # the cgroup is gone with the box (and under cgroup1 its cgroup for cgroup.kill)
    for d in _cgroup_bases():
        assert not [p for p in os.listdir(d) if p.startswith(f"{_cgroup.PREFIX}{os.getpid()}-")]


# ------------------------------------------------------------------- the result channel
@pytest.mark.parametrize("name, words", [
    ("frame_flood.py", "more than 1 'imported' frame"),
    ("frame_forger.py", "nested too deep"),
])
def test_a_student_made_channel_error_is_result_refused(name, words, backend, hostile):
    report = _check(hostile, name, backend)
    assert report.codes == ["result-refused"], report
    assert words in _message(report, "result-refused")


def test_huge_values_are_the_student_s_result_not_a_breach(backend, hostile):
    """1.7e308 in every x̂ and P is a value (a filter that runs away returns such numbers): it is
    judged as the student's result, never refused as tampering (issue 40)."""
    report = _check(hostile, "huge_values.py", backend)
    assert report.codes == ["p-mismatch"], report
    assert "ratio to the right value overflows" in _message(report, "p-mismatch")


# ------------------------------------------------------------------------ leave nothing
def test_a_box_folder_of_a_killed_supervisor_is_removed(tmp_path, hostile):
    """A worker SIGKILLed mid-check leaves its box folder (a copy of the submission): the next
    box removes it."""
    # room for all 80 of fork_lingers' children: its box then lives 20 s (its runner's sleep),
    # not the moment until the process limit stops it, and the look below cannot miss it
    code = ("import numpy as np\nfrom gpsaccel import sandbox as sb\n"
            f"sub = sb.load_submission({str(hostile.DIR / 'fork_lingers.py')!r}, "
            f"'kalman_filter')\n"
            "sb.run(sub, [sb.Call('kalman_filter', (np.zeros((3, 2)),), "
            "(sb.Output('x', (3, 3)),))], sb.Limits(time=30, processes=100), 'basic')\n")
    proc = subprocess.Popen([sys.executable, "-c", code], env=hostile.env())
    try:
        pattern = os.path.join(tempfile.gettempdir(), f"{sb.BOX_PREFIX}{proc.pid}-*")
        # the event: this box's runner has imported the student's file (its marker, on a process
        # below the supervisor: a marked process of another run must not stand for it, or the
        # supervisor is killed before its runner is marked, and the runner, missed by the sweep
        # below, forks its 80 children into the next hostile module); a hang guard only
        def ours() -> set[int]:
            try:
                below = {p.pid for p in psutil.Process(proc.pid).children(recursive=True)}
            except psutil.Error:
                return set()
            return hostile.marked_pids() & below

        give_up = time.monotonic() + hostile.HANG
        while not ours() and proc.poll() is None and time.monotonic() < give_up:
            time.sleep(0.05)
        assert ours() and glob.glob(pattern), f"the box never started (exit {proc.poll()})"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    sb.sweep_stale_boxes()
    assert not glob.glob(pattern)
    # its students outlived it (the runner's children, re-parented to init); under root they
    # run as the box's uid, which the next box of that uid kills; here until none is left (the
    # runner may be forking still)
    give_up = time.monotonic() + hostile.HANG
    while hostile.marked_pids() and time.monotonic() < give_up:
        for pid in hostile.marked_pids():
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        time.sleep(0.05)
    if CGROUP is not None:  # its cgroup is removed by the next box made
        _cgroup.create(1 << 30, 8).remove()
        for d in _cgroup_bases():
            assert not [p for p in os.listdir(d) if p.startswith(f"{_cgroup.PREFIX}{proc.pid}-")]


@needs_root
def test_boxes_at_once_in_one_process_get_uids_of_their_own():
    """Threads of one process (check_many(executor="threads")) run boxes at once: each box
    locks a slot of its own, so no box's end kills another's processes."""
    a, b = _boxuser.acquire(), _boxuser.acquire()
    try:
        assert a[0] != b[0] and a[0] >= _boxuser.UID_BASE
        assert a[0] - _boxuser.UID_BASE < (1 << 32) - 1 - _boxuser.UID_BASE
    finally:
        _boxuser.release(a[1])
    c = _boxuser.acquire()
    _boxuser.release(b[1])
    _boxuser.release(c[1])
    assert c[0] == a[0]  # a released slot is taken again


# ------------------------------------------------------------------ the answers are not there
#: What a box that may import gpsaccel hides (the checks' and the homework's list).
HIDE = check.problem.BOX_HIDES

_RAW_READ = '''
import ctypes, os
import numpy as np
import gpsaccel

libc = ctypes.CDLL(None, use_errno=True)
ROOT = os.path.dirname(gpsaccel.__file__)


def _read_fd(fd):
    if fd < 0:
        return -ctypes.get_errno()
    buf = ctypes.create_string_buffer(1 << 16)
    n = libc.read(fd, buf, len(buf))
    libc.close(fd)
    return n


def raw_read(path):
    """Bytes read by libc open/read (no Python-level file call, so no audit event), or -errno."""
    return _read_fd(libc.open(path.encode(), os.O_RDONLY))


def raw_openat(path):
    top = libc.open(b"/", os.O_RDONLY | os.O_DIRECTORY)
    n = _read_fd(libc.openat(top, path.lstrip("/").encode(), os.O_RDONLY))
    libc.close(top)
    return n


def through_symlink(path):
    """A link made in /tmp to the file's folder, then the file read through it."""
    link = "/tmp/lnk-%d" % os.getpid()
    libc.unlink(link.encode())
    libc.symlink(os.path.dirname(path).encode(), link.encode())
    return raw_read(link + "/" + os.path.basename(path))


def through_hard_link(path):
    link = "/tmp/hl-%d" % os.getpid()
    libc.unlink(link.encode())
    if libc.link(path.encode(), link.encode()) != 0:
        return -ctypes.get_errno()
    return raw_read(link)


WAYS = [raw_read, raw_openat, lambda p: raw_read("/proc/self/root" + p),
        lambda p: raw_read("/proc/self/cwd/" + os.path.relpath(p)),
        lambda p: raw_read(os.path.join(ROOT, "kalman", "..", os.path.relpath(p, ROOT))),
        through_symlink, through_hard_link]


def f(x):
    read = [way(os.path.join(ROOT, rel)) for rel in REL for way in WAYS]
    return np.array(read, dtype=float)
'''


#: How many ways of opening a file _RAW_READ tries, and what a refused one gives.
WAYS = 7
REFUSED = {-errno.ENOENT, -errno.EACCES, -errno.EXDEV, -errno.EPERM}


def read_in_box(tmp_path, rel: list[str], backend: str, hide) -> np.ndarray:
    """(file, way) -> bytes read, or -errno, by a box that may import gpsaccel but not ``hide``."""
    f = tmp_path / "s.py"
    f.write_text(f"REL = {rel!r}\n" + _RAW_READ)
    box = sb.run(sb.load_submission(f, "f"), [sb.Call("f", (np.zeros(1),), (
        sb.Output("read", (len(rel) * WAYS,)),))], LIMITS, backend, allow_gpsaccel=True,
        hide=hide)
    assert box.failure is None, (box.detail, box.problem, box.output)
    return box.results[0]["read"].reshape(len(rel), WAYS)


def test_a_box_that_may_import_gpsaccel_reads_no_check_nor_answer_file(backend, tmp_path):
    """A notebook's box imports the course's models (allow_gpsaccel) but reads no file of the
    folders its caller hides (the checks, the graded questions, the answers), by any way of
    opening them: libc's open and openat (no audit event), /proc/self/root and cwd, a path
    through a public folder, a symbolic or hard link made in /tmp.  bwrap binds empty folders
    over them (ENOENT); basic fences them (Landlock: EACCES, EXDEV or EPERM for a link; a mount
    namespace: ENOENT).  A public module of the same package is read."""
    rel = ["check/batch.py", "check/problem.py", "assignments/ship.py",
           "assignments/__init__.py", "assignments/masters/calibration/graded.py",
           "exercises/answers.py", "homework/example/cv2d/graded.py", "calibration/model.py"]
    read = read_in_box(tmp_path, rel, backend, HIDE)
    assert set(read[:-1].ravel().tolist()) <= REFUSED, read
    size = min((sb.PACKAGE_DIR / rel[-1]).stat().st_size, 1 << 16)
    assert read[-1, :6].tolist() == [size] * 6  # every way but a hard link (root's file)


def test_a_box_that_may_not_import_gpsaccel_reads_none_of_it(backend, tmp_path):
    """Without allow_gpsaccel no file of the package is readable, through libc either."""
    f = tmp_path / "s.py"
    f.write_text("REL = ['calibration/model.py', 'check/problem.py']\n"
                 + _RAW_READ.replace("import gpsaccel\n", "").replace(
                     "os.path.dirname(gpsaccel.__file__)", repr(str(sb.PACKAGE_DIR))))
    box = sb.run(sb.load_submission(f, "f"), [sb.Call("f", (np.zeros(1),), (
        sb.Output("read", (2 * WAYS,)),))], LIMITS, backend)
    assert box.failure is None, (box.detail, box.problem)
    assert set(box.results[0]["read"].tolist()) <= REFUSED
