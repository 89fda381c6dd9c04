r"""Who each submission of an LMS's export is, as it was downloaded: the ids its names carry,
looked up in the roster's columns (:data:`~gpsaccel.classrun.entries.Layout`).

* **Canvas** (the assignment's *Download Submissions*, unzipped): one file per submitted file,
  ``<name>_[LATE_]<user id>_<submission id>_<file>``; a file handed in again under the same name
  is ``<file>-1``, ``-2``.  The user id is looked up in the roster's ``canvas_id`` (Canvas's
  gradebook export: its ``ID`` column), else in its ids when every one is a number.
* **Moodle** (*View all submissions* > *Download all submissions*, unzipped): a folder per
  student and plugin, ``<Full Name>_<participant>_assignsubmission_file_/`` (the default since
  Moodle 3.1), or flat files ``<Full Name>_<participant>_assignsubmission_file_<file>``.  The
  participant number is looked up in the roster's ``participant`` (Moodle's grading worksheet,
  "Participant 123456"), else the full name in the roster's names (without case; ``_`` is a
  space, as Moodle writes it); another plugin's folder (``_onlinetext_``) is noted and left out.
* **Gradescope** (*Review Grades* > *Export Submissions*, unzipped): ``submission_<n>/`` folders
  and ``submission_metadata.yml``, which names each folder's submitters (``:name:``, ``:sid:``,
  ``:email:``); the email is looked up in the roster's ``email`` (or its ids, where they are
  emails), else the SID in its ``sis_id``.
* **plain**: a folder or notebook per student named by the roster's id (NFC or NFD alike).

Without a roster each entry is who its name says (Canvas's user id, Moodle's full name,
Gradescope's email; a plain name as found).  With one, an entry that names nobody on it is
``not-on-roster``, one that names two students (two roster rows of one full name, a group
submission) ``ambiguous-student``, a name not written as the export writes them
``unrecognised-name``: each is reported under its name as found and never graded, since its
variant would be a guess.  Which export a folder is, is told from its names (every one written
the Canvas or the Moodle way; Gradescope's metadata file) unless given.
"""

from __future__ import annotations

import os
import re
import unicodedata
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

from gpsaccel import _untrusted
from gpsaccel.assignments.roster import Student
from gpsaccel.classrun.entries import Kind, Name, Naming, plain

#: The exports :func:`layout` reads ("auto": told from the folder).
LAYOUTS = ("auto", "plain", "canvas", "moodle", "gradescope")

#: Canvas's flat export: name, ``LATE``, user id, submission id, the file's own name (the first
#: ``_ID_ID_`` after the name: the student's own file name comes after it).
CANVAS = re.compile(r"(?P<login>.*?)_(?:(?P<late>LATE)_)?(?P<uid>\d+)_(?P<sub>\d+)_(?P<file>.+)",
                    re.S)

#: A file handed in again under one name: Canvas numbers it ``-1``, ``-2`` before its extension.
AGAIN = re.compile(r".+-(?P<n>\d{1,4})(?:\.[^.]*)?", re.S)

#: Moodle's download: full name, participant number, plugin, the file's own name (flat).  Moodle
#: writes a name's ``_`` as a space, so the first ``_`` ends it: the student's own file name
#: (``..._file_x_1234567_assignsubmission_file_hw.ipynb``) cannot name another participant.
MOODLE = re.compile(r"(?P<name>[^_]*)_(?P<participant>\d+)_assignsubmission_(?P<plugin>[a-z]+)_"
                    r"(?P<file>.*)", re.S)

#: Gradescope's export: a folder per submission, and the file naming their submitters.
GRADESCOPE = re.compile(r"submission_(?P<n>\d+)")
METADATA = "submission_metadata.yml"

#: Largest ``submission_metadata.yml`` read (bytes).
MAX_METADATA = 64 << 20


def name_key(text: str) -> str:
    """A full name as compared: NFC, without case, ``_`` as a space (Moodle writes them so),
    runs of spaces as one."""
    return " ".join(unicodedata.normalize("NFC", text).replace("_", " ").casefold().split())


