"""What ``pip install gpsaccel`` gives: declared dependencies, one version, the metadata, the
lessons as package data, ``--version``, ``python -m gpsaccel``, ``lessons --copy``, ``lab``; and a
built wheel installed in a fresh environment outside the repository: with the core alone (the
quick run's wheel test), and with the grading extra for an instructor's steps (slow)."""

from __future__ import annotations

import ast
import importlib.metadata as md
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import gpsaccel
from gpsaccel import lessons, registry
from gpsaccel.cli import main

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
PROJECT = PYPROJECT["project"]


def _name(requirement: str) -> str:
    """The normalized distribution name of a requirement (``"PyYAML>=6"`` -> ``"pyyaml"``)."""
    return re.sub(r"[-_.]+", "-", re.match(r"[A-Za-z0-9_.-]+", requirement).group()).lower()


def _declared(extra: str | None = None, seen: frozenset = frozenset()) -> set[str]:
    """Distributions the core (``extra=None``) or an extra pulls in, extras of gpsaccel expanded."""
    reqs = PROJECT["dependencies"] if extra is None else PROJECT["optional-dependencies"][extra]
    names = set()
    for req in reqs:
        if _name(req) == "gpsaccel":
            for sub in re.search(r"\[(.*)\]", req).group(1).split(","):
                if sub.strip() not in seen:
                    names |= _declared(sub.strip(), seen | {sub.strip()})
        else:
            names.add(_name(req))
    return names


def _imports(source: str) -> set[str]:
    """Top-level module names a piece of Python imports (absolute imports only)."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found


def _third_party_imports() -> dict[str, set[str]]:
    """Every third-party module imported by the package's code and the lessons' code cells, with
    the files that import it."""
    where: dict[str, set[str]] = {}
    sources = [(p, p.read_text(encoding="utf-8")) for p in (ROOT / "gpsaccel").rglob("*.py")]
    for nb in sorted(lessons.lessons_dir().rglob("*.ipynb")):
        cells = json.loads(nb.read_text(encoding="utf-8"))["cells"]
        code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        code = "\n".join(line for line in code.splitlines() if not line.lstrip().startswith(("%", "!")))
        sources.append((nb, code))
    for path, source in sources:
        for module in _imports(source) - set(sys.stdlib_module_names) - {"gpsaccel"}:
            where.setdefault(module, set()).add(str(path.relative_to(ROOT)))
    return where


def test_every_imported_module_is_declared():
    """PyYAML and psutil were imported and never declared: every import's distribution must be a
    dependency of the core or of an extra."""
    declared = _declared() | {n for e in PROJECT["optional-dependencies"] for n in _declared(e)}
    providers = md.packages_distributions()
    undeclared = {}
    for module, files in _third_party_imports().items():
        dists = {_name(d) for d in providers.get(module, [])}
        if not dists & declared:
            undeclared[module] = (sorted(dists) or ["not installed"], sorted(files)[:3])
    assert not undeclared, f"imported but not declared in pyproject.toml: {undeclared}"
    assert "pyyaml" in _declared("grading") and "psutil" in _declared()  # the sandbox: core


@pytest.mark.slow
def test_the_main_job_needs_only_the_core(tmp_path):
    """``gpsaccel run`` (``make run``) imports nothing beyond the core dependencies: every optional
    distribution is made unimportable for it."""
    optional = {n for e in PROJECT["optional-dependencies"] for n in _declared(e)} - _declared()
    providers = md.packages_distributions()
    blocked = sorted(m for m, ds in providers.items()
                     if {_name(d) for d in ds} & optional and not {_name(d) for d in ds} & _declared()
                     and m.isidentifier())
    assert "yaml" in blocked and "nbformat" in blocked
    script = f"""
import sys
BLOCKED = set({blocked!r})
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"blocked optional module {{name}}", name=name)
sys.meta_path.insert(0, Block())
from gpsaccel.cli import main
sys.exit(main(["run", "--runs", "20", "--out", {str(tmp_path / "out")!r}]))
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env=dict(os.environ, MPLBACKEND="Agg"), timeout=240)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "final estimates" in proc.stdout and (tmp_path / "out" / "index.html").is_file()
    # and its files are report 000's figures, each named as tests/figures/ expects (this run
    # draws them: a second `gpsaccel run` there cost 3 CPU s)
    figures = _module(ROOT / "tests" / "figures" / "test_figures.py")
    names = sorted(p.name for p in (tmp_path / "out").glob("*.png"))
    assert [figures.NAME.match(n).group(2) for n in names] == figures.EXPECTED["000"], names


