"""The sandbox (gpsaccel.sandbox): its generic interface, the result channel, what a
submission is, and every hostile submission of tests/submissions/hostile under every backend.

Hostile runs are bounded (see hostile/README.md): a 512 MiB memory limit and 16 MiB files here, at
most 80 sleeping children, every background process ends by itself within 20 s.  Each test that
starts processes asserts by PID that none is alive when the check returns.
"""

from __future__ import annotations

import json
import os
import struct
import sys

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel.check.problems import calibration as wf
from gpsaccel.sandbox.confinement import _bwrap_command

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=20)


def _frame(header: dict, payload: bytes = b"") -> bytes:
    data = json.dumps(header).encode()
    return struct.pack(">I", len(data)) + data + payload


def _calls(n: int = 2) -> list[sb.Call]:
    return [sb.Call("f", (np.zeros(2),), (sb.Output("a", (2,)), sb.Output("b", (2, 2))))
            for _ in range(n)]


# ------------------------------------------------------------------------ the result channel
def test_frames_are_read_against_the_declared_outputs():
    reader = sb.FrameReader(_calls(2))
    a, b = np.arange(2.0), np.eye(2)
    blob = (_frame({"t": "imported"})
            + _frame({"t": "result", "call": 0}, a.tobytes() + b.tobytes())
            + _frame({"t": "result", "call": 1}, (a + 1).tobytes() + b.tobytes())
            + _frame({"t": "done"}))
    for i in range(0, len(blob), 7):  # in pieces, as a pipe delivers them
        reader.feed(blob[i:i + 7])
    assert reader.done and len(reader.results) == 2
    np.testing.assert_array_equal(reader.results[1]["a"], a + 1)
    assert reader.results[0]["b"].shape == (2, 2) and reader.results[0]["b"].flags.writeable


@pytest.mark.parametrize("blob, words", [
    (struct.pack(">I", 1 << 30), "frame header of 1073741824 bytes"),
    (_frame({"t": "verdict", "passed": True}), "unknown kind 'verdict'"),
    (_frame({"t": "result", "call": 1}), "call 1 where call 0"),
    (_frame({"t": "done"}), "'done' after 0 of 2"),
    (struct.pack(">I", 5) + b"nope!", "not JSON"),
    (_frame([1, 2]), "not a JSON object"),
])
def test_anything_but_the_declared_frames_is_refused(blob, words):
    with pytest.raises(sb.Refused, match=words):
        sb.FrameReader(_calls(2)).feed(blob)


def test_bytes_after_the_last_frame_are_refused_and_memory_stays_bounded():
    reader = sb.FrameReader(_calls(1))
    payload = np.zeros(2).tobytes() + np.eye(2).tobytes()
    ok = _frame({"t": "result", "call": 0}, payload) + _frame({"t": "done"})
    with pytest.raises(sb.Refused, match="after the last frame"):
        reader.feed(ok + b"\0" * 100)
    # a result header that announces a flood: the reader keeps at most the declared size
    reader = sb.FrameReader(_calls(1))
    reader.feed(_frame({"t": "result", "call": 0}))
    reader.feed(b"\0" * (len(payload) - 1))
    assert reader.results == [] and len(reader.buf) < len(payload) + 64
    with pytest.raises(sb.Refused):
        reader.feed(b"\0" * 65536)


# ------------------------------------------------------------------------ the interface
def test_limits_outputs_and_calls_check_their_arguments():
    with pytest.raises(ValueError, match="limits.memory"):
        sb.Limits(memory=1 << 20)
    with pytest.raises(ValueError, match="limits.time"):
        sb.Limits(time=float("inf"))
    with pytest.raises(ValueError, match="limits.processes"):
        sb.Limits(processes=0)
    with pytest.raises(ValueError, match="dtype"):
        sb.Output("x", (3,), "object")
    with pytest.raises(ValueError, match="shape"):
        sb.Output("x", (-1,))
    with pytest.raises(ValueError, match="function"):
        sb.Call("not a name", (), (sb.Output("x", (1,)),))
    with pytest.raises(ValueError, match="sandbox must be one of"):
        sb.resolve_backend("docker")


