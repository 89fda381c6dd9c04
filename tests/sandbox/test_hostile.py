"""Every hostile submission of tests/submissions/hostile under every sandbox backend, through the
checker's front door (check.submission): the finding it ends in, nothing of it alive afterwards
(Ctrl-C included), and the honest fixtures passing under the same backends.

Hostile runs are bounded (see hostile/README.md): a 512 MiB memory limit and 16 MiB files here, at
most 80 sleeping children, every background process ends by itself within 20 s.  Each test that
starts processes asserts by PID that none is alive when the check returns.
"""

from __future__ import annotations

import os
import signal

import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb

from .._hostile import MARKER

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=20)


# ------------------------------------------------------------------------------- hostile
HOSTILE = [  # file, expected codes (both backends unless a dict by backend)
    ("imports_gpsaccel.py", ["uses-checker"]),
    ("sneaky_import.py", ["uses-checker"]),
    ("patches_runner.py", ["result-refused"]),
    ("classmates/copier.py", ["import-error"]),
    ("memory_hog.py", ["memory-limit"]),
    ("output_flood.py", ["output-limit"]),
    ("file_flood.py", ["file-limit"]),
    ("zip_bomb.py", ["result-refused"]),
    ("fork_lingers.py", ["process-limit"]),
    ("memory_reader.py", ["exception"]),
    ("env_reader.py", ["exception"]),
]


@pytest.mark.parametrize("name, codes", HOSTILE, ids=[n[:-3] for n, _ in HOSTILE])
def test_hostile_submission_fails_with_its_code(name, codes, backend, hostile, watch,
                                                monkeypatch):
    monkeypatch.setenv("GPSACCEL_TEST_SECRET_TOKEN", "hunter2-in-the-checker")
    report = check.submission(hostile.DIR / name, n_runs=3, timeout=LIMITS.time,
                              sandbox=backend, limits=LIMITS)
    assert report.codes == codes, report
    text = str(report)
    assert "LEAK" not in text and "hunter2" not in text
    for f in report.findings:
        if f.severity == "error":
            assert len(f.message) > 60, f  # a sentence a student can act on
    assert not hostile.alive(watch.seen), f"alive after the check: {hostile.alive(watch.seen)}"
    if name == "fork_lingers.py":
        assert len(watch.seen) > LIMITS.processes // 2  # the watcher did see the children
    # the readers see neither the checker's memory nor its environment (their messages say why)
    if name == "memory_reader.py":
        # bwrap: the checker is not even in the box's PID namespace; basic as root: the box's
        # own /proc shows it none of the checker's processes; else it sees it, but closed
        from gpsaccel.sandbox import fence

        hidden = backend == "bwrap" or os.geteuid() == 0 and fence.private_proc_allowed()
        expected = "LookupError" if hidden else "PermissionError"
        assert expected in report.findings[0].message, report
    if name == "env_reader.py":
        assert "no secret in reach" in report.findings[0].message, report


def test_processes_left_behind_are_killed_and_reported(backend, hostile, watch):
    report = check.submission(hostile.DIR / "fork_leaves_two.py", n_runs=3, sandbox=backend)
    assert report.passed, report  # a correct filter: the children cost it nothing but a warning
    assert len(watch.seen) >= 3  # the runner and its two children
    assert not hostile.alive(watch.seen)
    # counted while the runner waits after its last frame (under bwrap they would die with the
    # PID namespace once it exits)
    assert report.details["processes_killed"] == 2
    assert "left-processes" in [f.code for f in report.findings]


