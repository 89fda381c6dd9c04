"""Releasing the lessons: each master written as a student version and a solutions version.

One master, two versions (the way nbgrader and otter build a student release)::

    lessons/masters/NN-topic.ipynb      the source; holds the solutions
    lessons/NN-topic.ipynb              the student version: no solution text, no outputs
    lessons/solutions/NN-topic.ipynb    the solutions version (the rendered site's source)
    lessons/measured/NN-topic.json      measured at the lesson's full size: running time, printed text

Cell tags in a master: ``solution`` (code or markdown: removed from the student version),
``answer`` (the student's ``answer_… = None`` cell: removed from the solutions version, where the
solution assigns ``answer_…``) and ``check`` (one ``check("NN.k", answer_k)`` line; in the
solutions version it moves below the solution, so it shows ✓).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from gpsaccel._atomic import write_text
from gpsaccel.lessons import lessons_dir
from gpsaccel.lessons.render import _title

SOLUTION, ANSWER, CHECK = "solution", "answer", "check"

#: A number the text quotes from the lesson's own output is written ``[[0.687]]`` in the master
#: (``[[3.58 @04]]``: printed by lesson 04); the release writes it plainly, and
#: :func:`number_problems` finds it, digit for digit, in the measured output.
PRINTED = re.compile(r"\[\[([^\[\]@]+?)(?:\s*@(\w+))?\]\]")


#: The line the release writes (from lessons/measured/) under each lesson's title.
_TIME_LINE = re.compile(r"^\*Running time:.*\*$", re.M)

#: What JupyterLab 4 writes into a notebook's metadata on save (kernel ipykernel, Python).  The
#: interpreter's version, which Lab also writes, differs between machines: :func:`pre_save` drops
#: it, so a lesson saved from ``make lab`` is byte for byte what the release wrote.
LAB_METADATA = {
    "kernelspec": {"display_name": "Python 3 (ipykernel)", "language": "python", "name": "python3"},
    "language_info": {"codemirror_mode": {"name": "ipython", "version": 3}, "file_extension": ".py",
                      "mimetype": "text/x-python", "name": "python", "nbconvert_exporter": "python",
                      "pygments_lexer": "ipython3"},
}
NBFORMAT_MINOR = 5

_LESSON_NAME = re.compile(r"^(?:(?:masters|solutions)/)?\d\d[a-z]?-[\w.-]+\.ipynb$")


def masters_dir() -> Path:
    return lessons_dir() / "masters"


def _tags(cell) -> list[str]:
    return list(cell.get("metadata", {}).get("tags", []))


def _clean(cell, hidden: bool = False):
    """A copy of ``cell`` with no outputs, no execution count and the collapse flag set or gone."""
    import copy

    cell = copy.deepcopy(cell)
    if cell["cell_type"] == "code":
        cell["outputs"], cell["execution_count"] = [], None
    meta = cell.setdefault("metadata", {})
    jupyter = {k: v for k, v in meta.get("jupyter", {}).items() if k != "source_hidden"}
    if hidden:
        jupyter["source_hidden"] = True
    if jupyter:
        meta["jupyter"] = jupyter
    else:
        meta.pop("jupyter", None)
    meta.pop("collapsed", None)
    meta.pop("execution", None)
    return cell


#: A code cell that took at least this long (s) when measured says so in its first line.
SLOW_CELL = 5.0


def _fill_text(cell, stem: str, measured: dict | None):
    """Markdown: ``[[number]]`` written plainly; the first cell gets its running-time line.  Code:
    a cell measured at :data:`SLOW_CELL` seconds or more starts with ``# Slow cell: about N s``
    (in words: a clock glyph is an empty box without an emoji font)."""
    if cell["cell_type"] == "code":
        seconds = (measured or {}).get("cell_seconds", {}).get(cell.get("id", ""), 0.0)
        if seconds >= SLOW_CELL:
            note = f"# Slow cell: about {_rounded(seconds)} (measured); the output appears when it is done"
            cell["source"] = note + "\n" + cell["source"]
        return cell
    if cell["cell_type"] != "markdown":
        return cell
    source = PRINTED.sub(r"\1", "".join(cell["source"]) if isinstance(cell["source"], list)
                         else cell["source"])
    if source.startswith("# "):
        line = running_time_line(measured)
        title, _, rest = source.partition("\n")
        rest = _TIME_LINE.sub("", rest).lstrip("\n")
        source = f"{title}\n\n{line}\n\n{rest}".rstrip("\n")
    cell["source"] = source
    return cell


def running_time_line(measured: dict | None) -> str:
    """The sentence under a lesson's title, from its measurement."""
    if not measured:
        return "*Running time: not measured yet (`python -m gpsaccel.lessons measure`).*"
    s, runs = measured["seconds"], measured.get("runs")
    size = "" if runs is None else f" with `GPSACCEL_LESSON_RUNS={runs}`"
    full = "" if runs is None else "; the lesson's full size takes longer (not measured)"
    return (f"*Running time: about {_rounded(s)} for Run All{size}, measured {s:.0f} s on a shared "
            f"2-core machine at load {measured.get('load', 0):.1f} (an unloaded laptop is faster)"
            f"{full}.*")