def test_generic_calls_of_several_functions(tmp_path, backend):
    """What another checker (coop, ship) builds on: named functions, numpy inputs, declared
    outputs of any numeric dtype, one array or a tuple."""
    (tmp_path / "student.py").write_text(
        "import numpy as np\n\n"
        "def jacobian(x, u):\n    return np.outer(x, u)\n\n"
        "def counts(z):\n    return np.arange(len(z)), float(z.sum())\n")
    sub = sb.load_submission(tmp_path / "student.py", "jacobian")
    x, u = np.array([1.0, 2.0]), np.array([3.0, 4.0, 5.0])
    calls = [sb.Call("jacobian", (x, u), (sb.Output("F", (2, 3)),)),
             sb.Call("counts", (np.ones(4),), (sb.Output("k", (4,), "int64"),
                                                sb.Output("s", ()))),
             sb.Call("jacobian", (x, x), (sb.Output("F", (2, 3)),))]
    box = sb.run(sub, calls, LIMITS, backend)
    assert box.backend == backend
    np.testing.assert_array_equal(box.results[0]["F"], np.outer(x, u))
    assert box.results[1]["k"].dtype == np.int64 and box.results[1]["s"] == 4.0
    assert len(box.results) == 2 and box.failure == "wrong-shape"
    assert box.problem["call"] == 2 and box.problem["got"] == [2, 2]


def test_a_students_folder_with_helpers_and_data(tmp_path, backend):
    folder = tmp_path / "bob"
    (folder / "kf").mkdir(parents=True)
    (folder / "kf" / "__init__.py").write_text("")
    (folder / "kf" / "matrices.py").write_text(
        "import numpy as np\n\ndef load():\n"
        "    d = np.load('model.npz')\n    return d['Phi'], d['Q'], d['H'], d['V'], d['M0']\n")
    dt = 0.005
    G = np.array([[-dt**2 / 2], [-dt], [0.0]])
    np.savez(folder / "model.npz", Phi=np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]]),
             Q=G @ G.T * 0.0004, H=np.eye(2, 3), V=np.diag([1.0, 0.04**2]),
             M0=np.diag([100.0, 1.0, 0.01]))
    (folder / "filter.py").write_text(
        "import numpy as np\nfrom kf.matrices import load\n\n"
        "def kalman_filter(z):\n    Phi, Q, H, V, M = load()\n    x = np.zeros(3)\n"
        "    xs, Ps = [], []\n    for k, zk in enumerate(z):\n        if k:\n"
        "            for _ in range(40):\n                x, M = Phi @ x, Phi @ M @ Phi.T + Q\n"
        "        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)\n"
        "        x, M = x + K @ (zk - H @ x), (np.eye(3) - K @ H) @ M\n"
        "        xs.append(x)\n        Ps.append(M)\n    return np.array(xs), np.array(Ps)\n")
    (folder / "notes.txt").write_text("my notes")
    (folder / ".git").mkdir()
    (folder / ".git" / "secret").write_text("not copied")
    sub = sb.load_submission(folder, "kalman_filter")
    assert sub.entry == "filter.py"
    assert set(sub.files) == {"filter.py", "kf/__init__.py", "kf/matrices.py", "model.npz",
                              "notes.txt"}
    report = check.submission(folder, n_runs=3, sandbox=backend)
    assert report.passed, report
    assert report.details["entry"] == "filter.py" and report.details["sandbox"] == backend


def test_a_students_numpy_py_does_not_run_before_the_checkers_guards(tmp_path, backend):
    folder = tmp_path / "eve"
    folder.mkdir()
    (folder / "numpy.py").write_text("print('SHADOW')\nimport gpsaccel\n")
    (folder / "filter.py").write_text(
        "import numpy as np\n\ndef kalman_filter(z):\n"
        "    return np.zeros((len(z), 3)), np.tile(np.eye(3), (len(z), 1, 1))\n")
    box = sb.run(sb.load_submission(folder, "kalman_filter"), wf.calls(np.zeros((2, 151, 2))),
                 LIMITS, backend)
    assert box.failure is None and not box.uses_checker and "SHADOW" not in box.output


