"""The whole suite's markers: ``slow`` for the tests that take more than a few seconds.

``make test-all`` (the README's) runs every test; ``make test`` all but the slow ones, and of each
slow kind one test (:data:`KEPT`); CI runs ``make test-all`` on one Python and ``make test`` on
the other (``.ci/run``).  A test may carry
``@pytest.mark.slow`` itself; the ones below are marked here from measured durations
(``pytest --durations=40``, serial, a shared 2-core machine, and benchmarks/suite_per_test.py),
so their modules need not change: each entry is a node id prefix ("file" or "file::test").
"""

from __future__ import annotations

from pathlib import Path

import pytest

SLOW: tuple[str, ...] = (
    # seconds measured serially at load 5 (tests/kalman + tests/calibration: 255 s serial)
    "tests/calibration/test_montecarlo_memory.py::test_an_hour_at_5_hz_fits_in_tens_of_megabytes",  # 5 CPU s
    "tests/calibration/test_montecarlo.py::test_dask_cluster_gives_the_same_result",  # 21
    "tests/calibration/test_compare.py::test_sweep_",  # the sweeps' fixtures, 18
    "tests/calibration/test_compare.py::test_prior_sweep_",
    "tests/calibration/test_compare.py::test_gps_sweep_",
    "tests/calibration/test_montecarlo.py::test_cli_montecarlo_prints_the_table",  # 8
    # every one executes a notebook, renders one, or runs otter in a kernel
    "tests/lessons/test_lessons.py::test_solutions_version_runs_with_a_tick_under_every_self_check",
    "tests/lessons/test_lessons.py::test_student_version_runs_and_shows_no_answer",
    "tests/lessons/test_lessons.py::test_a_lesson_leaves_nothing_in_the_temporary_folder",
    "tests/lessons/test_lessons.py::test_the_temporary_folder_check_sees_what_a_lesson_leaves",
    "tests/lessons/test_figures.py",
    "tests/cli/test_lessons.py::test_lessons_html",
    "tests/cli/test_lessons.py::test_lessons_kernel",
    "tests/assignments/",
    # the checker's command on a hostile class, its Ctrl-C, its SIGTERM and SIGHUP: each kind
    # once in the quick run, under the basic backend, the one with more of its own code (the box
    # user, rlimits, the fence; tests/sandbox tries every attack under both backends); a hostile
    # class with one worker and under bwrap only in the whole run (5-6 CPU s each)
    "tests/check/test_batch.py::test_a_class_with_hostile_files_keeps_every_honest_verdict[bwrap-",
    "tests/check/test_batch.py::test_a_class_with_hostile_files_keeps_every_honest_verdict[basic-1]",
    "tests/check/test_batch.py::test_ctrl_c_kills_every_student_process_and_writes_what_is_done[bwrap-",
    "tests/check/test_batch.py::test_sigterm_and_sighup_stop_a_class_check_as_ctrl_c_does[bwrap-",
    # each coop mistake's code on its second seed (the first is in the quick run)
    "tests/check/problems/test_coop.py::test_coop_mistakes_get_their_code[1-",
)

#: Module fixtures that draw every figure of a report ("file::fixture"): every test that uses one,
#: however indirectly, is slow (report 002's: 10.6 CPU s; 000, 001 and 003's: 9.3; 004's: 5.3); a
#: new test on them joins the slow ones by itself.  The quick run keeps one report drawn through
#: the command (test_figures.py::test_cli_figures_one_report, 2.7) and the legend check's own test.
SLOW_FIXTURES: tuple[str, ...] = (
    "tests/figures/test_r002.py::drawn",
    "tests/figures/test_figures.py::drawn",
    "tests/figures/test_r004.py::drawn",
)

#: Of each slow kind, the one test the quick run keeps (never marked, though a SLOW entry
#: covers it), so ``make test`` still executes a lesson and grades a homework in its boxes:
#: the cheapest lesson (02, 1.4 CPU s at 20 runs; its student version reads the same execution) and
#: the tracker's homework (3.7 CPU s for its class).  The others of these kinds keep themselves:
#: the docs site's links (tests/test_docs.py, on the site CI builds, else built once per content)
#: and the core wheel in a fresh environment (tests/test_packaging.py).
KEPT: tuple[str, ...] = (
    "tests/lessons/test_lessons.py::test_solutions_version_runs_with_a_tick_under_every_self_check"
    "[02-error-model]",
    "tests/lessons/test_lessons.py::test_student_version_runs_and_shows_no_answer[02-error-model]",
    "tests/assignments/test_tracker.py",
)


