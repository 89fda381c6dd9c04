"""Shared by the sandbox tests (tests/sandbox/) and the checker's batch tests (tests/check/): a
``backend`` parameter (every sandbox backend that works here; bwrap is skipped, with its reason,
where it does not) and ``hostile``: where the hostile submissions are and a watcher that finds
their processes by PID from outside any PID namespace.

Not a conftest: tests/check/conftest.py and tests/sandbox/conftest.py import its fixtures and
hook, so the two folders share one watcher and one lock, not two copies.
"""

from __future__ import annotations

import atexit
import os
import shutil
import signal
import tempfile
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from gpsaccel import sandbox as sb
from gpsaccel.sandbox import warmbox, zygote

TESTS = Path(__file__).resolve().parent
SUBMISSIONS = TESTS / "submissions"

#: The ``comm`` every process of a hostile submission gives itself, as the files spell it
#: (hostile/README.md), and as this test process's copy of them spells it (:data:`HOSTILE`): one
#: of its own (at most 15 bytes, a comm's room; a pid is unique among live processes), so that
#: two suites on one machine, or two pytest-xdist workers, never take each other's hostile
#: processes for theirs (a watcher that sees them fails, a test that kills them kills another's).
FILE_MARKER = "gpsacc-hostile"
MARKER = f"gpsh-{os.getpid()}"


def _own_copy() -> Path:
    """tests/submissions/hostile copied with :data:`FILE_MARKER` made :data:`MARKER` (removed
    when this process exits)."""
    top = Path(tempfile.mkdtemp(prefix=f"gpsaccel-{MARKER}-"))
    atexit.register(shutil.rmtree, top, True)
    copy = top / "hostile"
    shutil.copytree(SUBMISSIONS / "hostile", copy)
    for f in copy.rglob("*"):
        if f.is_file():
            f.write_text(f.read_text(encoding="utf-8").replace(FILE_MARKER, MARKER),
                         encoding="utf-8")
    return copy


HOSTILE = _own_copy()

_NO_BWRAP = pytest.mark.skipif(sb.bwrap_path() is None, reason="bubblewrap is not installed or "
                                                              "cannot create namespaces here")
_NO_WARM = pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on Linux")

#: Each backend, with its boxes started cold (exec) and warm (forked from a zygote:
#: gpsaccel.sandbox.zygote).  A test receives the backend's name; for a ``-warm`` case the
#: zygotes serve its boxes while it runs.  The warm cases are slow (``make test-all`` runs them,
#: ``make test`` not): they double every hostile test, and the quick run keeps of the kind
#: tests/sandbox/test_zygote.py, which compares a warm box with a cold one field by field.
BACKENDS = [
    pytest.param(("basic", False), id="basic"),
    pytest.param(("bwrap", False), id="bwrap", marks=_NO_BWRAP),
    pytest.param(("basic", True), id="basic-warm", marks=[_NO_WARM, pytest.mark.slow]),
    pytest.param(("bwrap", True), id="bwrap-warm", marks=[_NO_BWRAP, _NO_WARM, pytest.mark.slow]),
]


def _read(path: str) -> bytes:
    """The bytes of a small /proc file, b"" when its process is gone (unbuffered: a scan reads
    one per process, every 10 ms while a :class:`Watch` runs)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return b""
    try:
        return os.read(fd, 4096)
    except OSError:
        return b""
    finally:
        os.close(fd)


_MARKER_COMM = MARKER.encode() + b"\n"


def marked_pids() -> set[int]:
    """Live (not zombie) processes whose comm is :data:`MARKER`: every process's
    ``/proc/<pid>/comm`` (a few bytes), then the state of those that match (from ``stat``, as
    :func:`gpsaccel.sandbox.procs._proc_table` reads it).  A scan costs about a quarter of the
    CPU of reading every ``stat`` through Python's buffered files, and the watcher scans all
    the time a hostile test runs."""
    if not os.path.isdir("/proc/self"):  # psutil's table (macOS, the BSDs)
        from gpsaccel.sandbox.procs import _proc_table

        return {pid for pid, (_, state, comm) in _proc_table().items()
                if comm == MARKER and state not in ("Z", "X")}
    out = set()
    for name in os.listdir("/proc"):
        if name.isdigit() and _read(f"/proc/{name}/comm") == _MARKER_COMM:
            raw = _read(f"/proc/{name}/stat")
            close = raw.rfind(b")")
            state = raw[close + 2:close + 3]
            if close > 0 and state and state not in (b"Z", b"X"):
                out.add(int(name))
    return out


def alive(pids: set[int]) -> set[int]:
    """Those of ``pids`` that are still live processes with the marker."""
    return pids & marked_pids()


#: A hang guard, not an expected duration: how long a liveness test waits for an event that comes
#: within seconds when the code works (a loaded shared machine has taken minutes).  The Ctrl-C and
#: timeout tests fail by the event never coming, never by a clock.
HANG = 600.0


def wait_gone(pids: set[int], limit: float = HANG) -> set[int]:
    """Wait until none of ``pids`` is a live marked process (a killed process takes a moment to
    go, longer under load); those still alive after ``limit`` s (they spin forever: never gone)."""
    give_up = time.monotonic() + limit
    while alive(pids) and time.monotonic() < give_up:
        time.sleep(0.05)
    return alive(pids)


class Watch:
    """Collect, every 10 ms in a thread, the PIDs of every marked process that appears."""

    def __init__(self) -> None:
        self.seen: set[int] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.seen |= marked_pids()
            except Exception:  # noqa: BLE001 - a process that vanished mid-scan: scan again
                pass
            time.sleep(0.01)

    def __enter__(self) -> Watch:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "backend" in metafunc.fixturenames:
        metafunc.parametrize("backend", BACKENDS, indirect=True)


@pytest.fixture(scope="session")
def zygotes():
    """Two zygotes for the session's warm cases: for boxes that may import gpsaccel and for
    boxes that may not (killed at the end, by pid, with their folders).  They import numpy only:
    what a zygote imports does not change how a box is confined, and a zygote with scipy.stats
    (a third of a GiB of address space) serves no box of these tests' 512 MiB
    (zygote.MEMORY_SHARE); the grader's own is tried by tests/assignments/test_attacks.py."""
    started = [zygote.start(zygote.Warm(("numpy",), allow)) for allow in (False, True)]
    yield started
    for z in started:
        zygote.stop(z)


