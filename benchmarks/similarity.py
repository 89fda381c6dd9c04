"""The similarity report measured: false flags on honest classes, detections of planted copies,
its cost for 200 students with a ring of 20 (docs/grading.md, "Integrity").

Classes of the calibration homework come from ``benchmarks/_similarity_classes.py``, their
copies from ``_similarity_copies.py`` (seeded):

* **honest** classes of 50 and 200 (several seeds): a student is a false flag when the report
  puts them in a group or says they match the published solution;
* **planted** copies in honest classes of 50: pairs for each disguise (renamed, reordered,
  padded with about 90 dead statements, all three, all three and three hand edits), rings of 3,
  5, 10 and 20 (one answer, each member disguised differently), and the published solution
  pasted with each disguise.  A pair or ring is detected when its members are all in one
  group, a paste when the report names the published solution;

per question: q1 (six matrices), q2 (the filter), q3 (two NEES functions).  Every answer goes
the grader's way: its notebook's record (``answercode.record``, from the cells as IPython's
transformer leaves them), then ``similarity.report`` with the homework's hand-out and published
solutions.

``--sweep`` prints, for other k-gram lengths and shares, the honest pairs over the share and
the lowest share of an edited copy (how the defaults were chosen); ``--cost`` the CPU for 200
students and a ring of 20.  ``--write`` replaces the table in docs/grading.md.

Usage: python benchmarks/similarity.py [--table] [--sweep] [--cost] [--write]  (no flag: all
three; ``make bench`` writes them to docs/benchmarks/similarity.txt)
"""

from __future__ import annotations

import re
import resource
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _similarity_classes as sc  # noqa: E402

from gpsaccel.assignments import answercode, fingerprint, published  # noqa: E402
from gpsaccel.assignments import similarity as sim  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "grading.md"
BEGIN, END = "<!-- similarity table: benchmarks/similarity.py -->", "<!-- end of table -->"

HONEST = ((50, (1, 2, 3, 4, 5)), (200, (1, 2, 3)))
PAIRS = 10  # pairs planted per disguise and question
RINGS = (3, 5, 10, 20)
QUESTIONS = ("q1", "q2", "q3")


class Homework:
    """The calibration homework's questions, hand-out and published solutions, once."""

    def __init__(self) -> None:
        from gpsaccel.assignments.generate import master_notebook

        self.asked = sim.questions_asked("calibration")
        master = master_notebook("calibration")
        self.boilerplate = published.boilerplate(master, self.asked)
        self.refs = published.references("calibration", master, self.asked)

    def record(self, answers: dict[str, str]) -> dict:
        from gpsaccel.assignments.notebook import transform

        srcs = sc.cells(answers)
        return answercode.record([(i, transform(s)) for i, s in enumerate(srcs, 1)],
                                 answercode.written_files(srcs), self.asked)

    def report(self, c: sc.Class) -> sim.Report:
        records = {s: self.record(a) for s, a in c.answers.items()}
        return sim.report(records, "calibration", self.boilerplate, self.refs)


def flagged(rep: sim.Report, q: str) -> set[str]:
    return {s for g in rep.groups if g.question == q for s in g.students} | \
        {m.student for m in rep.published if m.question == q}


def honest_rates(hw: Homework) -> dict[tuple[int, str], tuple[int, int]]:
    """(class size, question) -> (students falsely flagged, students), over the seeds."""
    out: dict[tuple[int, str], tuple[int, int]] = {}
    for n, seeds in HONEST:
        for seed in seeds:
            rep = hw.report(sc.honest(n, np.random.default_rng(seed)))
            for q in QUESTIONS:
                f, t = out.get((n, q), (0, 0))
                out[(n, q)] = (f + len(flagged(rep, q)), t + n)
    return out


