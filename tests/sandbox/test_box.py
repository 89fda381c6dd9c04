"""A box (gpsaccel.sandbox.run) under every backend: the generic calls another checker builds on,
a student's file that shadows numpy running only after the runner's guards, and the results a box
sent before it stopped."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from gpsaccel import sandbox as sb
from gpsaccel.check.problems import calibration as wf

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=20)


def test_generic_calls_of_several_functions(tmp_path, backend):
    """What another checker (coop, ship) builds on: named functions, numpy inputs, declared
    outputs of any numeric dtype, one array or a tuple; an output declared ``column`` takes
    filterpy's column form too (its axis dropped in the box) and nothing else."""
    (tmp_path / "student.py").write_text(
        "import numpy as np\n\n"
        "def jacobian(x, u):\n    return np.outer(x, u)\n\n"
        "def counts(z):\n    return np.arange(len(z)), float(z.sum())\n\n"
        "def column(x):\n    return x[:, None]\n")
    sub = sb.load_submission(tmp_path / "student.py", "jacobian")
    x, u = np.array([1.0, 2.0]), np.array([3.0, 4.0, 5.0])
    calls = [sb.Call("jacobian", (x, u), (sb.Output("F", (2, 3)),)),
             sb.Call("counts", (np.ones(4),), (sb.Output("k", (4,), "int64"),
                                                sb.Output("s", ()))),
             sb.Call("column", (x,), (sb.Output("c", (2,), column=True),)),
             sb.Call("column", (x,), (sb.Output("c", (2, 1), column=True),)),
             sb.Call("jacobian", (x, x), (sb.Output("F", (2, 3), column=True),))]
    box = sb.run(sub, calls, LIMITS, backend)
    assert box.backend == backend
    np.testing.assert_array_equal(box.results[0]["F"], np.outer(x, u))
    assert box.results[1]["k"].dtype == np.int64 and box.results[1]["s"] == 4.0
    np.testing.assert_array_equal(box.results[2]["c"], x)            # (2, 1) came back as (2,)
    np.testing.assert_array_equal(box.results[3]["c"], x[:, None])   # already what was declared
    assert len(box.results) == 4 and box.failure == "wrong-shape"    # (2, 2) is no column of (2, 3)
    assert box.problem["call"] == 4 and box.problem["got"] == [2, 2]


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


#: Ways a box stops in its third call (every process it starts named :data:`COMM`; every flood
#: bounded by itself too): the results of the two calls before it must come back.
STOPS = {
    "timeout": "time.sleep(300)",
    "process-limit": ("for _ in range(40):\n"
                      "            if os.fork() == 0:\n"
                      "                time.sleep(30)\n"
                      "                os._exit(0)\n"
                      "        time.sleep(30)"),
    "memory-limit": ("hog = []\n"
                     "        while len(hog) < 64:\n"
                     "            hog.append(bytearray(32 << 20))"),
    "crashed": "os.kill(os.getpid(), signal.SIGKILL)",
}
#: The name (comm) of those processes: this module's own, not the hostile tests' marker, whose
#: watchers (in other runs on the machine) kill what carries it; and this process's own (at most
#: 15 bytes, a comm's room): two pytest-xdist workers, or two suites, each killed the other's
#: boxes by that name (14 of 16 cases failed under -n 2, 'crashed' for the stop).
COMM = f"gpsst-{os.getpid()}"


def _named(comm: str) -> list[int]:
    out = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/comm", "rb") as f:
                if f.read().strip() == comm.encode():
                    out.append(int(pid))
        except OSError:
            pass
    return out


@pytest.mark.parametrize("stop", list(STOPS))
def test_results_before_a_stop_come_back(tmp_path, backend, stop):
    """What a notebook's grade keeps (issue 42): the frames the box sent before a limit, its
    deadline or a kill stopped it are its results, under every backend; no process of it is
    left."""
    (tmp_path / "student.py").write_text(
        "import ctypes, os, signal, time\n"
        f"ctypes.CDLL(None).prctl(15, {COMM.encode()!r}, 0, 0, 0)  # PR_SET_NAME\n\n"
        "def f(i):\n"
        "    if i == 2:\n"
        f"        {STOPS[stop]}\n"
        "    return i + 1.0\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    calls = [sb.Call("f", (np.array(float(i)),), (sb.Output("y", ()),)) for i in range(4)]
    try:
        box = sb.run(sub, calls, sb.Limits(memory=512 << 20, processes=8, time=3), backend)
    finally:
        left = _named(COMM)
        for pid in left:  # run returns once its box is empty: none, unless that broke
            os.kill(pid, signal.SIGKILL)
    assert box.failure == stop, (box.failure, box.detail, box.output[-2000:])
    assert [float(r["y"]) for r in box.results] == [1.0, 2.0]
    assert left == []


def test_nothing_the_box_wrote_outlives_it_in_the_machines_shared_folders(tmp_path, backend):
    """Every folder any user may write (``/run/lock`` too, which ``/var/lock`` names on Debian):
    a basic box's uid left a file in ``/run/lock`` that outlived the class run, for the next box
    of that uid (the next student of the worker) to read."""
    if backend == "basic" and os.geteuid() != 0:
        pytest.skip("a box user needs root; without one the files are the checker's own")
    tag = f"gpsacc-red3-left-{os.getpid()}"
    dirs = ("/tmp", "/var/tmp", "/dev/shm", "/run/lock", "/var/lock")
    (tmp_path / "student.py").write_text(
        "import os\n\n"
        "def f(x):\n"
        f"    for d in {dirs!r}:\n"
        "        try:\n"
        f"            open(os.path.join(d, {tag!r} + str(abs(hash(d)))), 'w').write('x')\n"
        "        except OSError:\n"
        "            pass\n"
        "    return x\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    try:
        box = sb.run(sub, [sb.Call("f", (np.array(1.0),), (sb.Output("y", ()),))], LIMITS, backend)
    finally:
        left = [os.path.join(d, n) for d in dirs if os.path.isdir(d)
                for n in os.listdir(d) if n.startswith(tag)]
        for p in left:
            os.unlink(p)
    assert box.failure is None, box.detail
    assert left == []


def test_the_box_sees_no_command_line_of_the_checker_nor_of_the_machine(tmp_path, backend):
    """A basic box shares the machine's PID namespace: it read every process's command line
    (``gpsaccel grade ... --seed 777`` gave a student the seed in their own feedback).  As root
    its ``/proc`` shows its own uid's processes only; bwrap's has its PID namespace."""
    if backend == "basic" and os.geteuid() != 0:
        pytest.skip("a box user needs root; without one the box is the checker's own user")
    import subprocess
    import sys

    marker = f"gpsacc-red3-seed-{os.getpid()}"
    (tmp_path / "student.py").write_text(
        "import os\n\n"
        "def f(x):\n"
        "    seen = 0\n"
        "    for p in os.listdir('/proc'):\n"
        "        try:\n"
        f"            seen += {marker.encode()!r} in open(f'/proc/{{p}}/cmdline', 'rb').read()\n"
        "        except OSError:\n"
        "            pass\n"
        "    own = 'Uid:' in open('/proc/self/status').read()  # its own, readable\n"
        "    return 10.0 * seen + own\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", "--seed",
                              marker])
    try:
        box = sb.run(sub, [sb.Call("f", (np.array(1.0),), (sb.Output("y", ()),))], LIMITS, backend)
    finally:
        other.kill()
        other.wait()
    assert box.failure is None, box.detail
    assert float(box.results[0]["y"]) == 1.0  # its own processes, and none of the others