def test_what_is_not_a_submission(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "helpers.py").write_text("def propagate(x):\n    return x\n")
    with pytest.raises(sb.SubmissionError, match="defines kalman_filter") as e:
        sb.load_submission(tmp_path / "a", "kalman_filter")
    assert e.value.code == "no-function"
    (tmp_path / "a" / "one.py").write_text("def kalman_filter(z):\n    pass\n")
    (tmp_path / "a" / "two.py").write_text("from one import kalman_filter\n")
    with pytest.raises(sb.SubmissionError, match="one.py, two.py") as e:
        sb.load_submission(tmp_path / "a", "kalman_filter")
    assert e.value.code == "ambiguous-entry"
    report = check.submission(tmp_path / "a", n_runs=2)
    assert report.codes == ["ambiguous-entry"], report
    report = check.submission(tmp_path / "missing.py", n_runs=2)
    assert report.codes == ["not-found"], report


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


def test_the_readers_see_neither_the_checkers_memory_nor_its_environment(backend, hostile,
                                                                         monkeypatch):
    monkeypatch.setenv("GPSACCEL_TEST_SECRET_TOKEN", "hunter2-in-the-checker")
    report = check.submission(hostile.DIR / "memory_reader.py", n_runs=2, sandbox=backend)
    msg = report.findings[0].message
    # bwrap: the checker is not even in the box's PID namespace; basic: it is, but closed
    expected = "LookupError" if backend == "bwrap" else "PermissionError"
    assert expected in msg, msg
    report = check.submission(hostile.DIR / "env_reader.py", n_runs=2, sandbox=backend)
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


def test_a_daemon_does_not_outlive_the_check(backend, hostile, watch):
    report = check.submission(hostile.DIR / "daemon.py", n_runs=3, sandbox=backend)
    assert not report.passed
    assert watch.seen and not hostile.alive(watch.seen)


def test_an_instructor_may_allow_gpsaccel(backend, hostile):
    report = check.submission(hostile.DIR / "imports_gpsaccel.py", n_runs=2, sandbox=backend,
                              allow_gpsaccel=True, timeout=60)
    assert report.passed, report


def test_the_answer_is_computed_only_after_the_box_is_empty(monkeypatch, hostile):
    events = []
    real_run, real_answer = sb.run, wf.with_answer

    def run(*args, **kwargs):
        assert wf._candidates.cache_info().currsize == 0  # no cached covariance either
        events.append("box starts")
        box = real_run(*args, **kwargs)
        events.append("box empty")
        return box

    def with_answer(data):
        events.append("answer")
        return real_answer(data)

    monkeypatch.setattr(sb, "run", run)
    monkeypatch.setattr(wf, "with_answer", with_answer)
    wf._candidates(wf._default_data(2, 0).model, 1)  # fill the cache
    report = check.submission(hostile.SUBMISSIONS / "mutant_m0_order.py", n_runs=2)
    assert report.codes == ["m0-order"]
    assert events == ["box starts", "box empty", "answer"]


# ------------------------------------------------------------------ honest submissions
CORRECT = ["correct_covariance.py", "correct_information.py", "correct_joseph.py",
           "correct_filterpy.py", "correct_gps_rate.py", "correct_lists.py",
           "correct_prints_a_lot.py"]


@pytest.mark.parametrize("name", CORRECT, ids=[n[:-3] for n in CORRECT])
def test_every_correct_fixture_passes_under_every_backend(name, backend, hostile):
    report = check.submission(hostile.SUBMISSIONS / name, n_runs=5, seed=1, sandbox=backend)
    assert report.passed, report
    assert report.details["sandbox"] == backend