class Export:
    """The :data:`~gpsaccel.classrun.entries.Layout` of ``kind``'s submissions exported the way
    ``layout`` says (:data:`LAYOUTS`), mapped through ``roster`` (None: no roster).  ``found``:
    what each folder walked was read as, and by which column (for the record)."""

    def __init__(self, kind: Kind, layout: str = "auto",
                 roster: Sequence[Student] | None = None) -> None:
        if layout not in LAYOUTS:
            raise ValueError(f"export must be one of {', '.join(LAYOUTS)}, got {layout!r}")
        self.kind, self.layout, self.roster = kind, layout, roster
        self.found: list[str] = []

    def __call__(self, folder: Path, names: Sequence[str]) -> Naming:
        layout = self.layout if self.layout != "auto" else detect(folder, names, self.kind)
        naming, how = _NAMINGS[layout](self, folder)
        self.found.append(f"{layout}: {how}")
        return naming

    # --------------------------------------------------------------- one per export
    def _plain(self, _folder: Path) -> tuple[Naming, str]:
        named = plain(self.kind)
        if self.roster is None:
            return named, "each name as found"
        ids = {unicodedata.normalize("NFC", s.id): s.id for s in self.roster}

        def naming(found: str, is_file: bool) -> Name:
            name = named(found, is_file).student
            sid = ids.get(unicodedata.normalize("NFC", name))
            if sid is None:
                return _nobody(found, "its name is no id of the roster")
            return Name(sid)
        return naming, "each name as a roster id"

    def _how(self, ids: str, through: str) -> str:
        """How the export was read, for the terminal: its ``ids`` mapped ``through`` the roster,
        or taken as found where no roster was given."""
        return f"{ids} through {through}" if self.roster is not None else \
            f"{ids} as found (no roster given: each is the student's id)"

    def _canvas(self, _folder: Path) -> tuple[Naming, str]:
        if self.roster is None:
            column, by = None, {}
        elif any(s.canvas_id for s in self.roster):
            column, by = "canvas_id", _index(self.roster, lambda s: [s.canvas_id])
        elif all(s.id.isdigit() for s in self.roster):
            column, by = "id", _index(self.roster, lambda s: [s.id])
        else:
            raise ValueError("roster: Canvas names each submission by the student's Canvas user "
                             "id, which this roster does not have: give Canvas's gradebook "
                             "export (Grades > Export), or a CSV roster with a canvas_id column")

        def naming(found: str, _is_file: bool) -> Name:
            m = CANVAS.fullmatch(found)
            if m is None:
                return _unrecognised(found, "Canvas", "name_[LATE_]USERID_SUBMISSIONID_file")
            again = AGAIN.fullmatch(m["file"])
            late, attempt = bool(m["late"]), int(again["n"]) if again else 0
            if column is None:
                return Name(m["uid"], late=late, attempt=attempt)
            return _looked_up(found, by.get(m["uid"], []), f"Canvas user id {m['uid']}",
                              late, attempt)
        return naming, self._how("Canvas user ids", f"the roster's {column}")

    def _moodle(self, _folder: Path) -> tuple[Naming, str]:
        roster = self.roster
        if roster is not None and any(s.participant for s in roster):
            column, by = "participant", _index(roster, lambda s: [s.participant])
        else:
            column = "full name"
            by = _index(roster or [], lambda s: [name_key(s.full_name)])

        def naming(found: str, is_file: bool) -> Name:
            m = MOODLE.fullmatch(found)
            if m is None:
                return _unrecognised(found, "Moodle", "Full Name_PARTICIPANT_assignsubmission_"
                                                      "file_")
            if m["plugin"] != "file":
                return Name("", skip=f"Moodle's {m['plugin']} submission, not a file")
            if not is_file and m["file"]:
                return _unrecognised(found, "Moodle", "a folder ending in _assignsubmission_"
                                                      "file_")
            label = f"participant {m['participant']}"
            if roster is None:
                return Name(m["name"].replace("_", " "), label=label)
            key = m["participant"] if column == "participant" else name_key(m["name"])
            return replace(_looked_up(found, by.get(key, []), label if column == "participant"
                                      else f"the name {m['name']!r}"), label=label)
        return naming, self._how(f"Moodle's {'full name' if roster is None else column}",
                                 "the roster")

    def _gradescope(self, folder: Path) -> tuple[Naming, str]:
        submitters = read_metadata(folder / METADATA)
        roster = self.roster
        emails = _index(roster or [], lambda s: [x.casefold() for x in (s.email, s.id)
                                                 if "@" in x])
        sids = _index(roster or [], lambda s: [s.sis_id])

        def who(person: dict[str, str]) -> list[Student]:
            email, sid = person.get("email", "").casefold(), person.get("sid", "")
            return emails.get(email, []) if email in emails else sids.get(sid, []) if sid \
                else []

        def naming(found: str, is_file: bool) -> Name:
            if is_file or GRADESCOPE.fullmatch(found) is None:
                return _unrecognised(found, "Gradescope", "submission_NUMBER")
            people = submitters.get(found)
            if not people:
                return Name("", problem=("unrecognised-name", f"{_untrusted.shown(found)}: "
                                         f"{METADATA} names no submitter of it"))
            if roster is None:
                if len(people) > 1:
                    return _two(found, "a group submission")
                return Name(people[0].get("email") or people[0].get("sid") or found)
            matched = list({s.id: s for p in people for s in who(p)}.values())
            if len(people) > 1 and matched:
                return _two(found, "a group submission of " + ", ".join(
                    repr(_untrusted.shown(s.id)) for s in matched))
            return _looked_up(found, matched, "its submitter's email or SID")
        return naming, self._how("Gradescope's submitters (email, else SID)", "the roster")


