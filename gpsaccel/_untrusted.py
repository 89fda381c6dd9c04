r"""Names, folders and text a student controls, made safe once for the grader and the checker.

Everything here is a student's: a folder or notebook name (any bytes but ``/`` and NUL; not
necessarily UTF-8; NFC or NFD; punctuation; any length), the depth and width of a folder, the
text of an exception.  This module is the only place that makes such input harmless; each tool
is used wherever the input enters or leaves:

* :func:`student_id` maps a name's raw bytes to a printable id that is a safe file name (a slug
  of the name, plus a short hash of the raw bytes whenever the slug is not the name itself), so
  two different names never get the same file: ``"Doe, Jane"`` is ``Doe_ Jane-5d0a7e1c`` and
  ``"Doe_ Jane"`` stays ``Doe_ Jane``.  Ids are compared without case (a Mac's or Windows' disk
  does not tell ``Bob.txt`` from ``bob.txt``): :func:`collisions` finds what is left.
* :func:`walk` lists a folder breadth first, never following a link, within
  :data:`MAX_DEPTH` levels and :data:`MAX_ENTRIES` entries (the checker's limits: one walk for
  the checker's box and the grader's search for notebooks); beyond them :class:`WalkLimit`,
  before the rest is read.  No recursion: 1500 nested folders cost 16 listings.
* :func:`printable` and :func:`shown` make a name (or a code, a path) printable: every
  control, format or separator character (ESC and so every escape sequence, bidirectional
  overrides, zero-width characters, U+2028/U+2029, NBSP and the other spaces but the ASCII one,
  unassigned code points, a byte that was not UTF-8) is *written out* (``\\x1b``, ``\\u202e``)
  rather than dropped, so no name can reorder or hide the text around it, and two names that
  differ only by such a character never look alike (``Bob`` and ``Bob\\u200b`` are two names, not
  one student's cell in a gradebook).
* :func:`clean` removes the same characters from running text (feedback, a student's exception
  message), keeping its newlines when asked; :func:`bounded` keeps such a text under a size,
  what matters most first, and says what it left out.
* :func:`cell` keeps a spreadsheet from evaluating a CSV text cell (``=``, ``+``, ``-``, ``@``,
  tab, CR lead a formula): every CSV the package writes guards its text cells with it.
* :func:`secret_seed` draws the seed of a class's data, the other side of the same line: what
  no student can predict, so answers computed at home for a public seed pass nothing.

Names stay ``str`` as :func:`os.fsdecode` gives them (bytes that are not UTF-8 as surrogate
escapes, exactly what :func:`os.scandir` returns), and are encoded back with
:func:`os.fsencode`; nothing here ever encodes them strictly.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import unicodedata
from collections import deque
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

#: Entries (files and folders, hidden ones too) a student's folder may hold, and its depth.
MAX_ENTRIES = 2000
MAX_DEPTH = 16

#: Longest slug kept from a name (characters), before the hash.
SLUG_CHARS = 80

#: Hex digits of the hash of the raw name added to an id whose slug is not the name.
HASH_DIGITS = 8

def clean(text: str, newlines: bool = False) -> str:
    """``text`` without the characters :func:`printable` writes out (control, format such as bidi
    and zero-width, private-use, unassigned; line and paragraph separators), for running text:
    a tab or another space becomes a space, a lone surrogate (a byte that was not UTF-8) U+FFFD,
    newlines are kept only when asked."""
    out = []
    for c in text:
        if c.isprintable() or (c == "\n" and newlines):
            out.append(c)
        elif c == "\t" or unicodedata.category(c) == "Zs":
            out.append(" ")
        elif unicodedata.category(c) == "Cs":
            out.append("\ufffd")
    return "".join(out)


def printable(text: str, keep_newlines: bool = False) -> str:
    """``text`` as it may reach a terminal or a file a person reads: every character that is not
    printable (:meth:`str.isprintable`: the control, format, surrogate, private-use and
    unassigned ones, and every separator but the ASCII space) written ``\\xNN``, ``\\uNNNN`` or
    ``\\UNNNNNNNN``; newlines kept only when asked."""
    out = []
    for c in text:
        if c.isprintable() or (keep_newlines and c == "\n"):
            out.append(c)
        else:
            n = ord(c)
            out.append(f"\\x{n:02x}" if n < 0x100 else f"\\u{n:04x}" if n < 0x10000
                       else f"\\U{n:08x}")
    return "".join(out)


def shown(name: str | bytes, limit: int = 200) -> str:
    """A name as a person reads it: UTF-8 decoded (other bytes as ``\\xNN``), NFC,
    :func:`printable`, at most ``limit`` characters (the last one ``…`` when cut)."""
    raw = os.fsencode(name)
    text = printable(unicodedata.normalize("NFC", raw.decode("utf-8", "backslashreplace")))
    return text if len(text) <= limit else text[:limit - 1] + "…"


def cell(value: str) -> str:
    """A CSV text cell a spreadsheet will not evaluate: a leading ``=``, ``+``, ``-``, ``@``,
    tab or CR (which start a formula) behind a ``'``."""
    return "'" + value if value[:1] in ("=", "+", "-", "@", "\t", "\r") else value