class Backend(str):
    """A backend's name (what ``sandbox.run`` takes), and whether its boxes start warm; a test
    whose boxes run in a process of its own says so (``elsewhere``), and starts a zygote there."""

    warm: bool = False
    elsewhere: bool = False


@pytest.fixture
def backend(request):
    """The backend's name; its boxes start warm while the test runs in a ``-warm`` case (and
    one of them must, unless they ran elsewhere, or in a check's forked items)."""
    name, warm = request.param
    b = Backend(name)
    b.warm = warm
    if not warm:
        yield b
        return
    served = warmbox.SERVED[0]
    with zygote.serve(*request.getfixturevalue("zygotes")):
        yield b
    if request.path.parent.name == "sandbox" and not b.elsewhere:
        assert warmbox.SERVED[0] > served, "no box of this warm case started warm"


@pytest.fixture
def watch():
    """A running :class:`Watch`; the test asserts on ``watch.seen``."""
    assert not marked_pids(), f"marked processes before the test: {marked_pids()}"
    with Watch() as w:
        yield w
    for pid in alive(w.seen):  # a failed test must not leave them to the next one
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def env_with_package() -> dict[str, str]:
    """The environment for a ``python -m gpsaccel.cli`` child: this checkout first on the path."""
    root = str(TESTS.parent)
    return dict(os.environ, PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""),
                MPLBACKEND="Agg")


@pytest.fixture
def hostile():
    """Paths and helpers of the hostile tests."""
    return SimpleNamespace(DIR=HOSTILE, SUBMISSIONS=SUBMISSIONS, MARKER=MARKER,
                           marked_pids=marked_pids, alive=alive, Watch=Watch,
                           env=env_with_package, HANG=HANG, wait_gone=wait_gone)


#: The modules whose hostile submissions leave marked processes that :func:`marked_pids` watches
#: machine-wide (paths below tests/): run side by side (two xdist workers, or two test runs on one
#: machine) each saw the other's processes ("marked processes before the test", "alive after the
#: command").
HOSTILE_MODULES = ("check/test_batch.py", "sandbox/test_hostile.py", "sandbox/test_attacks.py",
                   "sandbox/test_zygote.py")


@pytest.fixture(scope="module", autouse=True)
def _one_hostile_module_at_a_time(request):
    """Hold a machine-wide lock while a hostile module runs, so no two of them overlap (whichever
    folder, run or worker they belong to: one lock file)."""
    if request.path.resolve().relative_to(TESTS).as_posix() not in HOSTILE_MODULES:
        yield
        return
    import fcntl
    import tempfile

    with open(os.path.join(tempfile.gettempdir(), "gpsaccel-hostile-tests.lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, or the process dies
        yield


class Started:
    """How the boxes of a run started, counted across the processes it forks (each item of a
    class run is forked from the run's process: a counter in shared memory): ``cold`` and
    ``warm`` (:attr:`gpsaccel.sandbox.BoxResult.started`) while :meth:`counting` is active."""

    def __init__(self) -> None:
        import multiprocessing as mp

        ctx = mp.get_context("fork")
        self._cold, self._warm = ctx.Value("i", 0), ctx.Value("i", 0)

    @property
    def cold(self) -> int:
        return self._cold.value

    @property
    def warm(self) -> int:
        return self._warm.value

    def counting(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """From now on (until ``monkeypatch`` undoes it) every ``gpsaccel.sandbox.run`` of this
        process and of those it forks counts its box."""
        real = sb.run

        def run(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202 - sandbox.run's own
            box = real(*args, **kwargs)
            counter = self._warm if box.started == "warm" else self._cold
            with counter.get_lock():
                counter.value += 1
            return box

        monkeypatch.setattr(sb, "run", run)