_NAMINGS: dict[str, Callable[[Export, Path], tuple[Naming, str]]] = {
    "plain": Export._plain, "canvas": Export._canvas, "moodle": Export._moodle,
    "gradescope": Export._gradescope}


def detect(folder: Path, names: Sequence[str], kind: Kind) -> str:
    """Which export ``folder`` is (its top-level ``names`` that may be submissions): Gradescope
    where its metadata file is there, Canvas or Moodle where every name is written their way,
    else plain."""
    try:
        meta = (folder / METADATA).lstat()
    except OSError:
        meta = None
    if meta is not None and not os.path.islink(folder / METADATA):
        return "gradescope"
    if names and all(CANVAS.fullmatch(n) and n.lower().endswith(kind.suffix) for n in names):
        return "canvas"
    if names and all(MOODLE.fullmatch(n) for n in names):
        return "moodle"
    return "plain"


def read_metadata(path: Path) -> dict[str, list[dict[str, str]]]:
    """``submission_<n>`` -> its submitters (``name``, ``sid``, ``email``) from Gradescope's
    ``submission_metadata.yml``; ValueError naming the file when it cannot be read so."""
    import yaml

    if not path.is_file() or path.is_symlink():
        raise ValueError(f"export: {path} is missing: Gradescope's export names each "
                         f"submission's student there (unzip the whole export)")
    if path.stat().st_size > MAX_METADATA:
        raise ValueError(f"export: {path} is larger than {MAX_METADATA >> 20} MB")

    class Loader(yaml.SafeLoader):  # Ruby's tags (!ruby/object:...) read as plain data
        pass

    def untagged(loader, _suffix, node):  # noqa: ANN001, ANN202 - yaml's hook
        if isinstance(node, yaml.MappingNode):
            return loader.construct_mapping(node)
        if isinstance(node, yaml.SequenceNode):
            return loader.construct_sequence(node)
        return loader.construct_scalar(node)

    Loader.add_multi_constructor("!", untagged)
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=Loader)  # noqa: S506
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise ValueError(f"export: {path} is not Gradescope's YAML ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"export: {path} is not Gradescope's submission metadata (a mapping "
                         f"of submission_<n> to its :submitters:)")
    out = {}
    for key, value in data.items():
        people = value.get(":submitters") if isinstance(value, dict) else None
        out[str(key)] = [{k.lstrip(":"): str(v) for k, v in p.items() if v is not None}
                         for p in people or [] if isinstance(p, dict)]
    return out


# ------------------------------------------------------------------------------ statuses
def _index(roster: Sequence[Student], keys: Callable[[Student], list[str]]
           ) -> dict[str, list[Student]]:
    out: dict[str, list[Student]] = {}
    for s in roster:
        for k in dict.fromkeys(keys(s)):
            if k:
                out.setdefault(k, []).append(s)
    return out


def _looked_up(found: str, students: list[Student], what: str, late: bool = False,
               attempt: int = 0) -> Name:
    if not students:
        return _nobody(found, f"{what} is on no row of the roster")
    if len(students) > 1:
        return _two(found, f"{what} is on the roster's rows of " + ", ".join(
            repr(_untrusted.shown(s.id)) for s in students))
    return Name(students[0].id, late=late, attempt=attempt)


def _nobody(found: str, why: str) -> Name:
    return Name("", problem=("not-on-roster", f"Your submission {_untrusted.shown(found)!r} "
                             f"names no student of the class roster ({why}); your instructor "
                             f"must match it by hand. Nothing was graded."))


def _two(found: str, why: str) -> Name:
    return Name("", problem=("ambiguous-student", f"Your submission {_untrusted.shown(found)!r} "
                             f"names more than one student ({why}); your instructor must "
                             f"match it by hand. Nothing was graded."))


def _unrecognised(found: str, lms: str, form: str) -> Name:
    return Name("", problem=("unrecognised-name", f"{_untrusted.shown(found)!r} is not named "
                             f"as {lms} names a submission ({form}); your instructor must "
                             f"match it by hand. Nothing was graded."))
