r"""The class similarity report: copied answers, the published solution, hidden code.

Per-student data and variants make a copied *output* worthless; this looks at copied *code*.
It flags, never grades: no score depends on it.  It is judged like a grade, under attack: the
class it reports on is its attacker.

What it compares.  Each graded notebook's record (:mod:`gpsaccel.assignments.answercode`, made
from the grader's own parse of the notebook and kept with the grade): per question, the answer's
fingerprints (:mod:`gpsaccel.assignments.fingerprint`: names folded, dead and unreachable code
dropped, every run of :data:`~gpsaccel.assignments.fingerprint.K` tokens hashed), less those of
the hand-out (:func:`gpsaccel.assignments.published.boilerplate`).

What it flags, per question (thresholds chosen by ``benchmarks/similarity.py``, docs/grading.md):

* a **group**: students whose answers share at least :data:`SHARE` of the smaller answer's
  fingerprints (containment, not a mutual share: a small answer inside a padded one counts), as
  connected groups: k students handing in one answer are one group of size k, however big;
* a **hub**: a student whose matched classmates fall into :data:`HUB_PARTS` or more groups that
  do not match one another (one answer holding, or held in, many).  Containment lets one long
  answer hold many short ones; a hub's pairs join nobody, and it is named with what it matches,
  so one notebook cannot chain honest students into a group (at most one classmate with itself,
  as a real copy does);
* a **match of the published solution**: an answer inside a published text (a packaged master,
  a lesson's solution), or the master's answer to the question inside the answer
  (:func:`gpsaccel.assignments.published.references`); likewise an earlier year's submission
  (``compare_with``);
* **hidden code**: code that runs text the notebook does not show
  (:mod:`gpsaccel.assignments.hidden`), or a graded name that no visible code defines although
  the question scored.

An answer with fewer than :data:`MIN_PRINTS` fingerprints is never flagged as a copy or as the
published solution: it is too short to tell a copy from the one way of writing it (a model
matrix is one line for everybody).  Nothing is "common" because many students share it: a ring
of twenty is one group of twenty.

A notebook that could not be parsed within the grader's limits, or whose record could not be
made, is **not compared**, named with the reason; it never costs the class its report.
"""

from __future__ import annotations

import io
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from gpsaccel.assignments import answercode, fingerprint, hidden
from gpsaccel.assignments.published import Reference

#: Share of the smaller answer's fingerprints found in the other that flags a pair, and of an
#: answer found in a published text (or of the master's answer found in it).
SHARE = 0.8

#: Fewest fingerprints (after the hand-out's are left out) an answer needs to be flagged.
MIN_PRINTS = 120

#: A student whose matched classmates fall into this many groups or more, none of which matches
#: another, is a hub: named with what it matches, and never joins anyone into a group.
HUB_PARTS = 2


@dataclass(frozen=True)
class Group:
    """Students of one question whose answers are copies of one another: ``pairs`` are the
    flagged (a, b, share of the smaller answer found in the other)."""

    question: str
    students: tuple[str, ...]
    pairs: tuple[tuple[str, str, float], ...]

    @property
    def size(self) -> int:
        return len(self.students)

    @property
    def share(self) -> float:
        return min(p[2] for p in self.pairs)


@dataclass(frozen=True)
class Hub:
    """A student whose answer matches classmates that do not match one another (``parts``
    groups of them): one answer holding many others, or held in many; a group is never joined
    through it."""

    question: str
    student: str
    matches: tuple[str, ...]
    parts: int


@dataclass(frozen=True)
class Match:
    """One student's answer found in (or holding) a published or earlier text."""

    question: str
    student: str
    source: str
    share: float


@dataclass
class Report:
    """The report's findings (plain data; :func:`write_report` writes it)."""

    title: str
    compared: int = 0
    groups: list[Group] = field(default_factory=list)
    hubs: list[Hub] = field(default_factory=list)
    published: list[Match] = field(default_factory=list)
    earlier: list[Match] = field(default_factory=list)
    earlier_read: list[str] = field(default_factory=list)
    earlier_left: dict[str, str] = field(default_factory=dict)
    hidden: dict[str, list[str]] = field(default_factory=dict)
    not_compared: dict[str, str] = field(default_factory=dict)
    short: dict[str, int] = field(default_factory=dict)
    code: dict[tuple[str, str], str] = field(default_factory=dict)