def _rounded(seconds: float) -> str:
    """A duration as a lesson states it: 5 s steps up to 90 s, then minutes to one decimal."""
    return f"{max(5, 5 * round(seconds / 5)):.0f} s" if seconds < 90 else f"{seconds / 60:.1f} min"


def _notebook(cells, nb):
    import nbformat

    out = nbformat.v4.new_notebook()
    out.cells = cells
    out.metadata = json.loads(json.dumps(LAB_METADATA))
    for key, value in nb.metadata.items():
        if key not in ("kernelspec", "language_info", "widgets"):
            out.metadata[key] = value
    out.nbformat, out.nbformat_minor = 4, NBFORMAT_MINOR
    return out


#: How a solution cell starts in the solutions version.  JupyterLab shows a collapsed code cell's
#: first line in its placeholder: this line is what shows, not the solution's first step.  A
#: markdown cell shows its rendered text even when its source is hidden, so a markdown solution is
#: wrapped in ``<details>``: closed until the student opens it (JupyterLab and the HTML pages).
#: Each names its exercise (:func:`exercise_of`); the HTML template's summary of a code solution
#: reads the same label from the cell's ``gpsaccel.solution`` metadata.
SOLUTION_LINE = {"code": "# {label}", "markdown": "<details><summary>{label}</summary>"}


def solution_label(exercise: str | None) -> str:
    """The one wording of a collapsed solution: "Solution to exercise 03.2 (open once you have
    tried)", or without the number where the master does not say which exercise it solves."""
    to = f" to exercise {exercise}" if exercise else ""
    return f"Solution{to} (open once you have tried)"


#: What says which exercise a master's cell belongs to: a markdown cell opening with "*Exercise 2"
#: or "**Solution 2.", the key of a self-check (``self_check("03.2"``) or an id ``solution-2``.  (An
#: id like ``ex09s5`` does not: lesson 09's ``ex09q5`` is "*Exercise 3, solution:*".)
_EXERCISE_ID = re.compile(r"^solution-(\d+)")
_EXERCISE_TEXT = re.compile(r"^\*{1,2}(?:Exercise|Solution) (\d+)\b")
_EXERCISE_CHECK = re.compile(r"""self_check\(\s*["'][0-9a-z]+\.(\d+)["']""")


def exercise_of(cell, current: int | None) -> int | None:
    """The exercise number ``cell`` belongs to; ``current`` (the last one seen) when it says none."""
    source = cell["source"] if isinstance(cell["source"], str) else "".join(cell["source"])
    for pattern, text in ((_EXERCISE_TEXT, source.lstrip()), (_EXERCISE_CHECK, source),
                          (_EXERCISE_ID, cell.get("id", ""))):
        found = pattern.search(text)
        if found:
            return int(found.group(1))
    return current


def _solution_first_line(cell, exercise: str | None = None):
    label = solution_label(exercise)
    cell.setdefault("metadata", {})["gpsaccel"] = {"solution": label}
    if cell["cell_type"] == "markdown":
        cell["source"] = f"{SOLUTION_LINE['markdown'].format(label=label)}\n\n{cell['source']}\n\n</details>"
    else:
        cell["source"] = f"{SOLUTION_LINE['code'].format(label=label)}\n{cell['source']}"
    return cell


def student_version(nb, stem: str, measured: dict | None = None):
    """No cell tagged ``solution``; outputs cleared (a student's first Run All is theirs, and the
    committed file stays what ``git pull`` can update); nothing collapsed."""
    cells = [_fill_text(_clean(c), stem, measured) for c in nb.cells if SOLUTION not in _tags(c)]
    return _notebook(cells, nb)


#: What a master's "How the exercises work" cell says of the solutions (true of the student
#: version), and what the solutions version, which holds them, says instead.
SOLUTIONS_ELSEWHERE = ("The solutions are not in this notebook: they are in the `solutions/` "
                       "folder next to it (and, collapsed, on the rendered site), to open once you "
                       "have tried.")
