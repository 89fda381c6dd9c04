"""Run one grading command (``otter run`` on one notebook) isolated from the grader and the others.

This is the single place where a submission's code gets a process; it is meant to switch to the
checker's sandbox (:mod:`gpsaccel.check.sandbox`, issue 11) once that exists.  Until then it gives
each job:

* a private working directory (also its ``HOME`` and ``TMPDIR``), deleted afterwards;
* a scrubbed environment: only ``PATH``, the locale and ``PYTHONPATH`` pass through (no tokens, no
  credentials, no ``JUPYTER_*``/``IPYTHON*`` settings of the instructor), BLAS limited to one
  thread (jobs run in parallel on few cores);
* resource limits (POSIX): CPU seconds, file size, open files;
* a wall-clock limit: at the limit, or when the command ends, every process of the job is killed —
  the command's own session *and* the Jupyter kernel, which ``jupyter_client`` starts in a session
  of its own.  The job's processes are found by a marker in their environment
  (``GPSACCEL_GRADE_JOB``), which a child inherits and cannot remove from ``/proc/PID/environ``,
  so a kernel that daemonises is found too.

What it does **not** do (the sandbox's job): limit memory per job, block the network, hide the
rest of the file system.  A notebook can still read what the grading user can read.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

#: Environment variables passed through to a job (everything else is dropped).
PASS_THROUGH = ("PATH", "LANG", "LC_ALL", "LC_CTYPE", "PYTHONPATH", "SYSTEMROOT")

#: The environment variable that marks every process of a job.
MARKER = "GPSACCEL_GRADE_JOB"

#: Largest file a job may write (bytes) and most open files.
MAX_FILE_BYTES = 256 * 2**20
MAX_OPEN_FILES = 1024

#: Characters of a job's output kept.
OUTPUT_KEEP = 20_000


@dataclass(frozen=True)
class JobResult:
    """What one isolated command did.

    returncode : exit code (None when killed at the time limit); timed_out : killed at the limit;
    output : the last :data:`OUTPUT_KEEP` characters of its stdout and stderr; seconds : wall time;
    killed : number of leftover processes of the job killed at the end (kernels, forks).
    """

    returncode: int | None
    timed_out: bool
    output: str
    seconds: float
    killed: int


def scrubbed_env(workdir: Path, marker: str) -> dict[str, str]:
    """The environment of a job: the pass-through variables, a private HOME/TMPDIR, one thread."""
    env = {k: os.environ[k] for k in PASS_THROUGH if k in os.environ}
    env.setdefault("PATH", os.defpath)
    home = workdir / "home"
    tmp = workdir / "tmp"
    home.mkdir(exist_ok=True)
    tmp.mkdir(exist_ok=True)
    env.update({
        "HOME": str(home), "TMPDIR": str(tmp), "MPLBACKEND": "Agg", "PYTHONHASHSEED": "0",
        "PYTHONIOENCODING": "utf-8", "PYTHONDONTWRITEBYTECODE": "1",
        "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
        "JUPYTER_PLATFORM_DIRS": "1", MARKER: marker,
    })
    return env


def _limit(pid: int, cpu_seconds: int) -> None:
    """Set the job's resource limits on ``pid`` (Linux ``prlimit``; its children inherit them).

    Set from outside, right after the start (a ``preexec_fn`` is not safe with the grader's
    threads); the command spends its first second importing, long before it starts a kernel.
    """
    import resource

    if not hasattr(resource, "prlimit"):  # not Linux: the wall-clock limit still holds
        return
    try:
        resource.prlimit(pid, resource.RLIMIT_CPU, (cpu_seconds, cpu_seconds + 5))
        resource.prlimit(pid, resource.RLIMIT_FSIZE, (MAX_FILE_BYTES, MAX_FILE_BYTES))
        _, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        cap = MAX_OPEN_FILES if hard == resource.RLIM_INFINITY else min(MAX_OPEN_FILES, hard)
        resource.prlimit(pid, resource.RLIMIT_NOFILE, (cap, cap))
    except (ProcessLookupError, PermissionError, OSError):
        pass  # already gone


def _job_processes(marker: str) -> list[int]:
    """PIDs of the processes whose environment carries ``MARKER=marker`` (this user's only)."""
    import psutil

    needle = f"{MARKER}={marker}".encode()
    found = []
    me = os.getpid()
    for proc_dir in Path("/proc").iterdir() if Path("/proc").is_dir() else []:
        if not proc_dir.name.isdigit() or int(proc_dir.name) == me:
            continue
        try:
            if needle in (proc_dir / "environ").read_bytes().split(b"\0"):
                found.append(int(proc_dir.name))
        except OSError:  # gone, or another user's process
            continue
    if not Path("/proc").is_dir():  # no procfs (macOS): psutil reads the environment instead
        for p in psutil.process_iter(["pid"]):
            try:
                if p.pid != me and p.environ().get(MARKER) == marker:
                    found.append(p.pid)
            except (psutil.Error, OSError):
                continue
    return found


def _kill_job(proc: subprocess.Popen, marker: str) -> int:
    """Kill the command's session and every process carrying the job's marker; how many."""
    killed = 0
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    for _ in range(3):  # a process may fork while we kill: look again
        pids = _job_processes(marker)
        if not pids:
            break
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
                killed += 1
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.05)
    if proc.poll() is None:
        proc.kill()
    proc.wait()
    return killed


def run_isolated(cmd: Sequence[str], workdir: Path | str, timeout: float,
                 cpu_seconds: int | None = None) -> JobResult:
    """Run ``cmd`` in ``workdir`` with a scrubbed environment, limits and a wall-clock ``timeout``.

    ``workdir`` must exist and belong to this job only.  ``cpu_seconds`` (default: twice the
    timeout) caps the CPU time of each process.  Never raises for what the command does.
    """
    workdir = Path(workdir)
    marker = uuid.uuid4().hex
    env = scrubbed_env(workdir, marker)
    log = workdir / "output.txt"
    cpu = int(cpu_seconds if cpu_seconds is not None else max(10, 2 * timeout))
    t0 = time.perf_counter()
    timed_out = False
    with open(log, "wb") as logf:
        proc = subprocess.Popen(
            list(cmd), cwd=workdir, env=env, stdin=subprocess.DEVNULL, stdout=logf,
            stderr=subprocess.STDOUT, start_new_session=True)
        _limit(proc.pid, cpu)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
        killed = _kill_job(proc, marker)
    seconds = time.perf_counter() - t0
    size = log.stat().st_size
    with open(log, "rb") as f:
        if size > 4 * OUTPUT_KEEP:
            f.seek(size - 4 * OUTPUT_KEEP)
        text = f.read().decode("utf-8", errors="replace")[-OUTPUT_KEEP:]
    return JobResult(None if timed_out else proc.returncode, timed_out, text, seconds, killed)
