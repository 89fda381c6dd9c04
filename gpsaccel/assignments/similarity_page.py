"""``similarity.html``: the similarity report as a page an instructor reads.

Every name and every line of code on it is a student's text: each is HTML-escaped where it is
written (quotes too), and the page loads nothing (no script, no link, inline style only).
"""

from __future__ import annotations

import html

#: Answers shown side by side per group (the rest are named).
COLUMNS = 4

_STYLE = ("body{font-family:sans-serif;margin:2em;max-width:110em}"
          ".row{display:flex;gap:1em}.row>div{flex:1;min-width:0}"
          "pre{background:#f4f4f4;padding:.5em;overflow:auto;font-size:12px;max-height:40em}"
          "td,th{padding:.2em .6em;text-align:left;vertical-align:top}"
          "h2{margin-top:2em}.flag{color:#a00}")


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _code(rep, student: str, question: str) -> str:
    return (f"<div><b>{_e(student)}</b><pre>{_e(rep.code.get((student, question), ''))}</pre>"
            f"</div>")


def _groups(rep) -> str:
    if not rep.groups:
        return "<p>No two students share an answer.</p>"
    parts = []
    for g in rep.groups:
        shown = g.students[:COLUMNS]
        rest = g.students[COLUMNS:]
        pairs = "".join(f"<li>{_e(a)} &amp; {_e(b)}: {s:.0%}</li>" for a, b, s in g.pairs[:50])
        parts.append(
            f"<h3>{_e(g.question)}: a group of {g.size}</h3>"
            f"<p>{', '.join(_e(s) for s in g.students)}</p>"
            f"<details><summary>flagged pairs (share of the smaller answer found in the other)"
            f"</summary><ul>{pairs}</ul></details>"
            f"<div class=row>{''.join(_code(rep, s, g.question) for s in shown)}</div>"
            + (f"<p>and {len(rest)} more: {', '.join(_e(s) for s in rest)}</p>" if rest else ""))
    return "".join(parts)


def _hubs(rep) -> str:
    if not rep.hubs:
        return "<p>No answer matches classmates that do not match one another.</p>"
    return "".join(
        f"<h3>{_e(h.question)}: {_e(h.student)} matches {len(h.matches)} classmates</h3>"
        f"<p>in {h.parts} groups that do not match one another: one answer holding (or held "
        f"in) many others. Look at it; no group is joined through it, and its matches are not "
        f"flagged for it: {', '.join(_e(s) for s in h.matches)}</p>"
        f"<div class=row>{_code(rep, h.student, h.question)}</div>" for h in rep.hubs)


def _matches(rep, matches, none: str) -> str:
    if not matches:
        return f"<p>{none}</p>"
    return "".join(f"<h3>{_e(m.question)}: {_e(m.student)} ({m.share:.0%})</h3>"
                   f"<p>matches {_e(m.source)}</p>"
                   f"<div class=row>{_code(rep, m.student, m.question)}</div>" for m in matches)


def _table(items: dict[str, list[str]] | dict[str, str], none: str) -> str:
    if not items:
        return f"<p>{none}</p>"
    rows = []
    for s, what in sorted(items.items()):
        lines = what if isinstance(what, list) else [what]
        rows.append(f"<tr><td>{_e(s)}</td><td>{'<br>'.join(_e(x) for x in lines)}</td></tr>")
    return f"<table>{''.join(rows)}</table>"


def page(rep, share: float, min_prints: int) -> str:
    """The whole page of report ``rep`` (:class:`~gpsaccel.assignments.similarity.Report`)."""
    short = ", ".join(f"{_e(q)}: {n}" for q, n in sorted(rep.short.items()) if n)
    return (
        f"<!doctype html><meta charset=utf-8><title>{_e(rep.title)}: similarity</title>"
        f"<style>{_STYLE}</style><h1>{_e(rep.title)}: similarity and integrity</h1>"
        "<p>Flags to look at, not verdicts: grades are not affected. The code shown is the "
        "answer as graded, comments and layout removed.</p>"
        f"<p>{rep.compared} notebooks compared; {len(rep.groups)} group(s) of copies; "
        f"{len(rep.published)} answer(s) matching the published solution; "
        f"{len(rep.hubs)} hub(s); "
        f"{len(rep.hidden)} notebook(s) with hidden code; {len(rep.not_compared)} not compared."
        f" A group or a match needs {share:.0%} of the smaller answer's fingerprints in the "
        f"other; answers with fewer than {min_prints} fingerprints are too short to judge"
        f"{' (' + short + ')' if short else ''}.</p>"
        "<h2 class=flag>Hidden code</h2>"
        + _table(rep.hidden, "No notebook runs code it does not show.")
        + "<h2>Groups of copies</h2>" + _groups(rep)
        + "<h2 class=flag>Hubs</h2>" + _hubs(rep)
        + "<h2>Matches the published solution</h2>"
        + _matches(rep, rep.published, "No answer matches a published solution.")
        + ("<h2>Matches an earlier submission</h2>"
           + _matches(rep, rep.earlier, "No answer matches an earlier submission.")
           if rep.earlier else "")
        + "<h2>Not compared</h2>" + _table(rep.not_compared, "Every notebook was compared."))
