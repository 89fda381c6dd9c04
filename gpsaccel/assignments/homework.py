"""Where each homework lives: its folder, holding the master ``NAME.ipynb`` and ``graded.py``.

The packaged masters (``gpsaccel/assignments/masters/NAME/``), a folder of masters that replaces
them (``$GPSACCEL_ASSIGNMENTS``), or an instructor's own homework folder (:func:`use_folder`).
Both the generator (:mod:`gpsaccel.assignments.generate`) and the grader
(:mod:`gpsaccel.assignments.grading`, which loads ``graded.py``) find a homework here, so neither
imports the other for it.
"""

from __future__ import annotations

import os
from pathlib import Path

from gpsaccel import registry

#: Environment variable naming a folder of masters that replaces the packaged ones
#: (``NAME/NAME.ipynb`` and ``NAME/graded.py`` for each registered homework): an instructor who
#: edits the course's homework without editing the package.
ASSIGNMENTS_ENV = "GPSACCEL_ASSIGNMENTS"

#: The instructor's own homework folders registered in this process (:func:`use_folder`).
_FOLDERS: dict[str, Path] = {}


def packaged_masters() -> Path:
    """The masters the wheel carries: ``gpsaccel/assignments/masters/NAME/`` (their safety rests
    on fresh data, per-student variants and the sandbox, which hides this folder from a box)."""
    return Path(__file__).resolve().parent / "masters"


def assignments_dir() -> Path:
    """The folder of the registered homeworks' masters: ``$GPSACCEL_ASSIGNMENTS`` when set, else
    the packaged ones (:func:`packaged_masters`)."""
    env = os.environ.get(ASSIGNMENTS_ENV)
    if env:
        return Path(env).expanduser().resolve()
    return packaged_masters()


def homework_dir(name: str) -> Path:
    """The folder holding ``NAME.ipynb`` and ``graded.py`` of homework ``name``: the
    instructor's own folder (:func:`use_folder`), else :func:`assignments_dir`'s."""
    return _FOLDERS[name] if name in _FOLDERS else assignments_dir() / name


def own_folder(name: str) -> Path | None:
    """The instructor's own folder of homework ``name`` (:func:`use_folder`), None for one of the
    package's (whose files the wheel fixes)."""
    return _FOLDERS.get(name)


def use_folder(folder: str | os.PathLike) -> str:
    """Register the instructor's own homework in ``folder`` and return its name (the folder's).

    The folder holds the master notebook ``NAME.ipynb`` (otter's assign format, with a
    ``# your variant`` cell if it has per-student numbers) and ``graded.py``, which defines
    ``graded_questions()`` (:class:`gpsaccel.assignments.questions.Question` s),
    ``DEFAULT_VARIANT`` (the public notebook's numbers) and ``variant(number) -> dict``, and
    may define ``warm()`` (what grading any of its notebooks imports or computes first, done once
    in the class's parent: modules, inputs of its reads, never a reference answer).  It is
    then handed out and graded exactly as a packaged homework (same sandbox, variants, feedback);
    the package is not edited.  ValueError naming what is missing.
    """
    path = Path(folder).expanduser().resolve()
    if not path.is_dir():
        raise ValueError(f"assignment: {folder} is neither a registered homework nor a folder")
    name = path.name
    missing = [f for f in (f"{name}.ipynb", "graded.py") if not (path / f).is_file()]
    if missing:
        raise ValueError(f"assignment: the homework folder {path} lacks {' and '.join(missing)} "
                         f"(a master notebook named after its folder and the file declaring "
                         f"its graded questions)")
    if name in registry.assignments() and name not in _FOLDERS:
        raise ValueError(f"assignment: {name!r} is a homework of the package; name your folder "
                         f"otherwise")
    registry.add_assignment(name, f"gpsaccel_graded_{name}", title=name)
    _FOLDERS[name] = path
    return name


def resolve(name_or_folder: str) -> str:
    """A registered homework's name as given; a folder path registered with :func:`use_folder`."""
    if name_or_folder in registry.assignments():
        return name_or_folder
    if Path(name_or_folder).expanduser().is_dir():
        return use_folder(name_or_folder)
    raise ValueError(f"assignment must be one of {', '.join(registry.assignments())} or a "
                     f"folder holding NAME.ipynb and graded.py, got {name_or_folder!r}")


def copy_homework(name: str, folder: str | os.PathLike) -> Path:
    """Copy packaged homework ``name`` into ``folder``, a new folder the instructor keeps
    private, as a homework of their own: ``FOLDER/FOLDER.ipynb`` (the master, solutions in, its
    otter ``name`` set to the folder's) and ``graded.py`` (and ``requirements.txt``).  The
    packaged solutions are public (every install carries them); a copy is where the instructor
    changes what is asked, then hands it out and grades it like any folder of their own
    (:func:`use_folder`).  Returns the copied master; ValueError naming what is wrong."""
    import re
    import shutil

    registry.assignment(name)  # ValueError naming the homework registered
    src = packaged_masters() / name
    if name in _FOLDERS or not (src / f"{name}.ipynb").is_file():
        raise ValueError(f"--copy: {name!r} is not a homework of the package (a folder of your "
                         f"own is already yours)")
    dest = Path(folder).expanduser().resolve()
    new = dest.name
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_-]*", new):
        raise ValueError(f"--copy: the folder's name becomes the homework's; {new!r} must be "
                         f"letters, digits, '-' and '_', starting with a letter")
    if new in registry.assignments():
        raise ValueError(f"--copy: {new!r} is the name of a homework of the package; name "
                         f"your folder otherwise (e.g. {name}-private)")
    if dest.exists() and (not dest.is_dir() or any(dest.iterdir())):
        raise ValueError(f"--copy: {dest} exists and is not an empty folder")
    dest.mkdir(parents=True, exist_ok=True)
    master = (src / f"{name}.ipynb").read_text(encoding="utf-8")
    head = f'"name: {name}\\n"'
    if head not in master:
        raise ValueError(f"--copy: the master of {name} has no '{head}' line to rename")
    (dest / f"{new}.ipynb").write_text(master.replace(head, f'"name: {new}\\n"', 1),
                                       encoding="utf-8")
    for extra in ("graded.py", "requirements.txt"):
        if (src / extra).is_file():
            shutil.copy2(src / extra, dest / extra)
    return dest / f"{new}.ipynb"