def secret_seed() -> int:
    """A seed no student can predict (63 bits from :mod:`secrets`): the default of a class's
    check and grade, so answers precomputed at home for a public seed pass nothing.  The runs
    record it (``settings.seed``, ``grading.json``), so any verdict can be reproduced."""
    return secrets.randbits(63)


def _slug(text: str) -> str:
    out = []
    for c in unicodedata.normalize("NFC", text):
        ok = c.isalnum() or c in "_.- " or unicodedata.category(c)[0] == "M"
        if ok:
            out.append(c)
        elif not out or out[-1] != "_":
            out.append("_")
    return "".join(out)[:SLUG_CHARS].strip(" .")


def student_id(name: str | bytes) -> str:
    """The printable, file-safe id of a student's name (module docstring): the name itself when
    it is already a short slug of letters, digits, ``_.- ``; else its slug and a hash of its raw
    bytes, ``slug-1a2b3c4d``."""
    raw = os.fsencode(name)
    slug = _slug(raw.decode("utf-8", "replace"))
    if slug and slug.encode("utf-8") == raw:
        return slug
    return f"{slug or 'student'}-{hashlib.sha256(raw).hexdigest()[:HASH_DIGITS]}"


def hashed_id(name: str | bytes) -> str:
    """The id of ``name`` with the hash of its raw bytes always added (for names whose ids
    collide: two such ids differ unless the raw names are equal)."""
    raw = os.fsencode(name)
    digest = hashlib.sha256(raw).hexdigest()[:2 * HASH_DIGITS]
    return f"{_slug(raw.decode('utf-8', 'replace')) or 'student'}-{digest}"


def collisions(ids: list[str]) -> list[list[int]]:
    """Groups of indices of ``ids`` that name the same file on a disk that ignores case."""
    groups: dict[str, list[int]] = {}
    for i, x in enumerate(ids):
        groups.setdefault(x.casefold(), []).append(i)
    return [g for g in groups.values() if len(g) > 1]


def hidden(name: str) -> bool:
    """A name no student hands in as their work: a dot file or folder, or macOS's ``__MACOSX``
    (an unpacked archive's)."""
    return name.startswith(".") or name == "__MACOSX"


class WalkLimit(Exception):
    """A folder is deeper than :data:`MAX_DEPTH` (``kind="depth"``, ``where`` the folder that is
    too deep) or holds more than :data:`MAX_ENTRIES` entries (``kind="entries"``)."""

    def __init__(self, kind: str, where: str, limit: int) -> None:
        super().__init__(f"{kind} beyond {limit} at {where!r}")
        self.kind, self.where, self.limit = kind, where, limit


def walk(root: str | os.PathLike[str], skip: Callable[[str], bool] = lambda name: False,
         max_depth: int = MAX_DEPTH, max_entries: int = MAX_ENTRIES
         ) -> Iterator[tuple[str, os.DirEntry[str]]]:
    """``(relative path, entry)`` of everything under ``root``, breadth first, each folder's
    entries by name; a link is listed, never followed; an entry for which ``skip(name)`` is
    true is neither listed nor entered (it still counts).  :class:`WalkLimit` as soon as a
    folder is ``max_depth`` levels down or the entries seen exceed ``max_entries``; OSError
    when a folder cannot be listed."""
    top: str = os.fspath(root)
    queue: deque[tuple[str, int]] = deque([("", 0)])
    seen = 0
    while queue:
        rel_dir, depth = queue.popleft()
        listing: list[os.DirEntry[str]] = []
        with os.scandir(os.path.join(top, rel_dir) if rel_dir else top) as it:
            for e in it:  # counted as read: a folder of a million entries stops at the limit
                seen += 1
                if seen > max_entries:
                    raise WalkLimit("entries", rel_dir, max_entries)
                listing.append(e)
        for e in sorted(listing, key=lambda e: e.name):
            if skip(e.name):
                continue
            rel = f"{rel_dir}/{e.name}" if rel_dir else e.name
            yield rel, e
            if e.is_dir(follow_symlinks=False):
                if depth + 1 >= max_depth:
                    raise WalkLimit("depth", rel, max_depth)
                queue.append((rel, depth + 1))