SOLUTIONS_HERE = ("This is the solutions version: each exercise's solution is in this notebook, "
                  "collapsed under it, to open once you have tried (the student version, one "
                  "folder up, leaves them out).")


def _solutions_here(cell, stem: str):
    """``cell`` with :data:`SOLUTIONS_ELSEWHERE` replaced by :data:`SOLUTIONS_HERE`; a cell that
    still says the solutions are "not in this notebook" is a master whose wording changed: an
    error naming the lesson, never a solutions version that denies holding them."""
    if cell["cell_type"] == "markdown":
        cell["source"] = cell["source"].replace(SOLUTIONS_ELSEWHERE, SOLUTIONS_HERE)
        if "not in this notebook" in cell["source"]:
            raise ValueError(f"{stem}: a markdown cell says the solutions are not in this notebook"
                             f" in other words than release.SOLUTIONS_ELSEWHERE; the solutions "
                             f"version holds them (write the master's sentence as that one)")
    return cell


def solutions_version(nb, stem: str, measured: dict | None = None):
    """Every cell but the ``answer`` ones; each ``check`` below the solution cells that follow it
    (so it checks the solution's ``answer_…``); solutions collapsed; outputs cleared.  An exercise
    whose prompt is only in the lesson's "## Exercises" list gets it above its first solution
    (:func:`exercise_prompts`), so a reader of the solutions sees what each one answers; where
    the master says the solutions are elsewhere, this version says it holds them
    (:data:`SOLUTIONS_HERE`)."""
    cells, pending, number = [], [], None
    lesson = stem.split("-", 1)[0]
    prompts, shown = exercise_prompts(nb), set()
    for c in nb.cells:
        tags = _tags(c)
        number = exercise_of(c, number)
        if ANSWER in tags:
            continue
        if CHECK in tags:
            pending.append(_fill_text(_clean(c), stem, measured))
            continue
        if SOLUTION not in tags and pending:
            cells += pending
            pending = []
        cell = _fill_text(_clean(c, hidden=SOLUTION in tags), stem, measured)
        if SOLUTION not in tags:
            cell = _solutions_here(cell, stem)
            if cell["cell_type"] == "markdown" and _EXERCISE_TEXT.match(cell["source"].lstrip()):
                shown.add(number)                  # the master's own prompt cell: shown as it is
            cells.append(cell)
            continue
        if number in prompts and number not in shown:
            cells.append(_prompt_cell(number, prompts[number], stem, measured))
            shown.add(number)
        cells.append(_solution_first_line(cell, f"{lesson}.{number}" if number is not None else None))
    return _notebook(cells + pending, nb)


_LIST_ITEM = re.compile(r"^(\d+)\.\s+(.*)$")


def exercise_prompts(nb) -> dict[int, str]:
    """{number: text} of the items of the lesson's "## Exercises" cell (a numbered list, each
    item's continuation lines indented), as the master writes them."""
    prompts: dict[int, list[str]] = {}
    for cell in nb.cells:
        source = cell["source"] if isinstance(cell["source"], str) else "".join(cell["source"])
        if cell["cell_type"] != "markdown" or not source.startswith("## Exercises"):
            continue
        current = None
        for line in source.splitlines()[1:]:
            item = _LIST_ITEM.match(line)
            if item:
                current = int(item.group(1))
                prompts[current] = [item.group(2)]
            elif current is not None and line.startswith("   "):
                prompts[current].append(line[3:])
            elif line.strip():
                current = None                      # text after the list
        break
    return {n: "\n".join(lines).strip() for n, lines in prompts.items()}


def _prompt_cell(number: int, text: str, stem: str, measured: dict | None):
    import nbformat

    cell = nbformat.v4.new_markdown_cell(f"*Exercise {number}:* {text}", id=f"exercise-{number}-prompt")
    return _fill_text(cell, stem, measured)


def lab_text(nb) -> str:
    """The notebook as JupyterLab's server writes it: nbformat's JSON (indent 1, sorted keys,
    non-ASCII kept) and a trailing newline."""
    import nbformat

    text = nbformat.writes(nb, version=4)
    return text if text.endswith("\n") else text + "\n"


def measured(stem: str) -> dict | None:
    path = lessons_dir() / "measured" / f"{stem}.json"
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else None


