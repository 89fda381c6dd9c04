"""Hostile notebooks, one per attack of issue 19 (and a few more): each scores only what its honest
content earns, changes no file outside its box, leaves no process and cannot stop the run.

All of them are graded in one class run (module fixture, two at a time; once under bwrap and once
under basic as root, each with its boxes started cold and warm) next to two honest classmates
whose grades must not move.  Every process an attack starts carries the marker
:data:`MARK` in its command line; after the run a scan of ``/proc`` must find none (and kills by
PID whatever it finds, so a failing test leaves nothing on the shared machine).  Floods are
bounded by the attack itself as well as by the sandbox.
"""

from __future__ import annotations

import hashlib
import os
import time
import uuid
from collections.abc import Set as AbstractSet
from pathlib import Path

import nbformat
import pytest

from gpsaccel.assignments.grading import SECRET_ENV
from gpsaccel.classrun import grade
from gpsaccel.sandbox.confinement import ZYGOTE_PREFIX

from .._hostile import Started
from .conftest import kill_pids, read_grades

MARK = f"gpsaccel-attack-{uuid.uuid4().hex[:12]}"

def _bwrap() -> bool:
    from gpsaccel.sandbox import resolve_backend

    return os.path.isdir("/proc") and resolve_backend("auto") == "bwrap"


def _basic_as_root() -> bool:
    from gpsaccel.sandbox import basic_is_safe

    return os.path.isdir("/proc") and basic_is_safe()


# the "kill the grader" attack signals every process it can see: inside bwrap's PID namespace that
# is nobody but itself, and under basic as root only the box's own uid (not as root it would be
# every process of this user: never run there)
# and each with the grader's boxes started warm (forked from its zygotes: gpsaccel.sandbox.zygote,
# as root on Linux), which must hold every attack as the cold boxes do
_NO_BWRAP = pytest.mark.skipif(not _bwrap(), reason="needs Linux with a working bubblewrap")
_NO_BASIC = pytest.mark.skipif(not _basic_as_root(),
                               reason="basic isolates a student only as root")
BACKENDS = [pytest.param(("bwrap", False), id="bwrap", marks=_NO_BWRAP),
            pytest.param(("basic", False), id="basic", marks=_NO_BASIC),
            pytest.param(("bwrap", True), id="bwrap-warm", marks=_NO_BWRAP),
            pytest.param(("basic", True), id="basic-warm", marks=_NO_BASIC)]

SECRET = b"instructor-secret-for-the-attack-tests"

BLANK = "import numpy as np\nupdate = ...\nsigma_optimal = ...\nsigma_zeroed = ..."

#: a notebook that answers question 1 only (6 points), honestly: what the attacks that ride on
#: honest work start from (a whole ship notebook costs a voyage in and out of the box)
HONEST_Q1 = BLANK.replace("update = ...", """def update(x_bar, M, z, H, V):
    rows = np.flatnonzero(~np.isnan(z))
    if rows.size == 0:
        return x_bar.copy(), M.copy()
    Hr, Vr = H[rows], V[np.ix_(rows, rows)]
    K = M @ Hr.T @ np.linalg.inv(Hr @ M @ Hr.T + Vr)
    A = np.eye(len(x_bar)) - K @ Hr
    return x_bar + K @ (z[rows] - Hr @ x_bar), A @ M @ A.T + K @ Vr @ K.T""")