# ------------------------------------------------------------------------------ comparing
def shared_prints(rows: Sequence[frozenset[int]], cols: Sequence[frozenset[int]]):
    """The matrix of |rows[i] ∩ cols[j]| (sparse products).  Public for benchmarks/similarity.py,
    which sweeps the k-gram length over the same matrix the report computes."""
    import numpy as np
    from scipy import sparse

    vocab: dict[int, int] = {}
    for s in cols:
        for h in s:
            vocab.setdefault(h, len(vocab))

    def matrix(sets: Sequence[frozenset[int]]):
        at = [(i, vocab[h]) for i, s in enumerate(sets) for h in s if h in vocab]
        i, j = (list(x) for x in zip(*at, strict=True)) if at else ([], [])
        return sparse.csr_matrix((np.ones(len(i)), (i, j)), shape=(len(sets), max(len(vocab), 1)))

    return (matrix(rows) @ matrix(cols).T).toarray()


def _components(nodes: Sequence[int], edges: Sequence[tuple[int, int, float]]
                ) -> list[list[int]]:
    """The connected groups (singletons too) that ``edges`` make among ``nodes``."""
    parent = {i: i for i in nodes}

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i, j, _ in edges:
        if i in parent and j in parent:
            parent[root(i)] = root(j)
    members: dict[int, list[int]] = {}
    for i in nodes:
        members.setdefault(root(i), []).append(i)
    return list(members.values())


def _hubs(edges: Sequence[tuple[int, int, float]]
          ) -> tuple[dict[int, list[int]], dict[int, int]]:
    """(student -> the classmates it matches, hub -> how many groups those fall into by their
    own pairs): a hub is a student whose matches fall into :data:`HUB_PARTS` or more."""
    matched: dict[int, list[int]] = {}
    for i, j, _ in edges:
        matched.setdefault(i, []).append(j)
        matched.setdefault(j, []).append(i)
    parts = {i: len(_components(m, edges)) for i, m in matched.items()}
    return matched, {i: n for i, n in parts.items() if n >= HUB_PARTS}


def _groups(question: str, names: Sequence[str], prints: Sequence[frozenset[int]]
            ) -> tuple[list[Group], list[Hub]]:
    """The connected groups of pairs sharing :data:`SHARE` of the smaller answer, joined
    through no hub, and the hubs: students whose matched classmates fall into
    :data:`HUB_PARTS` or more groups, none of which matches another."""
    if len(names) < 2:
        return [], []
    import numpy as np

    size = np.array([len(p) for p in prints], dtype=float)
    share = shared_prints(prints, prints) / np.minimum.outer(size, size)
    edges = [(int(i), int(j), float(share[i, j]))
             for i, j in zip(*np.nonzero(np.triu(share >= SHARE, 1)), strict=True)]
    matched, hubs = _hubs(edges)
    kept = [e for e in edges if e[0] not in hubs and e[1] not in hubs]
    out = []
    for group in (g for g in _components(range(len(names)), kept) if len(g) > 1):
        inside = set(group)
        pairs = tuple((names[i], names[j], s) for i, j, s in kept if i in inside)
        out.append(Group(question, tuple(sorted(names[i] for i in group)), pairs))
    found = [Hub(question, names[i], tuple(sorted(names[j] for j in matched[i])), n)
             for i, n in hubs.items()]
    return (sorted(out, key=lambda g: (-g.size, g.students)),
            sorted(found, key=lambda h: (-len(h.matches), h.student)))


def _matches(question: str, names: Sequence[str], prints: Sequence[frozenset[int]],
             refs: Sequence[Reference]) -> list[Match]:
    """Each answer's best match among ``refs`` when it reaches :data:`SHARE`: the answer inside
    a reference, or a reference of this question (itself long enough) inside the answer."""
    refs = [r for r in refs if r.question in (None, question) and r.prints]
    if not names or not refs:
        return []
    shared = shared_prints(prints, [r.prints for r in refs])
    out = []
    for i, name in enumerate(names):
        best = (0.0, "")
        for j, r in enumerate(refs):  # in order: on a tie the first named (published) wins
            share = shared[i, j] / len(prints[i])
            if r.question is not None and len(r.prints) >= MIN_PRINTS:
                share = max(share, shared[i, j] / len(r.prints))
            if share > best[0]:
                best = (float(share), r.label)
        if best[0] >= SHARE:
            out.append(Match(question, name, best[1], best[0]))
    return out