#: The costliest work units (node id prefixes), costliest first: ``make test-all`` (``--dist loadscope``)
#: hands them out first, so the two workers end together instead of one running a long unit alone
#: at the end.  From ``--durations`` (2 workers, load 10 and more).
FIRST: tuple[str, ...] = (
    "tests/assignments/test_attacks.py",  # the whole run's (make test-all)
    "tests/assignments/test_coop.py",
    "tests/assignments/test_hostile_class.py",
    "tests/assignments/test_grading.py",
    "tests/check/test_batch.py",  # the quick run's too (make test)
    "tests/test_docs.py",
    "tests/test_packaging.py",
    "tests/lessons/test_lessons.py",
    "tests/assignments/",
    "tests/check/problems/test_coop.py",
    "tests/check/problems/test_calibration.py",
    "tests/sandbox/test_hostile.py",
    "tests/calibration/test_montecarlo_memory.py",
    "tests/figures/",
    "tests/sandbox/test_attacks.py",
)

#: Modules whose parametrized tests are work units of their own, one per parameter (a lesson):
#: they share no module fixture, and one unit of 18 lesson executions kept a worker busy alone at
#: the end.  The disk cache's lock keeps a lesson executed once either way.
SPLIT: tuple[str, ...] = ("tests/lessons/test_lessons.py",)


#: Third-party packages that pytest marks for assertion rewriting only because they ship a pytest
#: plugin: every module of theirs imported in a run is then parsed, rewritten and compiled from
#: source in each process, their bytecode ignored (hypothesis: 1 CPU s per xdist worker at
#: collection, against 0.2 s to import it).  Their own asserts are not the suite's.
NOT_REWRITTEN: tuple[str, ...] = ("hypothesis",)


def pytest_configure(config: pytest.Config) -> None:
    must = getattr(getattr(config.pluginmanager, "rewrite_hook", None), "_must_rewrite", None)
    if isinstance(must, set):  # pytest's AssertionRewritingHook (absent with --assert=plain)
        must.difference_update(NOT_REWRITTEN)