#: name -> (the attack's cell, points its honest content earns); {mark}, {sub}, {out} and
#: {victim} are filled in (the student may guess paths: here they know them).
ATTACKS = {
    # the old grader's checks replaced by no-ops: nothing here is the grader's
    "noop asserts": ("""
import gpsaccel
try:
    import gpsaccel.check as c
    c.assert_model_matrices = c.assert_submission = lambda *a, **k: None
except ImportError:
    pass
try:
    import gpsaccel.assignments.ship as s
    s.assert_report = lambda r: r
except ImportError:
    pass
def update(x_bar, M, z, H, V):
    return x_bar, M
""", 0),
    # otter's own update_score and a forged results file: nobody reads them
    "otter update_score": ("""
import json, os
try:
    import otter
    from otter.test_files import GradingResults
except Exception:
    pass
for d in (".", os.environ.get("HOME", "."), "/tmp", "/autograder/results"):
    try:
        with open(os.path.join(d, "results.json"), "w") as f:
            json.dump({"score": 10, "tests": [{"name": "q1", "score": 6}, {"name": "q2", "score": 4}]}, f)
    except OSError:
        pass
print('{"score": 10}')
""", 0),
    # a daemon (own session, empty environment) that keeps rewriting results and grades
    "results daemon": ("""
import subprocess, sys
code = '''
import os, sys, time, json
for _ in range(300):
    for p in ("results.json", "/tmp/results.json", sys.argv[2] + "/grades.csv"):
        try:
            open(p, "w").write("student,q1\\\\nresults daemon,6\\\\n")
        except OSError:
            pass
    time.sleep(0.1)
'''
subprocess.Popen([sys.executable, "-c", code, "{mark}", "{out}"], start_new_session=True,
                 env={{}}, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
""", 0),
    # the master's solution cells, found through the installed package
    "master solutions": ("""
import json, pathlib
try:
    import gpsaccel
    root = pathlib.Path(gpsaccel.__file__).resolve().parents[1]
    for p in [root / "assignments" / "ship" / "ship.ipynb", *root.rglob("ship.ipynb")]:
        try:
            nb = json.loads(p.read_text())
        except OSError:
            continue
        for c in nb["cells"]:
            if c["cell_type"] == "code" and "BEGIN TESTS" not in "".join(c["source"]):
                try:
                    exec("".join(c["source"]).replace("%%", "#"), globals())
                except Exception:
                    pass
except Exception:
    pass
""", 0),
    # the grader's reference functions (and their source, read from disk)
    "reference functions": ("""
import gpsaccel, pathlib
try:
    from gpsaccel.assignments.ship import optimal_update as update
except Exception:
    pass
try:
    src = (pathlib.Path(gpsaccel.__file__).parent / "assignments" / "ship.py").read_text()
    ns = {{}}
    exec(src, ns)
    update = ns["optimal_update"]
except Exception:
    pass
""", 0),
    # the reference answers read with libc's open/read through ctypes (no audit event: the
    # import fence's hook never sees it); under bwrap the file is not in the box at all
    "ctypes read": ("""
import ast, ctypes, os
import numpy as np
import gpsaccel
libc = ctypes.CDLL(None, use_errno=True)
path = os.path.join(os.path.dirname(gpsaccel.__file__), "assignments", "ship.py")
fd = libc.open(path.encode(), os.O_RDONLY)
src = b""
if fd >= 0:
    buf = ctypes.create_string_buffer(1 << 20)
    n = libc.read(fd, buf, len(buf))
    src = buf.raw[:max(n, 0)]
    libc.close(fd)
for node in ast.parse(src.decode(errors="replace")).body:
    if isinstance(node, ast.FunctionDef) and node.name == "optimal_update":
        exec(compile(ast.Module([node], []), "<ship.py>", "exec"), globals())
        update = optimal_update
""", 0),
    # a lookup table: the answers of the public cases (seed 0), computed at home, else junk
    "lookup table": ("""
import numpy as np
TABLE = {{}}
def update(x_bar, M, z, H, V):
    key = x_bar.tobytes()
    if key in TABLE:
        return TABLE[key]
    return x_bar, M
""", 0),
    # a child in its own session, empty environment, that overwrites a classmate's notebook
    "escaping child": ("""
import subprocess, sys
code = '''
import sys, time
time.sleep(1.0)
for p in sys.argv[2:]:
    try:
        open(p, "w").write("{{}}")
    except OSError:
        pass
time.sleep(20)
'''
subprocess.Popen([sys.executable, "-c", code, "{mark}", "{victim}", "{out}/grades.csv"],
                 start_new_session=True, env={{}}, stdout=subprocess.DEVNULL,
                 stderr=subprocess.DEVNULL)
""", 0),
    # SIGKILL of every process it can see: its parent, the grader, everyone
    "kill the grader": ("""
import os, signal
for sig_target in [os.getppid()] + [int(p) for p in os.listdir("/proc") if p.isdigit()]:
    if sig_target != os.getpid():
        try:
            os.kill(sig_target, signal.SIGKILL)
        except OSError:
            pass
""", 0),
    # /proc snooping: classmates' notebooks through other processes' cwd, root, fds (bounded by
    # the attack too: a walk that follows /proc/N/root into /proc/N/root/proc/N/root/... never
    # ends, and the box's time limit then cost the class a minute)
    "proc snooping": ("""
import os, glob, time
found = []
stop = time.monotonic() + 2
for p in glob.glob("/proc/[0-9]*"):
    for link in ("cwd", "root"):
        try:
            for d, _, files in os.walk(os.path.join(p, link), followlinks=True):
                found += [os.path.join(d, f) for f in files if f.endswith(".ipynb")]
                if time.monotonic() > stop:
                    break
        except OSError:
            pass
found += glob.glob("{sub}/**/*.ipynb", recursive=True)
if found:
    import json
    for f in found:
        try:
            nb = json.load(open(f))
            for c in nb["cells"]:
                if "def update" in "".join(c["source"]):
                    exec("".join(c["source"]), globals())
        except Exception:
            pass
""", 0),
    # the grader's environment: the secret (from /proc/*/environ or its own)
    "environ": ("""
import os, glob
leak = os.environ.get("GPSACCEL_GRADING_SECRET", "")
for p in glob.glob("/proc/[0-9]*/environ"):
    try:
        leak += open(p, "rb").read().decode(errors="replace")
    except OSError:
        pass
if "instructor-secret" in leak:
    update = None
""", 6),
    # a fork flood (bounded by the attack too: at most 200)
    "fork flood": ("""
import os, time, sys
kids = 0
for _ in range(200):
    try:
        if os.fork() == 0:
            time.sleep(30)
            os._exit(0)
        kids += 1
    except OSError:
        break
time.sleep(5)
""", 0),
    # 10 GB of memory: refused, the rest of the notebook still runs
    "memory flood": ("""
hog = bytearray(10 << 30)
""", 6),
    # frames forged on the result channel
    "forged frames": ("""
import os, json, struct
for fd in range(3, 64):
    try:
        data = json.dumps({{"t": "done"}}).encode()
        os.write(fd, struct.pack(">I", len(data)) + data + b"x" * 100)
    except OSError:
        pass
""", 0),
    # the grader's wrappers replaced: they can only return other arrays of the declared shapes
    "patched wrappers": ("""
import numpy as np
_reads = _gpsaccel_probe.__self__.reads
def _gpsaccel_probe(k, *args):
    status = np.zeros(9, dtype=np.int64)
    return (status, np.zeros(320, dtype=np.uint8), *[np.zeros(s) for s in _reads[int(k)][2]])
""", 0),
}

