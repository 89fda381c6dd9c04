"""A student's files, found and checked before any of it reaches a box: a ``.py`` file or a
folder, walked without following links and within limits (:func:`load_submission`), then opened
again, checked, when copied into the box (:func:`_open_checked`)."""

from __future__ import annotations

import ast
import os
import shutil
import stat
from dataclasses import dataclass
from pathlib import Path

from gpsaccel import _untrusted
from gpsaccel._untrusted import shown as _shown  # the one printable name

#: Largest submission copied into a box: files and bytes (a folder of data files may be large).
MAX_FILES = 200
MAX_BYTES = 32 << 20
#: Entries (files and folders, hidden ones too) a submission's folder may hold, and its depth:
#: the same walk and limits as the grader's (:mod:`gpsaccel._untrusted`).
MAX_ENTRIES = _untrusted.MAX_ENTRIES
MAX_DEPTH = _untrusted.MAX_DEPTH


@dataclass(frozen=True)
class Submission:
    """A student's files: ``root`` (a folder), the ``entry`` file defining the function, and
    ``files`` (paths relative to ``root``) copied into the box."""

    root: Path
    entry: str
    files: tuple[str, ...]


class SubmissionError(ValueError):
    """What is handed in is not a submission; ``code`` is the finding to report."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


def defines(path: str | os.PathLike, function: str) -> bool:
    """Whether the file defines ``function`` at top level (read with ast, never executed)."""
    try:
        tree = ast.parse(Path(path).read_bytes(), filename=str(path))
    except (SyntaxError, ValueError, OSError):
        return False
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == function:
            return True
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == function
                                                for t in node.targets):
            return True
        if isinstance(node, (ast.Import, ast.ImportFrom)) and any(
                (a.asname or a.name) == function for a in node.names):
            return True
    return False


def load_submission(path: str | os.PathLike, function: str) -> Submission:
    """The submission at ``path``: a ``.py`` file alone, or a folder (one student's) holding
    one ``.py`` file that defines ``function`` plus its helper modules and data files.

    Hidden entries and ``__pycache__`` are left out.  Refused with a finding, never followed:
    a symbolic link (the submission itself, or anything in its folder: ``mallory.py ->
    alice.py`` would pass as a copy, a link to the instructor's folder would hand its files to
    the box) and a hard link (a regular file with more than one name: it may be a file of
    someone else's, the instructor's 0600 solution, that the checker would copy readable into
    the box; whoever owns it, a submission unpacked from an archive or a repository never holds
    one).  A folder deeper than :data:`MAX_DEPTH` or with more than :data:`MAX_ENTRIES` entries
    is refused before it is walked further.  Raises :class:`SubmissionError` (``not-found``,
    ``link-refused``, ``no-function``, ``ambiguous-entry``, ``file-limit``) with a message for
    the student.
    """
    path = Path(path)
    if os.path.islink(path):
        raise SubmissionError("link-refused", f"{_shown(path.name)} is a symbolic link (to "
                              f"{_shown(os.readlink(path))}); hand in your own file, not a "
                              f"link to one.")
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        raise SubmissionError("not-found", f"{_shown(str(path))} is neither a file nor a "
                              f"folder.") from None
    if stat.S_ISREG(st.st_mode):
        if path.suffix != ".py":
            raise SubmissionError("not-found", f"{_shown(path.name)} is not a Python file "
                                  f"(.py).")
        _check_file(path, st, path.name)
        return Submission(path.resolve().parent, path.name, (path.name,))
    if not stat.S_ISDIR(st.st_mode):
        raise SubmissionError("not-found", f"{_shown(str(path))} is neither a file nor a "
                              f"folder.")
    root = path.resolve()
    files = _walk(root, path.name)
    py = [f for f in files if f.endswith(".py") and "/" not in f]
    entries = [f for f in py if defines(root / f, function)]
    if not entries:
        raise SubmissionError("no-function", f"No Python file at the top of the folder "
                              f"{_shown(path.name)} defines {function}(...) (files: "
                              f"{_shown(', '.join(py)) or 'none'}). Define it in one of them.")
    if len(entries) > 1:
        raise SubmissionError("ambiguous-entry", f"Several files of the folder "
                              f"{_shown(path.name)} define {function}: "
                              f"{_shown(', '.join(entries))}. Keep it in one file and import "
                              f"it from there.")
    return Submission(root, entries[0], tuple(files))


def _check_file(full: Path, st: os.stat_result, rel: str) -> None:
    """A regular file may be copied into the box: one name only, within the size limit."""
    if st.st_nlink > 1:
        raise SubmissionError("link-refused", f"{_shown(rel)} is a hard link ({st.st_nlink} "
                              f"names for one file); hand in a copy of your own file.")
    if st.st_size > MAX_BYTES:
        raise SubmissionError("file-limit", f"{_shown(rel)} is larger than "
                              f"{MAX_BYTES >> 20} MB.")


def _walk(root: Path, name: str) -> list[str]:
    """The files of a student's folder (relative paths), breadth first, without following
    anything (:func:`gpsaccel._untrusted.walk`); :class:`SubmissionError` at a link, below
    :data:`MAX_DEPTH` or beyond the limits of entries, files and bytes."""
    files: list[str] = []
    size = 0
    too_many = SubmissionError("file-limit", f"The folder {_shown(name)} holds more than "
                               f"{MAX_FILES} files, {MAX_ENTRIES} entries or "
                               f"{MAX_BYTES >> 20} MB: hand in your code and the data it reads, "
                               f"nothing else.")
    try:
        for rel, e in _untrusted.walk(root, skip=lambda n: n.startswith(".") or n == "__pycache__"):
            if e.is_symlink():
                raise SubmissionError("link-refused", f"{_shown(name)}/{_shown(rel)} is a "
                                      f"symbolic link; a submission holds its own files, not "
                                      f"links. Replace it with a copy.")
            st = e.stat(follow_symlinks=False)
            if stat.S_ISREG(st.st_mode):
                _check_file(Path(e.path), st, f"{name}/{rel}")
                files.append(rel)
                size += st.st_size
                if len(files) > MAX_FILES or size > MAX_BYTES:
                    raise too_many
    except _untrusted.WalkLimit as exc:
        if exc.kind == "entries":
            raise too_many from None
        raise SubmissionError("file-limit", f"The folder {_shown(name)} is nested more than "
                              f"{MAX_DEPTH} levels deep ({_shown(exc.where, 80)}); keep your "
                              f"code in a few folders.") from None
    except OSError as exc:
        raise SubmissionError("not-found", f"The folder {_shown(name)} cannot be read "
                              f"({exc.strerror}).") from None
    return files


def _open_checked(sub: Submission, rel: str) -> int:
    """A file of the submission, opened for the box: still a regular file with one name, not
    reached through a link (it may have changed since :func:`load_submission` looked)."""
    path = sub.root / rel
    if os.path.realpath(path) != str(path):
        raise SubmissionError("link-refused", f"{_shown(rel)} is reached through a link.")
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode) or st.st_nlink > 1:
        os.close(fd)
        raise SubmissionError("link-refused", f"{_shown(rel)} is not a regular file of its own "
                              f"(a hard link, or replaced since it was read).")
    return fd


def _copy_submission(sub: Submission, box: Path, uid: int | None = None) -> None:
    for rel in sub.files:
        dest = box / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        fd = _open_checked(sub, rel)
        with open(fd, "rb") as src, open(dest, "wb") as out:
            shutil.copyfileobj(src, out)
    if uid is not None:  # the box's user owns its working folder, nothing else
        for d, dirs, files in os.walk(box):
            for name in (d, *(os.path.join(d, f) for f in dirs + files)):
                os.chown(name, uid, uid, follow_symlinks=False)