def test_ctrl_c_during_a_single_check_kills_the_box(tmp_path, backend, hostile, watch):
    """A notebook's check.submission interrupted: nothing of the student's spins on."""
    import signal
    import subprocess
    import sys
    import time

    spin = tmp_path / "spin.py"
    spin.write_text("import ctypes\n\nctypes.CDLL(None).prctl(15, b'gpsacc-hostile', 0, 0, 0)\n\n\n"
                    "def kalman_filter(z):\n    while True:\n        pass\n")
    code = (f"from gpsaccel import check\n"
            f"check.submission({str(spin)!r}, n_runs=2, timeout={2 * hostile.HANG}, "
            f"sandbox={backend!r})\n")
    proc = subprocess.Popen([sys.executable, "-c", code], env=hostile.env(),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        # the event: the student's process exists (its marker, set when the box imports it);
        # the deadline only guards against a hang
        deadline = time.monotonic() + hostile.HANG
        while not watch.seen and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        assert watch.seen, proc.communicate(timeout=hostile.HANG)
        proc.send_signal(signal.SIGINT)
        # the box's time limit (2 HANG) is beyond the guard below, so only the interrupt can end
        # the check; then the box's processes must go (they spin forever otherwise)
        _, err = proc.communicate(timeout=hostile.HANG)
        assert b"KeyboardInterrupt" in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    left = hostile.wait_gone(watch.seen)
    assert not left, f"alive after Ctrl-C: {left}"


def test_bwrap_mounts_tmp_before_the_interpreters_folders(tmp_path, monkeypatch):
    """A venv below /tmp (CI's fresh clone) must stay visible: bwrap applies its mounts in order,
    so the /tmp tmpfs has to come before every bind, or it hides them."""
    entry = tmp_path / "f.py"
    entry.write_text("def kalman_filter(z):\n    return z\n")
    sub = sb.load_submission(entry, "kalman_filter")
    monkeypatch.setattr(sys, "prefix", "/tmp/some-venv")
    (tmp_path / "control").mkdir()
    cmd, fds = _bwrap_command("bwrap", tmp_path, sub, sb.Limits(), False, 9)
    for fd in fds:
        os.close(fd)
    first_tmpfs = next(i for i in range(len(cmd) - 1) if cmd[i:i + 2] == ["--tmpfs", "/tmp"])
    first_bind = cmd.index("--ro-bind")
    assert first_tmpfs < first_bind
    assert cmd.count("/tmp") == 1  # mounted once


def test_removing_a_box_never_changes_the_mode_of_the_folder_that_holds_it(tmp_path):
    """A box lives in /tmp; removing it once chmod-ed its parent (/tmp) to 0700 when the box's own
    folder could not be removed, which locked every other user (and every later box) out."""
    from gpsaccel.sandbox import confinement

    parent = tmp_path / "shared"
    parent.mkdir()
    parent.chmod(0o1777)
    confinement._remove_tree(str(parent / "gone-already"))  # rmtree fails on the root itself
    box = parent / "box"
    (box / "locked" / "deep").mkdir(parents=True)
    (box / "locked" / "deep" / "f").write_text("x")
    (box / "locked").chmod(0)  # what a student can do to a folder of theirs
    confinement._remove_tree(str(box))
    assert not box.exists()
    assert parent.stat().st_mode & 0o7777 == 0o1777


def test_a_grader_holding_many_descriptors_still_starts_its_boxes(tmp_path, backend):
    """A long-lived grader (a Jupyter kernel, a Dask worker, a test worker that ran hundreds of
    boxes) may hold more descriptors than a box may open.  They are still open in the child when
    preexec runs (close_fds comes after it): with RLIMIT_NOFILE set before the root-only reveal
    mounts opened their folders, every box of such a grader failed to start."""
    (tmp_path / "student.py").write_text("def f(x):\n    return x + 1.0\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    held = [os.open(os.devnull, os.O_RDONLY) for _ in range(LIMITS.open_files + 44)]
    try:
        box = sb.run(sub, [sb.Call("f", (np.ones(2),), (sb.Output("y", (2,)),))], LIMITS,
                     backend)
    finally:
        for fd in held:
            os.close(fd)
    assert box.failure is None, (box.failure, box.detail)
    np.testing.assert_array_equal(box.results[0]["y"], np.full(2, 2.0))