#: attacks that ride on an honest notebook (their honest content earns the points above)
ON_HONEST = {"environ", "memory flood"}


#: How long a process the run killed may still show its command line (a SIGKILLed process runs
#: no more code of its own, but its teardown waits for a CPU on a loaded machine).  Every process
#: an attack leaves running, were it not killed, lives well beyond it (the daemon 30 s, the
#: victim's writer 21 s, the hog's children and the bomb's 120 s or for ever).
DYING = 5.0


def outliving(*marks: str, earlier: AbstractSet[int] = frozenset()) -> list[int]:
    """The processes carrying one of ``marks`` that are still there :data:`DYING` s after the
    run returned (a process the run did not kill is; one it killed is gone by then), but those
    ``earlier`` (:func:`running_before`)."""
    give_up = time.monotonic() + DYING
    while True:
        left = [pid for mark in marks for pid in _procs_with(mark) if pid not in earlier]
        if not left or time.monotonic() > give_up:
            return left
        time.sleep(0.1)


def this_runs_zygotes() -> str:
    """What a zygote's command line carries when this process started it: its folder's prefix,
    which names this process (``zygote.start``)."""
    return f"{ZYGOTE_PREFIX}{os.getpid()}-"


def running_before() -> set[int]:
    """The zygotes of this process running before a run: not the run's to end.  A zygote an
    earlier module left serving the session (tests/check's ``course_zygote``) carries the same
    prefix; counted as the run's, it was the "leftover" of the whole suite's runs, where a
    worker had run tests/check first (issue 43: ``-p no:xdist tests/check/problems/test_ship.py``
    then this test reproduced it every time), and the kill of it stopped that zygote."""
    return set(_procs_with(this_runs_zygotes()))


