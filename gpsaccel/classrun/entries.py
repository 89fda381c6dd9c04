r"""One walk of a class into entries: who each submission is, a printable unique id, its path, or
why there is none.

A class is a folder (``gpsaccel grade``), or files and folders named on the command line
(``gpsaccel check``).  Each top-level entry of a folder is one student's submission, of a
:class:`Kind`: a ``.py`` file or a folder (:data:`PYTHON`, one student's, checked as a whole), or a
notebook or a folder holding one (:func:`notebooks`).  What is not a submission is noted, never
skipped silently.

Who an entry is comes from its name, through a :data:`Naming` (default :func:`plain`: a file's
stem, a folder's name).  That is the one place an LMS export is read as it was downloaded: a
naming parses ``nguyenan_84500_678900_calibration.ipynb`` (Canvas: user id, ``_LATE_``,
``-1``) or ``An Nguyen_84500_assignsubmission_file_`` (Moodle), looks the ids up in the roster and
answers a :class:`Name`: the roster's student, late or not, which attempt, or why it names no one
(a status, never a guess).  Of one student's entries the highest attempt is kept and the others
are noted as superseded; two of one attempt are a collision.

Every name is the student's to choose (any bytes, any length, any punctuation): it is kept as
found (:func:`os.fsdecode`) and given once a unique printable id
(:func:`gpsaccel._untrusted.student_id`) that names the student's files.  Entries whose ids or
shown names differ only in case are told apart by a hash of their raw names; where the kind's
ids name a student's files and key their variant (grading), both are refused
(``id-collision``), since neither can be told to be the one the roster means, unless the roster
names one of them exactly (its student is a roster id as it is, the others' are not): that one
is the roster's student and kept, the others refused.  Folders are walked
without recursion and without following links (:func:`gpsaccel._untrusted.walk`), so no name or
folder stops the class.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection, Iterable, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

from gpsaccel import _untrusted


@dataclass(frozen=True)
class Name:
    """Who an entry is, as its name says (what a :data:`Naming` answers).

    student : the student as the export names them, the key of their variant, data and roster
        row (the found name itself for a plain folder; the roster's id once an export is mapped);
    late : handed in after the deadline (an export's ``_LATE_``);
    attempt : which resubmission (Canvas' ``-1``, ``-2``); a student's highest attempt is graded;
    problem : ``(status, message)`` when the name maps to no student, or to several: the entry is
        reported with that status (under its name as found) and never run (nothing is graded on a
        guessed variant);
    skip : why the entry is no one's submission at all (an LMS's other files: Moodle's online
        text folder): it is noted and left out;
    label : the export's own number for the submission where its name carries one beside the
        student's name (``participant 1001``: Moodle's), which tells apart two submissions
        that show one name (a display name copied from a classmate's).
    """

    student: str
    late: bool = False
    attempt: int = 0
    problem: tuple[str, str] | None = None
    skip: str = ""
    label: str = ""


#: ``naming(found, is_file) -> Name``: who the top-level entry named ``found`` is.
Naming = Callable[[str, bool], Name]

#: ``layout(folder, names) -> Naming``: who the entries of one folder are, decided once from the
#: folder and every top-level name it holds that may be a submission (which LMS exported it:
#: :func:`gpsaccel.classrun.exports.layout`).
Layout = Callable[[Path, Sequence[str]], Naming]


@dataclass(frozen=True)
class Entry:
    """One submission of a class.

    student : who (:attr:`Name.student`): the name as found (:func:`os.fsdecode` of its bytes),
        or the roster's id when a naming mapped it; it keys the variant and the data;
    path : what the item runs on (a ``.py`` file or folder to check, a notebook to grade), as
        found under the path given; None: why not in ``problem`` (``(status, message)``);
    id : unique, printable and file-safe (:func:`gpsaccel._untrusted.student_id`): it names
        the student's files (feedback);
    found : the top-level name as found; late, attempt, label : as the naming read them.
    """

    student: str
    path: Path | None
    problem: tuple[str, str] | None = None
    id: str = ""
    found: str = ""
    late: bool = False
    attempt: int = 0
    label: str = ""

    @property
    def shown(self) -> str:
        return _untrusted.shown(self.student)


@dataclass(frozen=True)
class Kind:
    """What a submission is (module docstring).

    what : what the notes say one is; suffix : a submission file's extension (any case);
    ignored : ``name -> why`` a top-level name is not a submission ("" when it may be one);
    links : a symbolic link is an entry (the item refuses it, in the student's own report) rather
        than a note; inside : ``folder -> (path, problem)``, the submission a student's folder
        holds or why there is none (None: the folder itself is the submission);
        refuse_collisions : entries whose ids differ only in case are refused (their ids name
        files and key variants).
    """

    what: str
    suffix: str
    ignored: Callable[[str], str] = field(repr=False)
    links: bool = False
    inside: Callable[[Path], tuple[Path | None, tuple[str, str] | None]] | None = \
        field(default=None, repr=False)
    refuse_collisions: bool = False


def _hidden(name: str) -> str:
    return "hidden" if _untrusted.hidden(name) else ""


def _python_ignored(name: str) -> str:
    if name == "__pycache__":
        return "Python's cache"
    return _hidden(name) or ("a package's __init__.py" if name == "__init__.py" else "")


#: ``gpsaccel check``: a ``.py`` file or a folder (one student's: the file that defines the
#: contract's functions and its helpers and data; :func:`gpsaccel.sandbox.load_submission`).  A
#: link stays (its check refuses it: ``link-refused``; ``mallory.py -> alice.py`` is not a
#: second passing submission); a helper inside a student's folder is part of it.
PYTHON = Kind("a .py file or a folder", ".py", _python_ignored, links=True)


def notebooks(name: str) -> Kind:
    """``gpsaccel grade`` of homework ``name``: a notebook, or a folder holding one
    (:func:`gpsaccel.assignments.grading.notebook_in`: within the checker's depth and entry
    limits, ``NAME.ipynb`` among several)."""
    from gpsaccel.assignments.grading import notebook_in  # the grader's, when grading

    return Kind("a notebook or a student's folder", ".ipynb", _hidden,
                inside=partial(notebook_in, name=name), refuse_collisions=True)


def plain(kind: Kind) -> Naming:
    """The naming of a class laid out by hand, one file or folder per student: a file's name
    without its extension, a folder's name."""
    def naming(found: str, is_file: bool) -> Name:
        if is_file and found.lower().endswith(kind.suffix):
            return Name(found[:-len(kind.suffix)])
        return Name(found)
    return naming


# ------------------------------------------------------------------------------ the walk
def walk(paths: str | os.PathLike | Sequence[str | os.PathLike], kind: Kind,
         naming: Naming | None = None, known: Collection[str] = (),
         layout: Layout | None = None
         ) -> tuple[list[Entry], list[str]]:
    """Every entry of a class (module docstring) and notes on what is not one.

    ``paths``: one folder, whose top-level entries are the students (the notes name them as
    found in it); or a list of files and folders (the command line's: a file is one entry, a
    missing one too, for its item to report; a folder holds one per top-level entry; the notes
    name them by their paths).  Entries come in the order given, each folder's by name without
    case.  ``naming`` (default :func:`plain`) says who each one is; a ``layout`` (an LMS
    export's) is asked for the naming of each folder, with the names found in it.  ``known``:
    the roster's ids; of entries that collide, the one whose student is one of them exactly (the
    folder's name as found, byte for byte, or the naming's id), when no other of them is, is that
    student and kept; the others stay refused."""
    fixed = naming or plain(kind)
    layout = layout or (lambda _folder, _names: fixed)
    if isinstance(paths, (str, os.PathLike)):
        roots, one_folder = [Path(paths)], True
    else:
        roots, one_folder = [Path(p) for p in paths], False
    found: list[Entry] = []
    notes: list[str] = []
    for root in roots:
        if not one_folder and not root.is_dir():
            one = _named(layout(root.parent, [root.name]), Entry("", root, found=root.name),
                         True, notes, str(root.parent))
            found += [one] if one is not None else []
            continue
        n = len(found)
        found += _folder(root, kind, layout, notes, "" if one_folder else str(root))
        if len(found) == n and not one_folder:
            notes.append(f"{_untrusted.shown(str(root))}: no submission in it ({kind.what} "
                         f"each)")
    unique = list({(e.path, e.problem, e.found): e for e in found}.values())
    return _with_ids(_latest(unique, notes), kind, notes, frozenset(known)), notes


def _folder(root: Path, kind: Kind, layout: Layout, notes: list[str], where: str
            ) -> list[Entry]:
    """The entries at the top of ``root``; ``where`` prefixes the names in notes."""
    with os.scandir(root) as it:
        listing = sorted(it, key=lambda e: (os.fsencode(e.name).lower(), os.fsencode(e.name)))
    candidates = []
    for e in listing:
        why = kind.ignored(e.name) or _not_a_submission(e, kind)
        if why:
            notes.append(f"{_untrusted.shown(os.path.join(where, e.name))}: skipped ({why})")
        else:
            candidates.append(e)
    naming = layout(root, [e.name for e in candidates])
    out: list[Entry] = []
    for e in candidates:
        is_file = not e.is_dir(follow_symlinks=False)
        entry = Entry("", Path(e.path), found=e.name)
        if not is_file and kind.inside is not None:
            path, problem = kind.inside(Path(e.path))
            entry = replace(entry, path=path, problem=problem)
        named = _named(naming, entry, is_file, notes, where)
        if named is not None:
            out.append(named)
    return out


def _not_a_submission(e: os.DirEntry, kind: Kind) -> str:
    if e.is_symlink():
        return "" if kind.links else "a symbolic link"
    if e.is_dir(follow_symlinks=False):
        return ""
    if not e.is_file(follow_symlinks=False):
        return "not a file or folder"
    return "" if e.name.lower().endswith(kind.suffix) else f"not {kind.what}"


def _named(naming: Naming, entry: Entry, is_file: bool, notes: list[str], where: str = ""
           ) -> Entry | None:
    name = naming(entry.found, is_file)
    if name.skip:
        notes.append(f"{_untrusted.shown(os.path.join(where, entry.found))}: skipped "
                     f"({name.skip})")
        return None
    problem = name.problem or entry.problem
    return replace(entry, student=name.student or entry.found, late=name.late,
                   attempt=name.attempt, problem=problem, path=None if problem else entry.path,
                   label=name.label)


# ------------------------------------------------------------------- who is who, and their ids
def _key(student: str) -> str:
    return _untrusted.student_id(student).casefold()


class Superseded(str):
    """The note of an attempt a later one of its student replaced (:func:`_latest`): a note of
    its own type, so the run prints these (the instructor may expect the earlier file graded)
    and no file name that reads like one is taken for one."""


def _latest(entries: list[Entry], notes: list[str]) -> list[Entry]:
    """Of one student's entries (by id, without case) the highest attempt; the earlier ones are
    noted as superseded.  A naming that reads no attempts changes nothing here."""
    best: dict[str, int] = {}
    for e in entries:
        if e.problem is None:
            best[_key(e.student)] = max(best.get(_key(e.student), e.attempt), e.attempt)
    kept = []
    for e in entries:
        if e.problem is None and e.attempt < best[_key(e.student)]:
            notes.append(Superseded(f"{_untrusted.shown(e.found)}: superseded by a later "
                                    f"attempt of {e.shown}"))
        else:
            kept.append(e)
    return kept


class Collision(str):
    """The note of submissions that show one name but carry different numbers of the export
    (:attr:`Name.label`: Moodle's participant numbers), with what the instructor can do: a
    note of its own type, so the run prints it."""


#: What the instructor can do about a :class:`Collision` (the numbers are Moodle's alone).
_BY_NUMBER = ("give --roster Moodle's grading worksheet (the assignment's View all submissions "
              "> Download grading worksheet: its Identifier column holds the participant "
              "numbers) and grade again: each is then graded as its own participant")


def _with_ids(entries: list[Entry], kind: Kind, notes: list[str],
              known: frozenset[str] = frozenset()) -> list[Entry]:
    """Each entry with its id (module docstring): the found names tell apart what collides; of
    a collision, the one entry the roster names exactly (``known``) keeps its id."""
    ids = [_untrusted.student_id(x.student) for x in entries]
    clash = _clashes(ids, [x.shown for x in entries])
    named = {i for i in clash if entries[i].student in known
             and not any(entries[j].student in known for j in clash[i])}
    out = []
    for i, x in enumerate(entries):
        if i not in clash or i in named:
            out.append(replace(x, id=ids[i]))
            continue
        sid = _untrusted.hashed_id(x.found)
        if not kind.refuse_collisions:
            out.append(replace(x, id=sid))
            continue
        group = [entries[j] for j in sorted(clash[i])]
        if x.label and all(e.label and e.label != x.label for e in group):
            message = _numbered_collision(x, group, notes)
        else:
            others = ", ".join(repr(_untrusted.shown(e.found)) for e in group)
            notes.append(f"{_untrusted.shown(x.found)}: id-collision with {others}")
            message = (f"Your submission {_untrusted.shown(x.found)!r} cannot be told apart "
                       f"from {others} (the same name or id once case and punctuation are set "
                       f"aside); your instructor must rename one. Nothing was graded.")
        out.append(replace(x, path=None, problem=("id-collision", message), id=sid))
    return _numbered(out)


def _numbered_collision(x: Entry, group: list[Entry], notes: list[str]) -> str:
    """The student's message for submissions that show one name under different numbers of the
    export (each its :attr:`Entry.label`), and once per group the instructor's
    :class:`Collision` note naming the numbers and what to do."""
    def named(e: Entry) -> str:
        return f"{_untrusted.shown(e.found)!r} ({_untrusted.shown(e.label)})"

    members = sorted([x, *group], key=lambda e: e.found)
    if x is members[0]:
        notes.append(Collision(
            f"{' and '.join(named(e) for e in members)} show one name, "
            f"{_untrusted.shown(x.student)!r} (a display name copied from a classmate's, or "
            f"two students of one name), so neither can be graded as that student: "
            f"{_BY_NUMBER}"))
    return (f"Your submission {named(x)} shows the same name as "
            f"{', '.join(named(e) for e in group)}, so it cannot be told which one is "
            f"{_untrusted.shown(x.student)!r}; your instructor can tell them apart by their "
            f"numbers. Nothing was graded.")


def _clashes(ids: list[str], shown: list[str]) -> dict[int, set[int]]:
    clash: dict[int, set[int]] = {}
    for g in _untrusted.collisions(ids) + _untrusted.collisions(shown):
        for i in g:
            clash.setdefault(i, set()).update(j for j in g if j != i)
    return clash


def _numbered(entries: Iterable[Entry]) -> list[Entry]:
    """A forged name equal to another's hashed id (or one raw name given twice): numbered."""
    taken: set[str] = set()
    out = []
    for x in entries:
        sid, n = x.id, 1
        while sid.casefold() in taken:
            n += 1
            sid = f"{x.id}-{n}"
        taken.add(sid.casefold())
        out.append(replace(x, id=sid))
    return out
