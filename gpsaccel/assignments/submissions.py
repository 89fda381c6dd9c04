r"""A class's submissions as an LMS exports them: who the students are, and each one's notebook.

A folder per student (its name is the student's; the notebook inside, in any case of ``.ipynb``,
anywhere within the checker's depth and entry limits) or one notebook per student at the top
(its stem is the student's name).  Every entry is a student with a notebook or with the reason
there is none (``no-notebook``, ``ambiguous``, ``file-limit``, ``unreadable``,
``id-collision``); what is not a student is noted, never skipped silently.

Every name is the student's to choose: any bytes (not necessarily UTF-8), any length, any
punctuation.  It is kept as found (:func:`os.fsdecode`: its bytes key the student's variant and
data) and given once a unique printable id (:func:`gpsaccel._untrusted.student_id`) that names
the student's files; a folder is walked without recursion and without following links
(:func:`gpsaccel._untrusted.walk`), so no name or folder stops the class.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from gpsaccel import _untrusted


@dataclass(frozen=True)
class Entry:
    """One student's submission: the name as found (:func:`os.fsdecode` of its bytes: it keys
    the variant and the data), the notebook (None: why not in ``problem``) and the unique,
    printable id (:func:`gpsaccel._untrusted.student_id`) that names the student's files."""

    student: str
    path: Path | None
    problem: tuple[str, str] | None = None  # (status, message)
    id: str = ""

    @property
    def shown(self) -> str:
        return _untrusted.shown(self.student)


def _skipped(name: str) -> bool:
    return name.startswith(".") or name == "__MACOSX"


def _student_folder(e: os.DirEntry, name: str) -> tuple[Path | None, tuple[str, str] | None]:
    """The notebook of a student's folder, walked within the checker's limits, or why not."""
    who = _untrusted.shown(e.name)
    try:
        found = sorted(Path(e.path) / rel for rel, f in _untrusted.walk(e.path, skip=_skipped)
                       if f.name.lower().endswith(".ipynb") and f.is_file(follow_symlinks=False))
    except _untrusted.WalkLimit as exc:
        what = (f"more than {exc.limit} levels deep" if exc.kind == "depth" else
                f"more than {exc.limit} files and folders")
        return None, ("file-limit", f"The folder {who}/ is {what}: hand in the homework's "
                      f"notebook in a folder of a few files. Nothing was graded.")
    except OSError as exc:
        return None, ("unreadable", f"The folder {who}/ cannot be read ({exc.strerror}).")
    if len(found) > 1:
        named = [p for p in found if p.stem.lower() == name.lower()]
        found = named if len(named) == 1 else found
    if not found:
        return None, ("no-notebook", f"No .ipynb file in {who}/: hand in the homework's "
                      f"notebook.")
    if len(found) > 1:
        names = ", ".join(_untrusted.shown(os.path.relpath(p, e.path)) for p in found[:10])
        return None, ("ambiguous", f"Several notebooks in {who}/ ({names}) and none named "
                      f"{name}.ipynb: hand in one.")
    return found[0], None


def find_submissions(folder: Path, name: str) -> tuple[list[Entry], list[str]]:
    """Every student of an LMS export (module docstring) and notes on what is not a student.

    Names may be any bytes; each gets a unique printable id.  Two entries whose ids (or shown
    names) differ only in case are both ``id-collision``, each with an id of its own (neither
    is graded, neither's files overwrite the other's)."""
    entries: list[Entry] = []
    raws: list[str] = []
    notes: list[str] = []
    with os.scandir(folder) as it:
        listing = sorted(it, key=lambda e: os.fsencode(e.name).lower())
    for e in listing:
        shown = _untrusted.shown(e.name)
        if _skipped(e.name):
            notes.append(f"{shown}: skipped (hidden)")
        elif e.is_symlink():
            notes.append(f"{shown}: skipped (a symbolic link)")
        elif e.is_file(follow_symlinks=False):
            if e.name.lower().endswith(".ipynb"):
                entries.append(Entry(e.name[:-len(".ipynb")], Path(e.path)))
                raws.append(e.name)
            else:
                notes.append(f"{shown}: skipped (not a notebook or a student's folder)")
        elif not e.is_dir(follow_symlinks=False):
            notes.append(f"{shown}: skipped (not a file or folder)")
        else:
            path, problem = _student_folder(e, name)
            entries.append(Entry(e.name, path, problem))
            raws.append(e.name)
    return _with_ids(entries, raws, notes), notes


def _with_ids(entries: list[Entry], raws: list[str], notes: list[str]) -> list[Entry]:
    """Each entry with its id; ``raws`` are the top-level names (a notebook's with its
    extension), which tell apart what collides."""
    ids = [_untrusted.student_id(x.student) for x in entries]
    groups = _untrusted.collisions(ids) + _untrusted.collisions([x.shown for x in entries])
    clash: dict[int, set[int]] = {}
    for g in groups:
        for i in g:
            clash.setdefault(i, set()).update(j for j in g if j != i)
    out = []
    for i, x in enumerate(entries):
        if i not in clash:
            out.append(Entry(x.student, x.path, x.problem, ids[i]))
            continue
        others = ", ".join(repr(_untrusted.shown(raws[j])) for j in sorted(clash[i]))
        notes.append(f"{_untrusted.shown(raws[i])}: id-collision with {others}")
        message = (f"Your submission {_untrusted.shown(raws[i])!r} cannot be told apart from "
                   f"{others} (the same name or id once case and punctuation are set aside); "
                   f"your instructor must rename one. Nothing was graded.")
        out.append(Entry(x.student, None, ("id-collision", message),
                         _untrusted.hashed_id(raws[i])))
    taken: set[str] = set()
    for k, x in enumerate(out):  # a forged name equal to another's hashed id: numbered
        sid, n = x.id, 1
        while sid.casefold() in taken:
            n += 1
            sid = f"{x.id}-{n}"
        taken.add(sid.casefold())
        out[k] = Entry(x.student, x.path, x.problem, sid)
    return out