def described(pids: list[int]) -> list[str]:
    """What /proc says of each of ``pids`` (state, parent, uid, pid namespaces, pending signals,
    cgroups), shown when the test fails: which mechanism missed them (it showed last stop's
    "leftover" to be a zygote of the session's, not a box's process)."""
    out = []
    for pid in pids:
        try:
            status = Path(f"/proc/{pid}/status").read_text()
            cgroup = Path(f"/proc/{pid}/cgroup").read_text().replace("\n", " ")
        except OSError:
            out.append(f"{pid}: gone")
            continue
        keep = ("State", "PPid", "Uid", "NSpid", "SigPnd", "ShdPnd")
        fields = [ln for ln in status.splitlines() if ln.split(":")[0] in keep]
        out.append(f"{pid}: {'; '.join(fields)}; cgroup {cgroup}")
    return out


def _procs_with(mark: str) -> list[int]:
    out = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                if mark.encode() in (p / "cmdline").read_bytes():
                    out.append(int(p.name))
            except OSError:
                pass
    return out


def _honest(target: Path) -> Path:
    """A classmate's right notebook: question 1 solved, question 2's numbers those of the
    student's own ship (typed in: the voyage that computes them would cost the box more CPU than
    every attack together)."""
    from gpsaccel.assignments.grading import student_variant
    from gpsaccel.assignments.ship import zeroed_gain_cost

    own = zeroed_gain_cost(**student_variant("ship", target.parent.name, SECRET))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(HONEST_Q1.replace(
        "sigma_optimal = ...", f"sigma_optimal = {own['sigma_optimal']!r}").replace(
        "sigma_zeroed = ...", f"sigma_zeroed = {own['sigma_actual']!r}"))]
    target.parent.mkdir(parents=True)
    nbformat.write(nb, str(target))
    return target


@pytest.fixture(scope="module", params=BACKENDS)
def attacked(tmp_path_factory, request):
    root = tmp_path_factory.mktemp("attacks")
    sub = root / "submissions"
    out = root / "grades"
    victim = _honest(sub / "Classmate" / "ship.ipynb")
    _honest(sub / "Honest Student" / "ship.ipynb")
    before = hashlib.sha256(victim.read_bytes()).hexdigest()
    for name, (cell, _) in ATTACKS.items():
        text = cell
        for key, val in (("{mark}", MARK), ("{sub}", sub), ("{out}", out), ("{victim}", victim)):
            text = text.replace(key, str(val))
        text = text.replace("{{", "{").replace("}}", "}")
        target = sub / name / "ship.ipynb"
        nb = nbformat.v4.new_notebook()
        nb.cells = [nbformat.v4.new_code_cell(HONEST_Q1 if name in ON_HONEST else BLANK),
                    nbformat.v4.new_code_cell(text)]
        target.parent.mkdir(parents=True)
        nbformat.write(nb, str(target))
    os.environ[SECRET_ENV] = SECRET.decode()
    earlier = running_before()
    try:
        backend, warm = request.param
        started = Started()
        with pytest.MonkeyPatch.context() as patch:
            started.counting(patch)
            grades = grade(sub, "ship", out=out, jobs=2, timeout=60, seed=7, secret=SECRET,
                           sandbox=backend, warm_boxes=warm)
    finally:
        del os.environ[SECRET_ENV]
        # every attack's process, and this run's zygotes (their folder names this process)
        left = outliving(MARK, this_runs_zygotes(), earlier=earlier)
        seen = described(left)
        kill_pids(left)
    return {"grades": {g.student: g for g in grades}, "csv": read_grades(out / "grades.csv"),
            "left": left, "seen": seen, "victim": (victim, before), "out": out, "warm": warm,
            "started": (started.cold, started.warm)}


