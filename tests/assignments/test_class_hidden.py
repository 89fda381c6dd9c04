"""A class's own folders are out of every box's reach under ``--sandbox basic``, as under bwrap.

A basic box runs as a uid of its own and reads whatever other users may, and an unzipped LMS
export is world-readable (0755/0644).  Here the whole class is laid out as such an export would
be, under a folder of ``/tmp`` other users may enter (pytest's own ``tmp_path`` is 0700, which
would hide everything and prove nothing): the submissions, the ``--out`` folder with an earlier
run's feedback, a ``--compare-with`` folder, the instructor's own homework folder (its master
with the solutions, ``graded.py``) and the folder of the secret file.  A hostile notebook tries
to read each by absolute path, through ``/proc/<pid>/cwd`` of every process it can see (the
grader works from the submissions folder), and by a relative path from its box.  It answers
question 1 honestly (6 points) and throws its answer away when it read anything, naming what in
its feedback; its honest classmate's grade must not move.

Graded under basic with cold boxes and with warm ones, under bwrap (the control: its boxes see
none of these folders), and once under basic with the hiding taken away, which must leak (so the
attack is known to reach what it aims at).  Every process an attack starts is killed by PID.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import uuid
from pathlib import Path

import nbformat
import pytest

from gpsaccel.classrun import grade, running
from gpsaccel.classrun.grading import grade_class
from gpsaccel.sandbox import fence
from gpsaccel.sandbox.confinement import ZYGOTE_PREFIX

from .._hostile import Started
from .conftest import kill_pids, read_grades
from .test_attacks import HONEST_Q1, _basic_as_root, _bwrap, _procs_with

MARK = f"gpsaccel-hide-{uuid.uuid4().hex[:12]}"
PLANTED = f"planted-{uuid.uuid4().hex}"
HOMEWORK = "hideship"

# {targets}: the files to read; {root}: the class's folder; {sub}: its submissions
ATTACK = """
import glob, os
leaked = []
def _try(path, tag):
    try:
        with open(path, "rb") as f:
            data = f.read(1 << 20)
    except OSError:
        return
    if data:  # every file aimed at holds something of the class's
        leaked.append(tag)
targets = {targets}
for i, t in enumerate(targets):
    _try(t, f"a{i}")                                      # by absolute path
    _try(os.path.relpath(t, os.getcwd()), f"r{i}")        # relative, from the box's folder
    for cwd in glob.glob("/proc/[0-9]*/cwd"):              # the grader works in the class
        _try(os.path.join(cwd, os.path.relpath(t, "{sub}")), f"p{i}")
for t in glob.glob("{root}/**/*", recursive=True):         # whatever the walk lists
    if os.path.isfile(t) and "Attacker" not in t:
        _try(t, "w")
if leaked:
    update = None
    raise RuntimeError("LEAKED " + " ".join(sorted(set(leaked))) + " .")
