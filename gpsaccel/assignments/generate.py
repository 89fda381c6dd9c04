"""The homework notebooks: their questions, ``otter assign`` on them, one copy per student.

A master notebook (``gpsaccel/assignments/masters/NAME/NAME.ipynb``, shipped in the wheel; or an
instructor's own folder, :func:`use_folder`) is in otter-grader's
assign format: raw cells ``# BEGIN QUESTION`` (name, points), ``# BEGIN SOLUTION``, ``# BEGIN
TESTS`` ...; solutions and hidden tests live only there.  :func:`generate` runs ``otter assign``
and returns the student notebook (solutions stripped, public tests only) and the autograder zip
(every test), ready to hand out and to grade.  The homeworks are those registered in
:mod:`gpsaccel.registry` (each ``gpsaccel/assignments/NAME.py`` registers its own:
:func:`gpsaccel.registry.assignments`); where each one's folder is:
:mod:`gpsaccel.assignments.homework`.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import yaml

from gpsaccel import _untrusted, registry
from gpsaccel.assignments.homework import (  # noqa: F401 - re-exported: callers find them here too
    _FOLDERS,
    ASSIGNMENTS_ENV,
    assignments_dir,
    homework_dir,
    packaged_masters,
    resolve,
    use_folder,
)


def master_notebook(name: str) -> Path:
    """The master notebook of homework ``name`` (ValueError for an unknown name)."""
    registry.assignment(name)  # ValueError naming the homework registered
    path = homework_dir(name) / f"{name}.ipynb"
    if not path.is_file():
        raise FileNotFoundError(f"master notebook {path} not found"
                                + (f" (${ASSIGNMENTS_ENV} names {assignments_dir()}: it must "
                                   f"hold {name}/{name}.ipynb)" if os.environ.get(ASSIGNMENTS_ENV)
                                   else " (a broken installation of gpsaccel: reinstall it)"))
    return path


def questions(master: Path | str) -> dict[str, float]:
    """Question name -> points of a master notebook, read from its ``# BEGIN QUESTION`` cells.

    A question's ``points`` is a number or one number per test case (their sum).
    """
    import nbformat

    nb = nbformat.read(str(master), as_version=4)
    out: dict[str, float] = {}
    for cell in nb.cells:
        lines = cell.source.strip().splitlines()
        if cell.cell_type != "raw" or not lines or lines[0].strip() != "# BEGIN QUESTION":
            continue
        config = yaml.safe_load("\n".join(lines[1:])) or {}
        points = config.get("points", 1)
        out[str(config["name"])] = float(sum(points) if isinstance(points, list) else points)
    return out


@dataclass(frozen=True)
class Generated:
    """What :func:`generate` wrote: the student notebook, the autograder zip, the solution."""

    student: Path
    autograder: Path
    solution: Path
    out: Path


def generate(name: str, out: Path | str, run_tests: bool = True, timeout: float = 900
             ) -> Generated:
    """``otter assign`` homework ``name`` into ``out`` (created; an earlier output is replaced).

    ``out/student/NAME.ipynb`` is handed out; ``out/NAME-autograder.zip`` grades (``gpsaccel
    grade`` or Gradescope); ``out/autograder/NAME.ipynb`` is the solved notebook.  With
    ``run_tests`` otter executes the solution against every test first (slower; a failing master
    raises RuntimeError with otter's output).
    """
    master = master_notebook(name)
    # absolute: otter assign runs in a temporary folder, where a relative path would land
    out = Path(out).resolve()
    if out.exists():
        if out.is_dir() and not any(out.iterdir()):
            out.rmdir()
        elif (out / "autograder").is_dir() and (out / "student").is_dir():
            shutil.rmtree(out)  # a previous output of this function
        else:
            raise ValueError(f"out: {out} exists and is not an earlier `gpsaccel assignment` "
                             f"output; give a new or empty folder")
    with tempfile.TemporaryDirectory(prefix="gpsaccel-assign-") as tmp:
        # otter assign writes next to the master's copy; keep the checkout clean
        work = Path(tmp) / name
        shutil.copytree(master.parent, work, ignore=shutil.ignore_patterns(
            "*.zip", "dist", "__pycache__", ".ipynb_checkpoints", "kalman_filter.py"))
        cmd = [sys.executable, "-m", "otter", "assign", str(work / master.name), str(out)]
        if not run_tests:
            cmd.insert(4, "--no-run-tests")
        proc = subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"otter assign failed on {master} (exit {proc.returncode}):\n"
                           f"{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}")
    zips = sorted((out / "autograder").glob(f"{name}-autograder_*.zip"))
    if not zips:
        raise RuntimeError(f"otter assign wrote no autograder zip into {out / 'autograder'}")
    autograder = out / f"{name}-autograder.zip"
    shutil.copy(zips[-1], autograder)  # a stable name for the instructor's commands
    return Generated(out / "student" / master.name, autograder, out / "autograder" / master.name,
                     out)


def personalize(name: str, student_notebook: Path | str, students: list[str], secret: bytes,
                out: Path | str, progress=None) -> Path:
    """One copy of the student notebook per student, ``out/<id>/NAME.ipynb``, whose variant cell
    holds that student's numbers (:func:`gpsaccel.assignments.grading.student_variant`): the
    notebook tells each student their own variant.  ``progress``: a tqdm bar advanced once per
    student.  Returns ``out``."""
    import nbformat

    from gpsaccel.assignments.boxcalls import is_variant_cell
    from gpsaccel.assignments.scoring import student_variant

    out = Path(out)
    nb0 = nbformat.read(str(student_notebook), as_version=4)
    marked = [c for c in nb0.cells if c.cell_type == "code" and is_variant_cell(c.source)]
    others = [p for p in Path(student_notebook).parent.iterdir() if p.name != f"{name}.ipynb"]
    if len(students) != len(set(students)):
        raise ValueError("students: the roster lists a student id twice")
    for sid in students:
        v = student_variant(name, sid, secret)
        for c in marked:
            head = [ln for ln in c.source.splitlines() if ln.lstrip().startswith("#")]
            c.source = "\n".join(head + [f"VARIANT = {v!r}  # {sid}"])
        target = out / _untrusted.student_id(sid) / f"{name}.ipynb"
        target.parent.mkdir(parents=True, exist_ok=True)
        for extra in others:  # what otter hands out beside the notebook (data, tests, files)
            copy = shutil.copytree if extra.is_dir() else shutil.copy2
            copy(extra, target.parent / extra.name)
        nbformat.write(nb0, str(target))
        if progress is not None:
            progress.set_postfix_str(sid[:40])
            progress.update()
    return out


def student_package_dir() -> Path:
    """Where the wheel carries each homework's student side: ``gpsaccel/assignments/student/NAME``
    (the notebook without solutions and otter's public tests, for ``grader.check``)."""
    return Path(__file__).resolve().parent / "student"


def refresh_student_package(name: str) -> Path:
    """Regenerate the packaged student side of ``name`` from its master (a source checkout's
    ``otter assign``; run when a master changes — a test compares the two)."""
    with tempfile.TemporaryDirectory(prefix="gpsaccel-student-") as tmp:
        g = generate(name, Path(tmp) / name, run_tests=False)
        target = student_package_dir() / name
        if target.exists():
            shutil.rmtree(target)
        shutil.copytree(g.student.parent, target)
    return target


def copy_student_side(name: str, out: Path | str) -> Path:
    """The packaged student side of ``name`` copied to ``out`` (what a student needs from
    ``pip install gpsaccel``: no master, no solutions, no graded questions)."""
    registry.assignment(name)  # ValueError naming the homework registered
    src = student_package_dir() / name
    out = Path(out).resolve()
    if out.exists() and any(out.iterdir()):
        raise ValueError(f"out: {out} is not empty; give a new or empty folder")
    shutil.copytree(src, out, dirs_exist_ok=True)
    return out / f"{name}.ipynb"