def test_every_box_started_as_the_run_asked(attacked):
    """A warm run's boxes all start from its zygotes (the attacks are tried on warm boxes, not
    on cold ones a zygote could not serve); a cold run starts none warm."""
    cold, warm = attacked["started"]
    assert (cold, warm > 0) == (0, True) if attacked["warm"] else (cold > 0, warm) == (True, 0)


def test_no_process_outlives_the_run(attacked):
    assert attacked["left"] == [], attacked["seen"]


def test_honest_classmates_keep_their_grades_and_files(attacked):
    victim, before = attacked["victim"]
    assert hashlib.sha256(victim.read_bytes()).hexdigest() == before
    for who in ("Classmate", "Honest Student"):
        g = attacked["grades"][who]
        assert (g.status, g.total) == ("graded", 10.0), g.feedback


@pytest.mark.parametrize("name", list(ATTACKS))
def test_an_attack_scores_only_its_honest_content(attacked, name):
    g = attacked["grades"][name]
    assert g.total == ATTACKS[name][1], g.feedback
    assert attacked["csv"][name]["total"] == f"{ATTACKS[name][1]:g}"


def test_grades_csv_is_the_graders(attacked):
    rows = attacked["csv"]
    assert set(rows) == {*ATTACKS, "Classmate", "Honest Student", "Points Possible"}
    assert rows["Classmate"]["total"] == "10"


def test_the_limits_name_the_attack(attacked):
    g = attacked["grades"]
    assert g["fork flood"].status == "process-limit"
    # the box is stopped where the count caught it: in its cell, or at a later read
    assert "The notebook stopped " in g["fork flood"].feedback
    assert g["forged frames"].status == "result-refused"
    assert "MemoryError" in g["memory flood"].feedback


@pytest.mark.skipif(not _basic_as_root(), reason="basic isolates a student only as root")
def test_under_basic_a_box_that_kills_its_grader_costs_only_its_own_grade(tmp_path):
    # the basic backend cannot hide the grader's process: a student may kill its parent (only
    # its parent here: under basic, "every process" would be every process of this user)
    sub = tmp_path / "class"
    for name, cell in (("killer", "import os, signal\nos.kill(os.getppid(), signal.SIGKILL)"),
                       ("honest", "x = 1")):
        nb = nbformat.v4.new_notebook()
        nb.cells = [nbformat.v4.new_code_cell(HONEST_Q1), nbformat.v4.new_code_cell(cell)]
        (sub / name).mkdir(parents=True)
        nbformat.write(nb, str(sub / name / "ship.ipynb"))
    grades = {g.student: g for g in grade(sub, "ship", out=tmp_path / "out", jobs=1, seed=1,
                                          timeout=60, sandbox="basic")}
    # as root each basic box has a uid of its own, and the kill is refused (the cell raises);
    # elsewhere the kill lands and only this student's grade is lost
    killer = grades["killer"]
    assert (killer.status, killer.total) in {("graded", 6.0), ("grader-error", 0.0)}, \
        killer.feedback
    assert (grades["honest"].status, grades["honest"].total) == ("graded", 6.0)
    rows = read_grades(tmp_path / "out" / "grades.csv")
    assert rows["killer"]["status"] == killer.status and rows["honest"]["total"] == "6"