def released(master: Path) -> dict[Path, str]:
    """What the release writes for ``master``: {target path: text}."""
    import nbformat

    nb = nbformat.read(master, as_version=4)
    stem, m = master.stem, measured(master.stem)
    return {lessons_dir() / master.name: lab_text(student_version(nb, stem, m)),
            lessons_dir() / "solutions" / master.name: lab_text(solutions_version(nb, stem, m))}


def masters(only: list[str] | None = None) -> list[Path]:
    """Every master (any ``NN-topic.ipynb`` in lessons/masters/), or those starting with ``only``."""
    paths = sorted(p for p in masters_dir().glob("*.ipynb") if _LESSON_NAME.match(p.name))
    if only:
        paths = [p for p in paths if any(p.name.startswith(o) for o in only)]
        if not paths:
            raise ValueError(f"no master in {masters_dir()} starts with {' or '.join(only)}")
    return paths


def lessons_table() -> str:
    """The table of docs/lessons.md: each lesson, what it covers (its title) and its running time."""
    import nbformat

    rows = ["| lesson | covers | running time |", "|---|---|---|"]
    for master in masters():
        title = _title(nbformat.read(master, as_version=4)).split("—", 1)[-1].strip()
        m = measured(master.stem)
        said = f"about {_rounded(m['seconds'])}" if m else "not measured yet"
        rows.append(f"| `{master.stem}` | {title} | {said} |")
    return "\n".join(rows)


def _page_with_table(name: str, marker: str, table: str) -> tuple[Path, str]:
    """docs/``name`` (the checkout's) with what stands between its ``<!-- marker -->`` and
    ``<!-- /marker -->`` lines replaced by ``table``."""
    path = Path(__file__).resolve().parents[2] / "docs" / name
    block = re.compile(rf"(<!-- {marker} -->\n).*?(<!-- /{marker} -->)", re.S)
    text = path.read_text(encoding="utf-8")
    return path, block.sub(lambda m: m.group(1) + table + "\n" + m.group(2), text)


def docs_page() -> tuple[Path, str]:
    """docs/lessons.md with its table as the release writes it."""
    return _page_with_table("lessons.md", "lessons-table", lessons_table())


def taught_table() -> str:
    """The table of docs/checker.md: every code a student can be shown and the lesson section
    that teaches its fix (:data:`gpsaccel._taught.TAUGHT`; a lesson self-check's key is left
    out), each linked to the section on the rendered site."""
    from gpsaccel._taught import TAUGHT

    rows = ["| code | where the course teaches it |", "|---|---|"]
    for code, s in sorted((c, s) for c, s in TAUGHT.items() if not c[:1].isdigit()):
        link = f"[lesson {s.number}, {s.heading}](_lessons/{s.notebook}#{s.anchor})"
        rows.append(f"| `{code}` | {link}{f' (exercise {s.exercise})' if s.exercise else ''} |")
    return "\n".join(rows)


def checker_page() -> tuple[Path, str]:
    """docs/checker.md with its table of where each code is taught as the release writes it."""
    return _page_with_table("checker.md", "taught-table", taught_table())


def release(only: list[str] | None = None) -> list[Path]:
    """Write the student and solutions versions of every master (and the tables of
    docs/lessons.md and docs/checker.md); returns the notebooks written."""
    for path, text in (docs_page(), checker_page()):
        if path.read_text(encoding="utf-8") != text:
            write_text(path, text)
    written = []
    for master in masters(only):
        for target, text in released(master).items():
            target.parent.mkdir(parents=True, exist_ok=True)
            if not target.exists() or target.read_text(encoding="utf-8") != text:
                write_text(target, text)
            written.append(target)
    return written


def code_digest(master: Path) -> str:
    """SHA-256 of a master's code cells: a measurement is stale once it changes."""
    import hashlib

    import nbformat

    nb = nbformat.read(master, as_version=4)
    code = "\n\0".join(c.source for c in nb.cells if c.cell_type == "code")
    return hashlib.sha256(code.encode()).hexdigest()


def pre_save(model, path, **kwargs) -> None:
    """JupyterLab pre-save hook (``make lab`` sets it): a lesson is saved without outputs, execution
    counts or the interpreter's version, i.e. exactly as the release wrote it, so opening and
    running one leaves ``git status`` clean.  Other notebooks are saved untouched."""
    if model.get("type") != "notebook" or not _LESSON_NAME.match(path.lstrip("/")):
        return
    nb = model["content"]
    nb.get("metadata", {}).get("language_info", {}).pop("version", None)
    nb.get("metadata", {}).pop("widgets", None)
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "code":
            cell["outputs"], cell["execution_count"] = [], None
        cell.get("metadata", {}).pop("execution", None)