def _master_answer(q: str) -> str:
    """The published solution of question ``q`` as a student would paste it."""
    import json

    from gpsaccel.assignments.generate import master_notebook

    data = json.loads(master_notebook("calibration").read_text(encoding="utf-8"))
    codes = ["".join(c["source"]) for c in data["cells"] if c["cell_type"] == "code"]
    want = {"q1": "Phi = ", "q2": "%%writefile", "q3": "def average_nees"}[q]
    src = next(c for c in codes if want in c)
    src = src.split("\n", 1)[1] if q == "q2" else src
    return "\n".join(ln.replace("  # SOLUTION", "") for ln in src.splitlines()
                     if ln.strip() not in ("# BEGIN SOLUTION", "# END SOLUTION")) + "\n"


def planted(hw: Homework, seed: int = 11) -> dict[tuple[str, str], tuple[int, int]]:
    """(question, plant) -> (students found, students planted): a pair or a ring counts the
    most of its members one group holds (none when that is one), a paste whether the report
    names the published solution."""
    rng = np.random.default_rng(seed)
    c = sc.honest(50, rng)
    for q in QUESTIONS:
        for kind in sc.DISGUISES:
            for _ in range(PAIRS):
                sc.plant(c, q, kind, 2, rng)
        for size in RINGS:
            sc.plant(c, q, "mixed", size, rng)
        for kind in sc.DISGUISES:
            sc.plant(c, q, kind, 1, rng, source=_master_answer(q))
    rep = hw.report(c)
    out: dict[tuple[str, str], tuple[int, int]] = {}
    for q, kind, who in c.planted:
        if len(who) == 1:  # the published solution pasted
            found = int(who[0] in {m.student for m in rep.published if m.question == q})
            key = f"published solution pasted, {kind}"
        else:  # the most members one group holds
            found = max([len(set(who) & set(g.students)) for g in rep.groups
                         if g.question == q] or [0])
            found = found if found > 1 else 0
            key = f"pair, {kind}" if kind != "mixed" else f"ring of {len(who)}"
        d, t = out.get((q, key), (0, 0))
        out[(q, key)] = (d + found, t + len(who))
    return out


def table(hw: Homework) -> str:
    """The markdown table of docs/grading.md."""
    rates = honest_rates(hw)
    plants = planted(hw)
    head = "| | " + " | ".join(QUESTIONS) + " |\n|---|" + "---|" * len(QUESTIONS) + "\n"
    rows = []
    for n, seeds in HONEST:
        cells = [f"{f} of {t} ({100 * f / t:.1f} %)" for f, t in (rates[(n, q)]
                                                                  for q in QUESTIONS)]
        rows.append(f"| honest, class of {n} ({len(seeds)} seeds): falsely flagged | "
                    + " | ".join(cells) + " |")
    for key in dict.fromkeys(k for _, k in plants):
        cells = [f"{plants[(q, key)][0]} / {plants[(q, key)][1]}" for q in QUESTIONS]
        rows.append(f"| {key}: found | " + " | ".join(cells) + " |")
    return head + "\n".join(rows) + "\n"


def cost(hw: Homework) -> str:
    """CPU of the report for 200 honest students and a ring of 20 (q2), this process."""
    rng = np.random.default_rng(1)
    c = sc.honest(200, rng)
    sc.plant(c, "q2", "mixed", 20, rng)
    from gpsaccel.assignments.notebook import Cell, Notebook, transform

    parsed = {s: Notebook([Cell(i, x, transform(x)) for i, x in enumerate(sc.cells(a), 1)])
              for s, a in c.answers.items()}  # as the grader's parse leaves them
    t0 = _cpu()
    records = {s: answercode.from_notebook(nb, hw.asked) for s, nb in parsed.items()}
    t1 = _cpu()
    published.package_documents.cache_clear()
    rep = sim.report(records, "calibration",
                     published.boilerplate(sc_master(), hw.asked),
                     published.references("calibration", sc_master(), hw.asked))
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        sim.write_report(rep, Path(tmp))
    t2 = _cpu()
    ring = [g for g in rep.groups if g.question == "q2" and g.size >= 20]
    import os

    load = os.getloadavg()[0]
    return (f"{len(records)} notebooks (200 honest, a ring of 20 on q2): records "
            f"{t1 - t0:.2f} CPU s ({1000 * (t1 - t0) / len(records):.0f} ms a notebook, a "
            f"child under limits each, in each notebook's grading process); the report "
            f"(hand-out, published solutions, comparison, similarity.csv and .html) "
            f"{t2 - t1:.2f} CPU s; ring found as one group of {ring[0].size if ring else 0}; "
            f"load {load:.1f} on {os.cpu_count()} CPUs")