def _module(path: Path):
    """The test module (or conftest) at ``path``, loaded on its own for what it defines."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_loaded_{path.parent.name}_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_one_version():
    """Written once, in gpsaccel/_version.py; the metadata and gpsaccel.__version__ read it."""
    assert "version" not in PROJECT and "version" in PROJECT["dynamic"]
    attr = PYPROJECT["tool"]["setuptools"]["dynamic"]["version"]
    assert attr == {"attr": "gpsaccel._version.__version__"}
    written = [p for p in (ROOT / "gpsaccel").rglob("*.py")
               if re.search(r"^__version__\s*=", p.read_text(encoding="utf-8"), re.M)]
    assert written == [ROOT / "gpsaccel" / "_version.py"]
    assert md.version("gpsaccel") == gpsaccel.__version__


def test_version_flag_and_python_dash_m(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"gpsaccel {gpsaccel.__version__}"
    proc = subprocess.run([sys.executable, "-m", "gpsaccel", "--version"], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0 and proc.stdout.strip() == f"gpsaccel {gpsaccel.__version__}"


def test_metadata_declares_the_tested_pythons_and_the_license():
    meta = md.metadata("gpsaccel")
    tested = re.findall(r"^for v in (.*); do$", (ROOT / ".ci" / "run").read_text(), re.M)[0].split()
    declared = {c.rsplit(":: ", 1)[1] for c in meta.get_all("Classifier")
                if re.fullmatch(r"Programming Language :: Python :: 3\.\d+", c)}
    assert declared == set(tested)
    assert meta["License-Expression"] == "MIT" and (ROOT / "LICENSE").read_text().startswith("MIT")
    assert meta["Author"] or meta["Author-email"]


def test_the_lessons_are_package_data_that_follow_the_checkout():
    """An editable install reads the top-level lessons/ (a student who clones edits those)."""
    assert lessons.lessons_dir().resolve() == (ROOT / "lessons").resolve()
    names = sorted(p.name for p in lessons.lessons_dir().glob("*.ipynb"))
    assert names == sorted(p.name for p in (ROOT / "lessons").glob("*.ipynb")) and len(names) >= 12


def test_lessons_copy_copies_once_and_keeps_a_students_edits(tmp_path, capsys):
    target = tmp_path / "mine"
    assert main(["lessons", "--copy", str(target)]) == 0
    expected = sorted(p.relative_to(lessons.lessons_dir()).as_posix()
                      for p in [*lessons.lessons_dir().glob("*.ipynb"),
                                *lessons.solutions_dir().glob("*.ipynb")])
    got = sorted(p.relative_to(target).as_posix() for p in target.rglob("*.ipynb"))
    assert got == expected
    first = target / expected[0]
    first.write_text("my work", encoding="utf-8")
    assert main(["lessons", "--copy", str(target)]) == 0
    out = capsys.readouterr().out
    assert f"kept {len(expected)} already there" in out and first.read_text() == "my work"
    assert main(["lessons", "--copy", str(target), "--only", "02"]) == 2
    assert "--copy" in capsys.readouterr().err


def test_lab_copies_the_lessons_then_starts_jupyterlab_as_this_python(tmp_path, monkeypatch):
    pytest.importorskip("jupyterlab")
    calls, envs = [], []
    monkeypatch.setattr(os, "execve", lambda path, cmd, env: (calls.append(cmd), envs.append(env)))
    monkeypatch.setenv("JUPYTER_CONFIG_PATH", str(tmp_path / "mine"))
    assert main(["lab", str(tmp_path / "course"), "--no-browser", "--port", "8899"]) == 0
    (cmd,), (env,) = calls, envs
    # the news prompt off: gpsaccel's config directory first, the student's own kept after it
    assert env["JUPYTER_CONFIG_PATH"].split(os.pathsep) == [str(lessons.lab.LAB_CONFIG),
                                                          str(tmp_path / "mine")]
    assert cmd[:3] == [sys.executable, "-m", "jupyterlab"]
    assert f"--notebook-dir={tmp_path / 'course'}" in cmd and "--port=8899" in cmd
    assert ("--allow-root" in cmd) == (os.geteuid() == 0)
    assert (tmp_path / "course" / "01-truth-and-sensors.ipynb").is_file()


def test_the_lab_gpsaccel_starts_does_not_ask_about_jupyter_news(tmp_path, monkeypatch):
    """JupyterLab asks "Would you like to get notified about official Jupyter news?" while its
    notification setting fetchNews is "none": the environment ``gpsaccel lab`` starts it in makes
    jupyterlab_server's default for it "false" (read as the settings API reads it), and nothing
    else; without that environment the default is untouched."""
    pytest.importorskip("jupyterlab")
    from jupyterlab_server.settings_utils import _get_overrides

    monkeypatch.setenv("JUPYTER_CONFIG_DIR", str(tmp_path / "user"))  # no user's own labconfig
    monkeypatch.delenv("JUPYTER_CONFIG_PATH", raising=False)
    before, error = _get_overrides(str(tmp_path / "app-settings"))
    assert error == "" and "@jupyterlab/apputils-extension:notification" not in before
    monkeypatch.setenv("JUPYTER_CONFIG_PATH", lessons.lab.lab_environment()["JUPYTER_CONFIG_PATH"])
    after, error = _get_overrides(str(tmp_path / "app-settings"))
    assert error == "" and after == {**before, "@jupyterlab/apputils-extension:notification":
                                     {"fetchNews": "false"}}


def test_a_missing_extra_is_named(monkeypatch, tmp_path, capsys):
    def absent(*args, **kwargs):
        raise ModuleNotFoundError("gpsaccel lab needs JupyterLab", name="jupyterlab")

    monkeypatch.setattr(lessons.lab, "lab_command", absent)  # what the command calls
    assert main(["lab", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "jupyterlab is not installed" in err and "gpsaccel[lab]" in err


# ----------------------------------------------------------------------------- the built wheel

def _uv() -> str | None:
    return shutil.which("uv")


#: The extra the wheel is installed with for a student's steps: none, so the steps below show that
#: the core alone does them (the instructor's steps, HOMEWORK_STEPS, have "[grading]").
WHEEL_EXTRA = ""

#: What a user does from the installed wheel, in a folder outside the repository: (name, argv,
#: what the output must hold).
WHEEL_STEPS: list[tuple[str, list[str], str]] = [
    ("version", ["--version"], f"gpsaccel {gpsaccel.__version__}"),
    ("copy the lessons", ["lessons", "--copy", "course"], "notebooks into course"),
    ("check a homework file", ["check", str(ROOT / "tests/submissions/correct_joseph.py"),
                               "--runs", "2", "--sandbox", "basic"], "1 submission, problem calibration"),
    # the example of a homework of one's own, from the core install (no otter needed for it)
    ("write the example homework", ["assignment", "--example", "own"], "graded.py"),
]


#: The instructor's steps, after ``[grading]`` is added to the same environment: nothing but the
#: installed package (its masters and graded questions), a roster of 8, the secret, and a class of
#: two in LMS layout (folders named with a space; the second copied the first's notebook).
HOMEWORK_STEPS: list[tuple[str, list[str], str]] = [
    ("hand out a homework", ["assignment", "calibration", "--out", "dist/calibration",
                             "--no-run-tests", "--roster", "roster.csv", "--secret-file",
                             "secret.txt"], "(8 students)"),
    ("grade a class", ["grade", "--assignment", "calibration", "class", "--secret-file",
                       "secret.txt", "--roster", "roster.csv"], "10 / 10  graded"),
]

ROSTER = "id,name,email,sis_id\n" + "".join(
    f"{who},{who},{who.split()[0].lower()}@example.edu,10{i:02d}\n" for i, who in enumerate(
        ["Alice Smith", "Bob Jones", "Carol King", "Dan Wu", "Eve Ode", "Fay Lin", "Gus Roe",
         "Hal Poe"]))

def _solved_notebook(name: str, target: Path) -> None:
    """An honest student's notebook of homework ``name`` (the homework tests' own maker)."""
    import nbformat

    module = _module(ROOT / "tests" / "assignments" / "conftest.py")
    target.parent.mkdir(parents=True)
    nbformat.write(module.solved(name), str(target))


def _share_bytecode(venv: Path) -> None:
    """Give the new venv the bytecode this venv compiled for each module file the two share: the
    same file (one inode: uv links both venvs' files from its cache), so the same bytecode, which
    Python checks against the file as ever; gpsaccel itself, from the wheel, is not shared.  pip
    compiles at install, uv does not: the steps below compiled numpy, scipy, otter and their kin
    from source on first import (about 6 of the test's 25 CPU s).  Where nothing is shared (pip,
    another file system) the steps compile as before."""
    import sysconfig

    here = Path(sysconfig.get_paths()["purelib"])
    (there,) = (venv / "lib").glob("python3*/site-packages")
    name = f"{{}}.{sys.implementation.cache_tag}.pyc"
    for src in there.rglob("*.py"):
        mine = here / src.relative_to(there)
        pyc = mine.parent / "__pycache__" / name.format(src.stem)
        target = src.parent / "__pycache__" / pyc.name
        try:
            if target.exists() or not (pyc.is_file() and os.path.samefile(src, mine)):
                continue
            target.parent.mkdir(exist_ok=True)
            try:
                os.link(pyc, target)  # Python replaces a stale .pyc, never writes into it
            except OSError:
                shutil.copy2(pyc, target)
        except OSError:  # not in this venv, or not writable: compiled on import
            continue


needs_uv = pytest.mark.skipif(_uv() is None, reason="needs uv to build and install quickly")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel, built from the sdist as uv builds it (once for this module's two tests)."""
    dist = tmp_path_factory.mktemp("dist")
    subprocess.run([_uv(), "build", "-q", "-o", str(dist), str(ROOT)], check=True, timeout=600)
    (built,) = dist.glob("gpsaccel-*.whl")
    return built


def _fresh_venv(where: Path, requirement: str) -> tuple[Path, dict[str, str]]:
    """A new venv at ``where`` with ``requirement`` installed (the wheel, perhaps with an extra),
    and a user's environment to run it in: not this checkout's PYTHONPATH or venv; and bytecode
    is written (pip compiles it at install, uv does not): under a developer's
    PYTHONDONTWRITEBYTECODE every process of the steps, the sandbox's boxes included, compiled
    numpy and scipy again."""
    subprocess.run([_uv(), "venv", "-q", "-p", sys.executable, str(where)], check=True,
                   timeout=600)
    subprocess.run([_uv(), "pip", "install", "-q", "--python", str(where / "bin" / "python"),
                    requirement], check=True, timeout=600)
    _share_bytecode(where)
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONDONTWRITEBYTECODE",
                        "GPSACCEL_ASSIGNMENTS")}
    env["MPLBACKEND"] = "Agg"
    return where, env