def _disguised(marker: str) -> set[int]:
    """Live processes named ``bwrap`` with ``marker`` on their command line (named_bwrap.py's
    child: its comm is the disguise, so the watcher's look for the marker's comm misses it)."""
    out = set()
    for name in os.listdir("/proc"):
        try:
            with open(f"/proc/{name}/comm", "rb") as f:
                if f.read() != b"bwrap\n":
                    continue
            with open(f"/proc/{name}/cmdline", "rb") as f:
                args = f.read().split(b"\0")
            with open(f"/proc/{name}/stat", "rb") as f:
                state = f.read().rsplit(b")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if marker.encode() in args and state not in (b"Z", b"X"):
            out.add(int(name))
    return out


def test_a_process_named_bwrap_is_counted_and_killed(backend, hostile, watch):
    """A student's process may give itself any name (prctl PR_SET_NAME), ``bwrap`` too, the
    name of the box's own processes (bwrap's two, a warm box's pid 1).  The count of what a
    student left running skipped every process so named, so the child hid from it (0 counted,
    no ``left-processes``); the box's own are now known by their pids (the process the
    supervisor started and its child, the box's pid 1), which no student can choose."""
    marker = f"{hostile.MARKER}-bwrap"
    assert not _disguised(marker)
    try:
        report = check.submission(hostile.DIR / "named_bwrap.py", n_runs=3, sandbox=backend)
        assert report.passed, report
        assert report.details.get("processes_killed", 0) == 1, report.details
        assert "left-processes" in [f.code for f in report.findings]
        assert not _disguised(marker)  # killed: it sleeps 20 s otherwise
        assert not hostile.alive(watch.seen)
    finally:  # a failed test must not leave it to the next one
        for pid in _disguised(marker):
            os.kill(pid, signal.SIGKILL)


def test_a_daemon_does_not_outlive_the_check(backend, hostile, watch):
    report = check.submission(hostile.DIR / "daemon.py", n_runs=3, sandbox=backend)
    assert not report.passed
    assert watch.seen and not hostile.alive(watch.seen)


def test_an_instructor_may_allow_gpsaccel(backend, hostile):
    report = check.submission(hostile.DIR / "imports_gpsaccel.py", n_runs=2, sandbox=backend,
                              allow_gpsaccel=True, timeout=60)
    assert report.passed, report


# ------------------------------------------------------------------ honest submissions
CORRECT = ["correct_covariance.py", "correct_information.py", "correct_joseph.py",
           "correct_filterpy.py", "correct_gps_rate.py", "correct_lists.py",
           "correct_prints_a_lot.py"]


@pytest.mark.parametrize("name", CORRECT, ids=[n[:-3] for n in CORRECT])
def test_every_correct_fixture_passes_under_every_backend(name, backend, hostile):
    report = check.submission(hostile.SUBMISSIONS / name, n_runs=5, seed=1, sandbox=backend)
    assert report.passed, report
    assert report.details["sandbox"] == backend


def _single_check(tmp_path, backend, hostile, watch, sig, processes):
    """A spinning submission (``processes`` of it: the runner, and a child when 2) checked by
    ``check.submission`` in a process of its own, given ``sig`` once they all run; the process
    (ended) and its stderr."""
    import subprocess
    import sys
    import time

    spin = tmp_path / "spin.py"
    spin.write_text("import ctypes, os\n\nctypes.CDLL(None).prctl(15, b'" + MARKER + "', 0, 0, 0)"
                    "\n\n\ndef kalman_filter(z):\n" + "    os.fork()\n" * (processes - 1) +
                    "    while True:\n        pass\n")
    # SIGINT's handler put back: a suite started as a script's background job has it ignored,
    # which this process would inherit (POSIX), and Ctrl-C would then never reach the check
    code = (f"import signal\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
            f"from gpsaccel import check\n"
            f"check.submission({str(spin)!r}, n_runs=2, timeout={2 * hostile.HANG}, "
            f"sandbox={str(backend)!r})\n")
    if backend.warm:  # its box forked from a zygote of that process's
        backend.elsewhere = True
        code = ("from gpsaccel import sandbox as sb\n"
                "with sb.warm_boxes(sb.Warm(('numpy',))):\n"
                + "".join("    " + line + "\n" for line in code.splitlines()))
    proc = subprocess.Popen([sys.executable, "-c", code], env=hostile.env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        # the event: the student's processes exist (their marker, set when the box imports the
        # file); the deadline only guards against a hang
        deadline = time.monotonic() + hostile.HANG
        while len(watch.seen) < processes and time.monotonic() < deadline and \
                proc.poll() is None:
            time.sleep(0.05)
        assert len(watch.seen) == processes, proc.communicate(timeout=hostile.HANG)
        proc.send_signal(sig)
        # the box's time limit (2 HANG) is beyond the guard below, so only the signal can end
        # the check; then the box's processes must go (they spin forever otherwise)
        _, err = proc.communicate(timeout=hostile.HANG)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc, err


def test_ctrl_c_during_a_single_check_kills_the_box(tmp_path, backend, hostile, watch):
    """A notebook's check.submission interrupted: nothing of the student's spins on."""
    import signal

    _, err = _single_check(tmp_path, backend, hostile, watch, signal.SIGINT, 1)
    assert b"KeyboardInterrupt" in err
    left = hostile.wait_gone(watch.seen)
    assert not left, f"alive after Ctrl-C: {left}"


def test_sigterm_during_a_single_check_empties_the_box_then_ends_the_process(tmp_path, backend,
                                                                            hostile, watch):
    """A box run outside a pool (a notebook's check.submission, Gradescope's one notebook):
    SIGTERM, which would end the process at once, first empties the box (its processes, its
    cgroup, its folder), then ends the process by SIGTERM; nothing of the box is alive when the
    process is gone (counted then, no clock)."""
    import glob
    import signal
    import tempfile

    proc, _ = _single_check(tmp_path, backend, hostile, watch, signal.SIGTERM, 2)
    assert proc.returncode == -signal.SIGTERM
    assert not hostile.alive(watch.seen), f"alive after SIGTERM: {hostile.alive(watch.seen)}"
    assert not glob.glob(os.path.join(tempfile.gettempdir(), f"gpsaccel-box-{proc.pid}-*"))