def sc_master():
    from gpsaccel.assignments.generate import master_notebook

    return master_notebook("calibration")


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    c = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime + c.ru_utime + c.ru_stime


def sweep(hw: Homework, ks: Sequence[int] = (8, 10, 12, 16, 20),
          shares: Sequence[float] = (0.7, 0.8, 0.9)) -> str:
    """Honest pairs (class of 200, seed 1) over each share, per k and question, and the
    lowest and median share of an edited copy (20 pairs): how K and SHARE were chosen."""
    rng = np.random.default_rng(1)
    c = sc.honest(200, rng)
    toks = {s: _tokens(hw.record(a)) for s, a in c.answers.items()}
    edits = {q: [] for q in QUESTIONS}
    for q in QUESTIONS:
        for _ in range(20):
            base = sc.GENERATORS[q](rng)
            a = {x: g(rng) for x, g in sc.GENERATORS.items()}
            b = dict(a)
            a[q], b[q] = base, sc.DISGUISES["all three + 3 edits"](base, rng)
            edits[q].append((_tokens(hw.record(a))[q], _tokens(hw.record(b))[q]))
    lines = [f"k   question  honest pairs of 200 at share >= {', '.join(map(str, shares))} "
             f"(answers >= {sim.MIN_PRINTS} prints)   edited copy: lowest / median share"]
    for k in ks:
        bp = published.boilerplate(sc_master(), hw.asked, k)
        for q in QUESTIONS:
            prints = [fingerprint.kgrams(t[q], k) - bp[q] for t in toks.values()]
            prints = [p for p in prints if len(p) >= sim.MIN_PRINTS]
            counts = []
            if len(prints) > 1:
                shared = sim.shared_prints(prints, prints)
                size = np.array([len(p) for p in prints], dtype=float)
                cont = shared / np.minimum.outer(size, size)
                iu = np.triu_indices(len(prints), 1)
                counts = [int((cont[iu] >= s).sum()) for s in shares]
            ed = sorted(len((fingerprint.kgrams(a, k) - bp[q]) & (fingerprint.kgrams(b, k)
                                                                    - bp[q]))
                        / max(1, min(len(fingerprint.kgrams(a, k) - bp[q]),
                                     len(fingerprint.kgrams(b, k) - bp[q])))
                        for a, b in edits[q])
            lines.append(f"{k:<3} {q:<9} {len(prints):>3} judged; "
                         f"{' / '.join(map(str, counts)) or '-':<16} "
                         f"{ed[0]:.2f} / {ed[len(ed) // 2]:.2f}")
    return "\n".join(lines)


def _tokens(record: dict) -> dict[str, list[int]]:
    return {q: answercode.unpack(a["tokens"]) for q, a in record["questions"].items()}


def write(text: str) -> None:
    doc = DOC.read_text(encoding="utf-8")
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    if not pattern.search(doc):
        raise SystemExit(f"{DOC} has no {BEGIN} ... {END} block")
    DOC.write_text(pattern.sub(lambda _: f"{BEGIN}\n{text}{END}", doc), encoding="utf-8")


def main(argv: list[str]) -> int:
    hw = Homework()
    t0 = time.perf_counter()
    parts = [p for p in ("--table", "--sweep", "--cost") if p in argv] or \
        ["--table", "--sweep", "--cost"]
    if "--table" in parts or "--write" in argv:
        text = table(hw)
        print(f"Detections and false flags (thresholds: {fingerprint.K} tokens a fingerprint, "
              f"share {sim.SHARE}, answers of {sim.MIN_PRINTS} fingerprints or more)\n\n{text}")
        if "--write" in argv:
            write(text)
    if "--sweep" in parts:
        print(f"How K and SHARE were chosen\n\n{sweep(hw)}\n")
    if "--cost" in parts:
        print(f"Cost\n\n{cost(hw)}")
    print(f"({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