@needs_uv
def test_the_wheel_in_a_fresh_environment_outside_the_repository(wheel, tmp_path):
    """The wheel with the core dependencies only, in a new venv under /tmp, used from there: a
    student's steps, the lessons and the homework's student side shipped, the instructor's kit
    in it (the quick run's one wheel test; the instructor's steps with the grading extra are
    the slow one below)."""
    venv, env = _fresh_venv(tmp_path / "venv", f"{wheel}{WHEEL_EXTRA}")
    work = tmp_path / "student"
    work.mkdir()
    where = subprocess.run([str(venv / "bin" / "python"), "-c",
                            "import gpsaccel, gpsaccel.lessons as l; print(gpsaccel.__file__); "
                            "print(l.lessons_dir())"], cwd=work, env=env, capture_output=True,
                           text=True, check=True).stdout.split()
    assert all(Path(p).is_relative_to(venv) for p in where), where  # not the checkout
    for name, argv, expected in WHEEL_STEPS:
        proc = subprocess.run([str(venv / "bin" / "gpsaccel"), *argv], cwd=work, env=env,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0 and expected in proc.stdout, (name, proc.stdout, proc.stderr)
    shipped = sorted(p.relative_to(work / "course").as_posix()
                     for p in (work / "course").rglob("*.ipynb"))
    repo = sorted(p.relative_to(ROOT / "lessons").as_posix()
                  for p in [*(ROOT / "lessons").glob("*.ipynb"),
                            *(ROOT / "lessons").glob("solutions/*.ipynb")])
    assert shipped == repo and not any(p.startswith("masters/") for p in shipped)
    # the student side of the homework is in the wheel, the masters and graded questions are not
    files = subprocess.run([str(venv / "bin" / "python"), "-c",
                            "import importlib.resources as r; root = r.files('gpsaccel'); "
                            "print(*(p.name for p in root.joinpath('assignments', 'student')"
                            ".iterdir()))"], cwd=work, env=env, capture_output=True, text=True,
                           check=True).stdout.split()
    # the package's own homework (an instructor's folder registered by another test in this
    # process, tests/homework/'s cv2d example, is not in the package)
    packaged = sorted(n for n in registry.assignments()
                      if registry.assignment(n).module.startswith("gpsaccel.assignments."))
    assert sorted(files) == packaged
    installed = Path(where[0]).parent
    # the instructor's kit is in the wheel: every homework's master and graded questions
    for name in packaged:
        assert (installed / "assignments" / "masters" / name / "graded.py").is_file(), name


@pytest.mark.slow
@needs_uv
def test_an_instructor_hands_out_and_grades_from_the_wheel_with_the_grading_extra(wheel,
                                                                                   tmp_path):
    """The grading extra, nothing else (no checkout, no $GPSACCEL_ASSIGNMENTS), in a new venv:
    :data:`HOMEWORK_STEPS` from the installed package alone."""
    venv, env = _fresh_venv(tmp_path / "venv", f"{wheel}[grading]")
    instructor = tmp_path / "instructor"
    instructor.mkdir()
    (instructor / "roster.csv").write_text(ROSTER, encoding="utf-8")
    (instructor / "secret.txt").write_text("k" * 64, encoding="utf-8")
    for who in ("Alice Smith", "Bob Jones"):  # Bob handed in Alice's notebook
        _solved_notebook("calibration", instructor / "class" / who / "calibration.ipynb")
    out = {}
    for name, argv, expected in HOMEWORK_STEPS:
        proc = subprocess.run([str(venv / "bin" / "gpsaccel"), *argv], cwd=instructor, env=env,
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0 and expected in proc.stdout, (name, proc.stdout, proc.stderr)
        out[name] = proc.stdout
    dist = instructor / "dist" / "calibration"
    mine = sorted((dist / "students").glob("*/calibration.ipynb"))
    assert len(mine) == 8 and (dist / "calibration-autograder.zip").is_file()
    import zipfile  # the Gradescope zip carries a wheel rebuilt from the installed package

    with zipfile.ZipFile(dist / "calibration-gradescope.zip") as z:
        (carried,) = [n for n in z.namelist() if n.endswith(".whl")]
        with zipfile.ZipFile(z.open(carried)) as w:
            names = set(w.namelist())
    assert "gpsaccel/assignments/masters/calibration/graded.py" in names
    assert not any("_lessons/masters" in n for n in names)
    variants = {next(line for line in p.read_text().splitlines() if "VARIANT =" in line)
                .split("#")[0] for p in mine}
    assert len(variants) == 8 and not any("'rate_hz': 200}" in v for v in variants), variants
    grades = instructor / "class-grades"
    assert (grades / "grades.csv").read_text().splitlines()[-1].startswith("Bob Jones,")
    for f in ("canvas.csv", "moodle.csv", "gradescope-roster.csv", "gradescope-scores.csv",
              "similarity.html", "grades.json"):
        assert (grades / f).is_file(), f
    assert "Alice Smith,,1000,,,10" in (grades / "canvas.csv").read_text()
    # the copy is flagged, and both hand in the published solution, which the wheel carries
    assert "q2: group of 2: Alice Smith, Bob Jones" in out["grade a class"]
    assert "Bob Jones matches the published solution of calibration q2" in out["grade a class"]
    # the example the core install writes out (the student's steps above show it does)
    proc = subprocess.run([str(venv / "bin" / "gpsaccel"), "assignment", "--example", "own"],
                          cwd=instructor, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0 and "graded.py" in proc.stdout, proc.stderr
    _own_homework(venv, env, instructor / "own" / "cv2d", instructor)


def _own_homework(venv: Path, env: dict, course: Path, instructor: Path) -> None:
    """An instructor's own homework from the example the wheel ships (written out by the
    command), nothing else: handed out, and a class of two graded, one with V given as σ: that
    costs half of V's part (the example's credit), not the whole question."""
    import nbformat

    gpsaccel_bin = str(venv / "bin" / "gpsaccel")
    proc = subprocess.run([gpsaccel_bin, "assignment", str(course), "--out", "dist/cv2d",
                           "--no-run-tests"], cwd=instructor, env=env, capture_output=True,
                          text=True, timeout=400)
    assert proc.returncode == 0 and "cv2d-gradescope.zip" in proc.stdout, proc.stderr
    solution = nbformat.read(str(instructor / "dist/cv2d/autograder/cv2d.ipynb"), as_version=4)
    for who, edit in (("Ann", None), ("Ben", ('V = VARIANT["sigma_p"] ** 2 * I2',
                                              'V = VARIANT["sigma_p"] * I2'))):
        nb = nbformat.from_dict(solution)
        if edit:
            (cell,) = [c for c in nb.cells if c.cell_type == "code" and edit[0] in c.source]
            cell.source = cell.source.replace(*edit)
        (instructor / "own-class" / who).mkdir(parents=True)
        nbformat.write(nb, str(instructor / "own-class" / who / "cv2d.ipynb"))
    proc = subprocess.run([gpsaccel_bin, "grade", "own-class", "--assignment", str(course),
                           "--no-similarity"], cwd=instructor, env=env, capture_output=True,
                          text=True, timeout=400)
    assert proc.returncode == 0, proc.stderr
    scores = {line.split()[0]: line.split()[1] for line in proc.stdout.splitlines()
              if line.split()[:1] in (["Ann"], ["Ben"])}
    assert scores == {"Ann": "10", "Ben": "9.75"}, proc.stdout