def compare(question: str, answers: Mapping[str, Sequence[int]],
            boilerplate: frozenset[int] = frozenset(), refs: Sequence[Reference] = (),
            earlier: Sequence[Reference] = ()
            ) -> tuple[list[Group], list[Hub], list[Match], list[Match], int]:
    """One question: (groups, hubs, published matches, earlier matches, answers too short to
    judge) among ``answers`` (student -> tokens)."""
    prints = {s: fingerprint.kgrams(t) - boilerplate for s, t in answers.items() if t}
    names = sorted(s for s, p in prints.items() if len(p) >= MIN_PRINTS)
    short = sum(1 for s, p in prints.items() if len(p) < MIN_PRINTS)
    sets = [prints[s] for s in names]
    return (*_groups(question, names, sets), _matches(question, names, sets, refs),
            _matches(question, names, sets, earlier), short)


# ------------------------------------------------------------------------------ the class
def report(records: Mapping[str, dict], title: str,
           boilerplate: Mapping[str, frozenset[int]] | None = None,
           refs: Sequence[Reference] = (), earlier: Sequence[Reference] = (),
           scores: Mapping[str, Mapping[str, float]] | None = None) -> Report:
    """The report on a class: ``records`` maps each student to their notebook's record
    (:func:`gpsaccel.assignments.answercode.record`) or to ``{"why": reason}`` (not compared);
    ``scores`` (student -> question -> points) flags a graded name no visible code defines."""
    rep = Report(title)
    tokens: dict[str, dict[str, list[int]]] = {}
    for student, rec in records.items():
        why, answers = _read(rec)
        if why:
            rep.not_compared[student] = why
            continue
        tokens[student] = {q: a["tokens"] for q, a in answers.items()}
        for q, a in answers.items():
            rep.code[(student, q)] = a["code"]
        found = _findings(rec)
        for q, a in answers.items():
            got = (scores or {}).get(student, {}).get(q, 0.0)
            if a["undefined"] and got > 0:
                found.append(f"{q}: {', '.join(a['undefined'][:5])} scored {got:g} although no "
                             f"code the notebook shows defines it")
        if found:
            rep.hidden[student] = [str(f)[:300] for f in found]
    rep.compared = len(tokens)
    questions = sorted({q for t in tokens.values() for q in t})
    for q in questions:
        groups, hubs, pub, old, short = compare(
            q, {s: t.get(q, []) for s, t in tokens.items()},
            (boilerplate or {}).get(q, frozenset()), refs,
            [r for r in earlier if r.question == q])
        rep.groups += groups
        rep.hubs += hubs
        rep.published += pub
        rep.earlier += old
        rep.short[q] = short
    return rep


def _findings(rec: dict) -> list[str]:
    """A record's hidden-code findings (a list of text, bounded; anything else: none)."""
    found = rec.get("hidden", [])
    return [str(f)[:300] for f in found[:hidden.MAX_FINDINGS]] if isinstance(found, list) else []


def _read(rec: object) -> tuple[str, dict[str, dict]]:
    """(why not compared, question -> {"tokens", "code", "undefined"}) of a record, its shape
    checked (it crossed a process boundary and a file)."""
    if not isinstance(rec, dict) or not rec:
        return "no record of its code (graded before this report existed: regrade it)", {}
    if rec.get("why"):
        return str(rec["why"])[:300], {}
    out = {}
    try:
        for q, a in dict(rec.get("questions", {})).items():
            out[str(q)] = {"tokens": answercode.unpack(a.get("tokens", "")),
                           "code": str(a.get("code", ""))[:answercode.MAX_SHOWN],
                           "undefined": [str(n)[:80] for n in list(a.get("undefined", []))[:20]]}
    except (TypeError, ValueError, AttributeError):
        return "its record is damaged", {}
    return "", out