"""


@pytest.fixture(scope="module")
def homework():
    """The instructor's own copy of the ship homework, registered for this module and
    unregistered after it (a later test that walks every homework must not find its folder
    gone)."""
    import sys

    from gpsaccel import registry
    from gpsaccel.assignments import homework as hw

    top = Path(tempfile.mkdtemp(prefix="gpsaccel-hidehw-"))
    try:
        top.chmod(0o755)
        master = hw.copy_homework("ship", top / HOMEWORK)
        for p in [top / HOMEWORK, *(top / HOMEWORK).rglob("*")]:
            p.chmod(0o755 if p.is_dir() else 0o644)
        assert hw.use_folder(master.parent) == HOMEWORK
        yield master.parent
    finally:
        hw._FOLDERS.pop(HOMEWORK, None)
        registry._ASSIGNMENTS.entries.pop(HOMEWORK, None)
        sys.modules.pop(f"gpsaccel_graded_{HOMEWORK}", None)
        shutil.rmtree(top, ignore_errors=True)


def _notebook(target: Path, *cells: str) -> None:
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in cells]
    target.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, str(target))


def _class(root: Path, homework: Path) -> dict:
    """The class laid out world-readable, as an unzipped export is; what the attack aims at."""
    sub, out, earlier, keys = root / "submissions", root / "grades", root / "earlier", root / "keys"
    victim = sub / "Classmate" / f"{HOMEWORK}.ipynb"
    _notebook(victim, HONEST_Q1 + f"\n# {PLANTED}")
    _notebook(earlier / "Last Year" / f"{HOMEWORK}.ipynb", HONEST_Q1 + f"\n# {PLANTED}")
    out.mkdir()
    (out / "feedback-of-everyone.txt").write_text(PLANTED)
    keys.mkdir()
    (keys / "roster.csv").write_text(PLANTED)
    secret = keys / "secret.txt"
    secret.write_text(f"{PLANTED}-secret-of-the-instructor")
    targets = [victim, out / "feedback-of-everyone.txt", out / "grades.csv",
               earlier / "Last Year" / f"{HOMEWORK}.ipynb", homework / f"{HOMEWORK}.ipynb",
               homework / "graded.py", keys / "roster.csv", secret]
    cell = ATTACK
    for key, val in (("{targets}", repr([str(t) for t in targets])), ("{root}", str(root)),
                     ("{sub}", str(sub))):
        cell = cell.replace(key, val)
    _notebook(sub / "Attacker" / f"{HOMEWORK}.ipynb", HONEST_Q1, cell)
    for p in [root, *root.rglob("*")]:
        p.chmod(0o755 if p.is_dir() else 0o644)
    secret.chmod(0o600)  # a world-readable secret is refused (below)
    return {"sub": sub, "out": out, "earlier": earlier, "secret": secret}


#: (backend, warm boxes, hidden, the basic fence: Landlock where this kernel has it, or the mount
#: namespace with Landlock taken away)
CASES = [pytest.param(("basic", False, True, "host"), id="basic"),
         pytest.param(("basic", True, True, "host"), id="basic-warm"),
         pytest.param(("basic", False, True, "mount"), id="basic-mount-fence"),
         pytest.param(("bwrap", False, True, "host"), id="bwrap-control",
                      marks=pytest.mark.skipif(not _bwrap(), reason="needs a working bubblewrap")),
         pytest.param(("basic", False, False, "host"), id="basic-unhidden-must-leak")]


@pytest.fixture(scope="module", params=CASES)
def graded(homework, request):
    if not _basic_as_root():
        pytest.skip("basic isolates a student only as root")
    backend, warm, hidden, kind = request.param
    if kind == "mount" and not fence.mounts_allowed():
        pytest.skip("this process may not make a mount namespace")
    top = Path(tempfile.mkdtemp(prefix="gpsaccel-hideclass-"))
    top.chmod(0o755)  # mkdtemp's 0700 would hide the class from every other user
    try:
        c = _class(top / "class", homework)
        started = Started()
        with pytest.MonkeyPatch.context() as patch:
            started.counting(patch)
            if kind == "mount":
                patch.setattr(fence, "landlock_abi", lambda: 0)
            real_choose, chosen = fence.choose, top / "fences.txt"

            def choose(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202 - fence.choose's own
                f = real_choose(*args, **kwargs)  # in each item's process: noted in a file
                with open(chosen, "a", encoding="utf-8") as log:
                    log.write(f"{None if f is None else f.kind}\n")
                return f

            patch.setattr(fence, "choose", choose)
            patch.chdir(c["sub"])  # the grader's /proc/<pid>/cwd
            if not hidden:
                patch.setattr(running, "hidden_from_boxes",
                              lambda *a, **k: __import__("contextlib").nullcontext())
            grades = grade_class(c["sub"], HOMEWORK, out=c["out"], jobs=2, timeout=60, seed=7,
                                 secret_file=c["secret"], sandbox=backend, warm_boxes=warm,
                                 compare_with=c["earlier"]).grades
        rows = read_grades(c["out"] / "grades.csv")
        modes = {k: os.stat(c[k]).st_mode & 0o777 for k in ("sub", "out", "earlier")}
        fences = set(chosen.read_text().split()) if chosen.exists() else set()
    finally:
        kill_pids(_procs_with(MARK) + _procs_with(f"{ZYGOTE_PREFIX}{os.getpid()}-"))
        shutil.rmtree(top, ignore_errors=True)
    return {"grades": {g.student: g for g in grades}, "rows": rows, "hidden": hidden,
            "backend": backend, "modes": modes, "warm": warm, "kind": kind, "fences": fences,
            "started": (started.cold, started.warm)}


def test_each_basic_box_had_the_fence_asked(graded):
    """Each basic box hid the folders with this host's kernel fence (Landlock here), or with the
    mount namespace where Landlock was taken away; bwrap's boxes need none."""
    if graded["backend"] == "bwrap":
        assert graded["fences"] == set()
    else:
        assert graded["fences"] == {"mount" if graded["kind"] == "mount"
                                    else fence.supported().split()[0]}