def decoded(name: str) -> str:
    """``name`` (from :func:`os.fsdecode`) with every byte that was not UTF-8 written ``\\xNN``:
    a ``str`` that can be encoded, for a JSON file or a terminal."""
    return os.fsencode(name).decode("utf-8", "backslashreplace")


def json_safe(obj: Any) -> Any:
    """A copy of a JSON-like value (dicts, lists, tuples, strings) whose strings and keys have
    passed through :func:`decoded` (a file name that was not UTF-8 crashed the JSON writer)."""
    if isinstance(obj, str):
        return decoded(obj) if any("\udc80" <= c <= "\udcff" for c in obj) else obj
    if isinstance(obj, dict):
        return {json_safe(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


def bounded(lines: Sequence[tuple[int, str]], limit: int, left_out: Mapping[int, str],
            line_chars: int) -> str:
    """``lines`` (priority, text) as one text of at most ``limit`` bytes of UTF-8
    (:func:`_size`), in their order: each line cut to ``line_chars`` characters (a text of
    several lines is kept or left out whole, each of its lines cut); every line of priority 0,
    then those of priority 1, 2, ... while they fit (:func:`_fit`); each run of lines left out
    replaced by one line, ``left_out[priority]`` formatted with ``n`` (how many) and ``kb`` (the
    limit in KiB).
    For text made of what a student controls (a grade's feedback: their messages, one per cell
    of a notebook of any length)."""
    cut = [(k, "\n".join(x if len(x) <= line_chars else x[:line_chars - 1] + "…"
                          for x in t.split("\n"))) for k, t in lines]
    keep = _fit(cut, limit, max(map(len, left_out.values()), default=0) + 40)
    out: list[str] = []
    dropped = 0
    for i, (k, t) in enumerate(cut):
        if keep[i]:
            out.append(t)
            continue
        dropped += 1
        if i + 1 == len(cut) or keep[i + 1] or cut[i + 1][0] != k:
            out.append(left_out[k].format(n=dropped, kb=limit >> 10))
            dropped = 0
    text = "\n".join(out)
    if _size(text) > limit:  # the lines always kept are over the limit by themselves
        data = text.encode("utf-8", "surrogatepass")[:limit - 16]
        while data and data[-1] & 0xC0 == 0x80:  # not in the middle of a character
            data = data[:-1]
        text = data[:-1 if data and data[-1] >= 0xC0 else None].decode(
            "utf-8", "surrogatepass") + "\n... (cut)"
    return text


def _size(text: str) -> int:
    """Bytes of ``text`` in UTF-8, a lone surrogate (a name's undecodable byte) as 3."""
    return len(text.encode("utf-8", "surrogatepass"))


def _fit(cut: Sequence[tuple[int, str]], limit: int, per_run: int) -> list[bool]:
    """Which lines :func:`bounded` keeps: every line of priority 0, then by priority, in order,
    until the first that does not fit in ``limit`` bytes less ``per_run`` for each run of lines
    that may be left out (nothing of a lower priority once a line is left out)."""
    cost = [_size(t) + 1 for _, t in cut]
    runs = sum(1 for i, (k, _) in enumerate(cut) if k and (i == 0 or cut[i - 1][0] != k))
    budget = limit - per_run * runs - sum(c for (k, _), c in zip(cut, cost, strict=True) if not k)
    keep = [not k for k, _ in cut]
    for level in sorted({k for k, _ in cut} - {0}):
        for i, (k, _) in enumerate(cut):
            if k == level and cost[i] > budget:
                return keep  # in order: nothing after the first line that does not fit
            if k == level:
                keep[i], budget = True, budget - cost[i]
    return keep