def class_report(grades: Sequence, name: str,
                 earlier: Sequence[tuple[str, Path | None]] = ()) -> Report:
    """The report on a graded class (:class:`~gpsaccel.assignments.scoring.Grade` s, each with
    the record its grading kept), against the published solutions of homework ``name`` and the
    ``earlier`` submissions ((name as shown, notebook or None): an earlier year's export, as the
    class run walks it)."""
    from gpsaccel import registry
    from gpsaccel.assignments import published
    from gpsaccel.assignments.generate import master_notebook

    asked = questions_asked(name)
    master = master_notebook(name)
    records: dict[str, dict] = {}
    shown = Counter(g.student for g in grades)

    def who(g) -> str:  # the name as shown; with its id where two show alike
        return g.student if shown[g.student] == 1 else f"{g.student} [{g.id}]"

    for g in grades:
        if not g.file:
            continue  # no notebook: its status says so in grades.csv
        record = getattr(g, "similarity", None) or {}
        if g.status == "unreadable":
            record = {"why": "its notebook could not be read within the grader's limits "
                             "(status unreadable)"}
        elif not record and g.status in ("not-graded", "grader-error"):
            record = {"why": f"its grading did not finish (status {g.status}): rerun it"}
        records[who(g)] = record
    title = registry.assignment(name).title or name
    old, read, left = earlier_references(earlier, asked)
    rep = report(records, title, published.boilerplate(master, asked),
                 published.references(name, master, asked), old,
                 {who(g): g.scores for g in grades})
    rep.earlier_read, rep.earlier_left = read, left
    return rep


def questions_asked(name: str) -> dict[str, answercode.Asked]:
    """Question -> what it grades, for homework ``name`` (its reads drawn once, public
    variant: only their names are used)."""
    from gpsaccel.assignments.questions import Draw
    from gpsaccel.assignments.scoring import assignment_module, questions_of

    draw = Draw(0, dict(assignment_module(name).DEFAULT_VARIANT))
    qs = questions_of(name)
    return answercode.asked(name, qs, {q.name: q.reads(draw) for q in qs if q.file is None})


def earlier_references(found: Sequence[tuple[str, Path | None]],
                       asked: Mapping[str, answercode.Asked]
                       ) -> tuple[list[Reference], list[str], dict[str, str]]:
    """(every answer of the earlier submissions ``found`` ((name as shown, notebook)), the
    names read, name -> why one was left out): each notebook parsed and its record made under
    the grader's limits; one that fails is left out and said (the report names it)."""
    from gpsaccel.assignments import notebook as nbm

    out: list[Reference] = []
    read: list[str] = []
    left: dict[str, str] = {}
    for shown, path in found:
        if path is None:
            left[shown] = "no notebook in it"
            continue
        try:
            rec = answercode.from_notebook(nbm.load(path), asked)
        except (nbm.NotebookError, OSError) as exc:
            left[shown] = str(exc)[:300]
            continue
        why, answers = _read(rec)
        if why:
            left[shown] = why
            continue
        read.append(shown)
        for q, a in answers.items():
            prints = fingerprint.kgrams(a["tokens"])
            if prints:
                out.append(Reference(f"earlier submission {shown}", prints, q))
    return out, read, left


# ------------------------------------------------------------------------------- writing
def _shown(text: str, limit: int = 60) -> str:
    """A student id (a folder name a student chose) or a finding, as one printable line."""
    from gpsaccel._untrusted import shown

    return shown(text, limit)


def rows(rep: Report) -> list[list[str]]:
    """The report as table rows: kind, question, students, size, share, detail."""
    out = []
    for s, why in sorted(rep.not_compared.items()):
        out.append(["not compared", "", s, "1", "", why])
    for s, why in sorted(rep.earlier_left.items()):
        out.append(["earlier submission left out", "", s, "1", "", why])
    for s, found in sorted(rep.hidden.items()):
        out += [["hidden code", f.split(":", 1)[0] if f.startswith("q") else "", s, "1", "", f]
                for f in found]
    for m in rep.published:
        out.append(["published solution", m.question, m.student, "1", f"{m.share:.2f}",
                    m.source])
    for m in rep.earlier:
        out.append(["earlier submission", m.question, m.student, "1", f"{m.share:.2f}",
                    m.source])
    for h in rep.hubs:
        out.append(["hub", h.question, h.student, "1", "",
                    f"matches {len(h.matches)} classmates in {h.parts} groups that do not match "
                    f"one another: {'; '.join(h.matches)}"])
    for g in rep.groups:
        out.append(["group", g.question, "; ".join(g.students), str(g.size), f"{g.share:.2f}",
                    f"{len(g.pairs)} flagged pair(s)"])
    return out