def test_every_box_started_as_the_run_asked(graded):
    """A warm run's boxes all start from its zygotes, whose key holds the hidden folders (the
    attack is tried on warm boxes, not on cold ones a zygote could not serve)."""
    cold, warm = graded["started"]
    assert (cold, warm > 0) == (0, True) if graded["warm"] else (cold > 0, warm) == (True, 0)


def test_the_attacker_reads_nothing_of_the_class(graded):
    g = graded["grades"]["Attacker"]
    if not graded["hidden"]:  # the attack reaches each thing it aims at when nothing hides it
        assert (g.total, "LEAKED" in g.feedback) == (0.0, True), g.feedback
        # every file aimed at, by absolute and by relative path (grades.csv: the run's record,
        # written before the boxes), but the 0600 secret itself
        tags = g.feedback.split("LEAKED ", 1)[1].split(" .")[0].split()
        assert {t for t in tags if t[0] in "ar"} == {
            f"{how}{i}" for how in "ar" for i in range(7)}, tags
        assert "w" in tags
        return
    assert "LEAKED" not in g.feedback, g.feedback
    assert (g.status, g.total) == ("graded", 6.0), g.feedback
    assert graded["rows"]["Attacker"]["total"] == "6"


def test_the_classmate_keeps_the_grade(graded):
    g = graded["grades"]["Classmate"]
    assert (g.status, g.total) == ("graded", 6.0), g.feedback
    assert graded["rows"]["Classmate"]["total"] == "6"


def test_the_folders_modes_are_left_alone_where_a_kernel_fence_works(graded):
    """Landlock or a mount namespace fences them: the instructor's folders keep their modes
    (only the permissions fence closes them, :func:`gpsaccel.sandbox.outside.close_to_others`)."""
    if fence.supported() in ("permissions", "none"):
        pytest.skip("this host fences by permissions")
    assert set(graded["modes"].values()) == {0o755}


def test_a_world_readable_secret_file_is_refused_by_the_python_entry_point(tmp_path, monkeypatch):
    open_dir = Path(tempfile.mkdtemp(prefix="gpsaccel-hidesecret-"))
    try:
        open_dir.chmod(0o755)
        secret = open_dir / "secret.txt"
        secret.write_text("x" * 32)
        secret.chmod(0o644)
        if not running.open_to_others(secret):
            pytest.skip("/tmp is not open to other users here")
        monkeypatch.setattr(running, "backend_of", lambda sandbox, *a: "basic")
        sub = tmp_path / "subs"
        _notebook(sub / "a" / "ship.ipynb", HONEST_Q1)
        with pytest.raises(ValueError, match=r"secret_file.*chmod 600"):
            grade(sub, "ship", out=tmp_path / "out", secret_file=secret, sandbox="basic")
        assert not (tmp_path / "out" / "grades.csv").exists()
    finally:
        shutil.rmtree(open_dir, ignore_errors=True)