@pytest.hookimpl(tryfirst=True)  # before -k and -m deselect: every collected item is marked
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    mark_slow(items, SLOW, KEPT, SLOW_FIXTURES)
    if hasattr(config, "workerinput"):  # an xdist worker: the controller hands out in this order
        items.sort(key=lambda item: first_rank(item.nodeid.replace("\\", "/"), FIRST))


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    """``--dist loadscope`` with :func:`work_unit`'s units, handed out in the collection's order
    (the costliest first, above) instead of the largest units first.  (``--dist loadgroup`` cannot
    do this: pytest-xdist 3.8 renames its items through ``_nodeid``, which pytest 9 ignores.)"""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class CostliestFirst(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return work_unit(nodeid)

    config.option.loadscopereorder = False
    return CostliestFirst(config, log)


def work_unit(nodeid: str, split: tuple[str, ...] = SPLIT) -> str:
    """The test's work unit: its module (or class), as ``--dist loadscope`` has it, except in
    the ``split`` modules: its parameters (``module[params]``)."""
    module = nodeid.split("::")[0]
    if module in split and nodeid.endswith("]") and "[" in nodeid:
        return f"{module}[{nodeid[nodeid.index('[') + 1:-1]}]"
    return nodeid.rsplit("::", 1)[0]


def first_rank(nodeid: str, first: tuple[str, ...]) -> int:
    """The position of the first ``first`` prefix ``nodeid`` starts with; after all, if none."""
    return next((k for k, prefix in enumerate(first) if nodeid.startswith(prefix)), len(first))


def mark_slow(items: list[pytest.Item], slow: tuple[str, ...], kept: tuple[str, ...] = (),
              fixtures: tuple[str, ...] = ()) -> None:
    """Mark the items that an entry of ``slow`` names, or that use a fixture ``fixtures`` names
    ("file::fixture"), and that no entry of ``kept`` names; UsageError for an entry that names
    no test (no fixture).

    An entry is stale when its file was collected but defines no test (fixture) it names (the
    test was renamed: it would then run in every "not slow" run, as 30 lesson notebooks did on
    3.13, or, kept, in none).  That is read from the module itself, not from the items, which are
    only the selected ones under ``pytest file::test``: a slow test run on its own, or ``-k``,
    must not make its neighbours' entries look stale.
    """
    modules: dict[str, object] = {}
    by_file: dict[str, set[str]] = {}
    for entry in fixtures:
        file, name = entry.split("::", 1)
        by_file.setdefault(file, set()).add(name)
    for item in items:
        node = item.nodeid.replace("\\", "/")
        file = node.split("::")[0]
        uses = by_file.get(file, set()) & set(getattr(item, "fixturenames", ()))
        if (uses or any(node.startswith(prefix) for prefix in slow)) and \
                not any(node.startswith(prefix) for prefix in kept):
            item.add_marker(pytest.mark.slow)
        module = item.getparent(pytest.Module)
        if module is not None:
            modules.setdefault(file, module.obj)
    for name, entries in (("SLOW", slow), ("KEPT", kept)):
        stale = [p for p in entries if "::" in p and p.split("::")[0] in modules
                 and not _defines(modules[p.split("::")[0]], p.split("::")[1:])]
        if stale:
            raise pytest.UsageError(f"tests/conftest.py {name} names tests that do not exist: "
                                    f"{stale}")
    stale = [p for p in fixtures if p.split("::")[0] in modules
             and not hasattr(modules[p.split("::")[0]], p.split("::")[1])]
    if stale:
        raise pytest.UsageError(f"tests/conftest.py SLOW_FIXTURES names fixtures that do not "
                                f"exist: {stale}")


def _defines(obj: object, parts: list[str]) -> bool:
    """Whether ``obj`` (a test module) defines a test whose node id starts with ``::``.join(parts):
    classes by exact name, then a function whose name (or ``name[parameters]``) starts so."""
    for part in parts[:-1]:
        obj = getattr(obj, part, None)
        if obj is None:
            return False
    last = parts[-1]
    return any(name.startswith(last) or last.startswith(name + "[")
               for name in dir(obj) if name.startswith("test") or name.startswith("Test"))


# ---------------------------------------------------------------------------- shared, cached work
# Executing a notebook or running ``otter assign`` costs seconds to minutes; these fixtures do each
# piece of work once per content: the result is kept on disk under a key that hashes everything
# it depends on (the file's bytes, the gpsaccel package's source, the Python and library
# versions, the arguments), so a change to any of them re-executes, and a file lock lets the
# xdist workers of one run share it.  GPSACCEL_TEST_CACHE names the folder (default
# .pytest_cache/gpsaccel beside tests/); GPSACCEL_TEST_CACHE=off executes every time.

_ROOT = Path(__file__).resolve().parent.parent
_DEPENDENCIES = ("numpy", "scipy", "filterpy", "matplotlib", "ipykernel", "jupyter_client",
                 "nbclient", "nbconvert", "nbformat", "jupyter_server_mathjax", "otter-grader",
                 "tqdm", "ipywidgets")


def _package_digest(root: Path) -> str:
    """sha256 over every file of the package at ``root`` (source, templates, data; not bytecode),
    the Python version and the versions of the libraries a notebook imports."""
    import hashlib
    import importlib.metadata as md
    import sys

    h = hashlib.sha256(sys.version.encode())
    for name in _DEPENDENCIES:
        try:
            h.update(f"{name}={md.version(name)};".encode())
        except md.PackageNotFoundError:
            h.update(f"{name}=none;".encode())
    for path in sorted(root.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
            h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


class DiskCache:
    """Results on disk, ``folder/kind/key``: ``key(*parts)`` hashes the parts with the package's
    digest; ``path(kind, key, make)`` returns the entry, made by ``make(target)`` when missing
    (one maker per key across processes, under a lock)."""

    def __init__(self, folder: Path, package: Path | None = None):
        import gpsaccel

        self.folder = folder
        self.package = package or Path(gpsaccel.__file__).resolve().parent  # default: imported
        self._digest: str | None = None

    @property
    def package_digest(self) -> str:
        if self._digest is None:
            self._digest = _package_digest(self.package)
        return self._digest

    def key(self, *parts: bytes | str) -> str:
        import hashlib

        h = hashlib.sha256(self.package_digest.encode())
        for part in parts:
            h.update(b"\0" + (part if isinstance(part, bytes) else part.encode()))
        return h.hexdigest()[:32]

    def path(self, kind: str, key: str, make) -> Path:
        """The cached entry ``folder/kind/key`` (a file or folder), made by ``make(target)`` under
        the key's lock when it is missing; a failed ``make`` leaves nothing behind."""
        import fcntl
        import os
        import tempfile

        where = self.folder / kind
        where.mkdir(parents=True, exist_ok=True)
        final = where / key
        with open(where / f"{key}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # another worker making it: wait for it
            if not final.exists():
                with tempfile.TemporaryDirectory(dir=where, prefix=f".{key}-") as tmp:
                    made = Path(tmp) / "entry"
                    make(made)
                    os.replace(made, final)
            fcntl.flock(lock, fcntl.LOCK_UN)
        return final


@pytest.fixture(scope="session")
def disk_cache(tmp_path_factory) -> DiskCache:
    """The cache of expensive results; with GPSACCEL_TEST_CACHE=off, a folder of this session."""
    import os

    setting = os.environ.get("GPSACCEL_TEST_CACHE", "")
    if setting.lower() in ("off", "0", "no"):  # once per worker and run
        return DiskCache(tmp_path_factory.getbasetemp() / "gpsaccel-cache")
    return DiskCache(Path(setting) if setting else _ROOT / ".pytest_cache" / "gpsaccel")


@pytest.fixture(scope="session")
def executed_lesson(disk_cache):
    """``executed_lesson(path, runs=None, timeout=600, crop_figures=True)``: the notebook at ``path``
    executed top to bottom by :func:`gpsaccel.lessons.execute` (a fresh kernel, in its own folder),
    as a new ``NotebookNode`` each call.  Executed once per notebook content, package source,
    library versions, ``runs`` and ``crop_figures``; a notebook whose cell raises is not cached
    (the error propagates)."""
    import nbformat

    from gpsaccel.lessons import execute  # the real one, even where a test patches it

    def run(path, runs: int | None = None, timeout: int = 600, crop_figures: bool = True):
        path = Path(path).resolve()
        key = disk_cache.key("lesson", path.name, path.read_bytes(), repr(runs), repr(crop_figures))

        def make(target: Path) -> None:
            nb = execute(path, timeout=timeout, runs=runs, crop_figures=crop_figures)
            nbformat.write(nb, str(target))

        return nbformat.read(str(disk_cache.path("lessons", key, make)), as_version=4)

    return run


@pytest.fixture(scope="session")
def lesson_02_html(disk_cache):
    """``gpsaccel lessons --html DIR --only 02 --runs 10`` run once, as a user runs it (its own
    process): ``(DIR, returncode, stdout, stderr)``; DIR holds 02-error-model.html and
    index.html.  Cached like :func:`executed_lesson` (the lesson's bytes, the package); a run
    that fails is not cached: the fixture fails with its stderr."""
    import os
    import subprocess
    import sys

    from gpsaccel.lessons import solutions_dir

    argv = ["lessons", "--only", "02", "--runs", "10"]
    key = disk_cache.key("cli", *argv, (solutions_dir() / "02-error-model.ipynb").read_bytes())

    def make(target: Path) -> None:
        target.mkdir()
        proc = subprocess.run([sys.executable, "-m", "gpsaccel", *argv, "--html", str(target / "html")],
                              capture_output=True, text=True, timeout=900,
                              env=dict(os.environ, MPLBACKEND="Agg"))
        assert proc.returncode == 0, f"gpsaccel {' '.join(argv)} --html: exit " \
            f"{proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}"
        (target / "returncode").write_text(str(proc.returncode))
        (target / "stdout").write_text(proc.stdout)
        (target / "stderr").write_text(proc.stderr)

    entry = disk_cache.path("cli", key, make)
    return (entry / "html", int((entry / "returncode").read_text()),
            (entry / "stdout").read_text(), (entry / "stderr").read_text())


class NestedFolders:
    """A chain of folders nested ``depth`` deep (what a hostile student hands in) and its removal:
    both on short relative paths, since pytest's rmtree recurses and dies on it and full paths
    would cost O(n²) lookups."""

    @staticmethod
    def make(root, depth: int) -> None:
        """``depth`` folders ``d`` one in the other below the existing folder ``root``."""
        import os

        fd = os.open(root, os.O_RDONLY)
        for _ in range(depth):
            os.mkdir("d", dir_fd=fd)
            fd, old = os.open("d", os.O_RDONLY, dir_fd=fd), fd
            os.close(old)
        os.close(fd)

    @staticmethod
    def remove(top) -> None:
        """Remove ``top`` and the chain below it, from the top down."""
        import os

        top, k = str(top), 0
        while top is not None:
            inner = None
            for e in os.scandir(top):
                if e.is_dir(follow_symlinks=False) and inner is None:
                    k += 1
                    inner = os.path.join(os.path.dirname(top), f".unnest-{k}")
                    os.rename(e.path, inner)
                elif not e.is_dir(follow_symlinks=False):
                    os.unlink(e.path)
            os.rmdir(top)
            top = inner


@pytest.fixture(scope="session")
def nested_folders() -> NestedFolders:
    """Make and remove folders nested too deep for a recursive walk (tests/test_untrusted.py,
    tests/assignments/test_hostile_class.py)."""
    return NestedFolders()