def write_report(rep: Report, out: Path) -> None:
    """``similarity.csv`` (:func:`rows`) and ``similarity.html``."""
    import csv

    from gpsaccel._atomic import write_text
    from gpsaccel._untrusted import cell
    from gpsaccel.assignments.similarity_page import page

    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["kind", "question", "students", "size", "share", "detail"])
    for r in rows(rep):
        w.writerow([cell(_shown(x, 2000)) for x in r])  # one line, printable, no formula
    write_text(out / "similarity.csv", buf.getvalue())
    write_text(out / "similarity.html", page(rep, SHARE, MIN_PRINTS))


def summary_rows(rep: Report) -> list[list[str]]:
    """The report's counts as rows of the class's ``summary.csv`` (its columns: question,
    possible, mean, full marks, students, code, count)."""
    rows = []
    for q in sorted({g.question for g in rep.groups} | {m.question for m in rep.published}
                    | {h.question for h in rep.hubs}):
        copied = {s for g in rep.groups if g.question == q for s in g.students}
        pasted = [m for m in rep.published if m.question == q]
        hubs = [h for h in rep.hubs if h.question == q]
        if copied:
            rows.append([q, "", "", "", "", "integrity: in a group of copies", str(len(copied))])
        if hubs:
            rows.append([q, "", "", "", "", "integrity: a hub (matches classmates that do not "
                         "match one another)", str(len(hubs))])
        if pasted:
            rows.append([q, "", "", "", "", "integrity: matches the published solution",
                         str(len(pasted))])
    for what, n in (("hidden code", len(rep.hidden)), ("not compared", len(rep.not_compared))):
        rows.append(["integrity", "", "", "", "", what, str(n)])
    return rows


def summary_lines(rep: Report, out: Path | None = None) -> list[str]:
    """What the terminal shows of the report (names printable, one line each)."""
    where = f" ({out / 'similarity.html'}; grades unchanged)" if out else " (grades unchanged)"
    head = (f"similarity: {rep.compared} notebooks compared; {len(rep.groups)} group(s) of "
            f"copies, {len(rep.published)} answer(s) matching the published solution, "
            f"{len(rep.hidden)} with hidden code, {len(rep.not_compared)} not compared"
            f"{f', {len(rep.hubs)} hub(s)' if rep.hubs else ''}{where}")
    lines = [head]
    for h in rep.hubs:
        lines.append(f"  {h.question}: hub: {_shown(h.student)} matches {len(h.matches)} "
                     f"classmates in {h.parts} groups that do not match one another (look at "
                     f"it; no group is joined through it)")
    for g in rep.groups:
        lines.append(f"  {g.question}: group of {g.size}: "
                     f"{', '.join(_shown(s) for s in g.students[:8])}"
                     f"{' ...' if g.size > 8 else ''} (at least {g.share:.0%} shared)")
    for m in rep.published + rep.earlier:
        lines.append(f"  {m.question}: {_shown(m.student)} matches {m.source} ({m.share:.0%})")
    for s, found in sorted(rep.hidden.items()):
        lines.append(f"  hidden code: {_shown(s)}: {_shown(found[0], 200)}"
                     f"{f' (+{len(found) - 1} more)' if len(found) > 1 else ''}")
    for s, why in sorted(rep.not_compared.items()):
        lines.append(f"  not compared: {_shown(s)}: {_shown(why, 300)}")
    if rep.earlier_read or rep.earlier_left:
        lines.append(f"  earlier submissions: {len(rep.earlier_read)} compared with, "
                     f"{len(rep.earlier_left)} left out")
    for s, why in sorted(rep.earlier_left.items()):
        lines.append(f"  earlier submission left out: {_shown(s)}: {_shown(why, 300)}")
    return lines

