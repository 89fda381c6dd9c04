"""The held-out set's confusion table (issue 40): every file of tests/check/heldout/ checked against
its problem, each result classed as

* ``named``      a wrong filter given exactly its own code (``expect``);
* ``generic``    a wrong filter given only a generic code (``p-mismatch``, ``gain-or-residual``,
  ``filter-mismatch``, or the ``accept`` code its file names);
* ``wrong name`` a wrong filter given another code (a misnamed mistake, or a failure of the box
  such as ``result-refused``);
* ``false pass`` a wrong filter that passes;
* ``false fail`` a right filter that does not pass.

Each file's docstring starts ``expect: CODE`` (``pass`` for a right filter) and may say ``accept:
CODE, CODE`` (the generic codes it may get instead) with the reason.  Run ``python
tests/check/heldout/confusion.py [--seed S] [--runs N]`` for the table (and each file's codes
with ``-v``); tests/check/test_heldout.py holds every file to it.
"""

from __future__ import annotations

import copy
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
PROBLEMS = ("calibration", "tracker", "ship", "coop", "wind")
GENERIC = {"p-mismatch", "gain-or-residual", "filter-mismatch"}
CLASSES = ("named", "generic", "wrong name", "false pass", "false fail", "right")
SEED, RUNS = 7, 3


@dataclass(frozen=True)
class Entry:
    path: Path
    problem: str
    expect: str
    accept: tuple[str, ...]

    @property
    def name(self) -> str:
        return f"{self.problem}/{self.path.stem}"


def entries() -> list[Entry]:
    out = []
    for problem in PROBLEMS:
        for path in sorted((HERE / problem).glob("*.py")):
            doc = path.read_text(encoding="utf-8")
            expect = re.search(r"^\"\"\"expect: ([A-Za-z0-9-]+)", doc, re.M)
            if expect is None:
                raise ValueError(f"{path}: no 'expect: CODE' at the start of its docstring")
            accept = re.search(r"^accept: ([A-Za-z0-9-]+(?:, [A-Za-z0-9-]+)*)", doc, re.M)
            out.append(Entry(path, problem, expect.group(1),
                             tuple(accept.group(1).split(", ")) if accept else ()))
    return out


def named(problem_name: str) -> set[str]:
    """The codes the set's wrong filters of ``problem_name`` must each get (their ``expect``)."""
    return {e.expect for e in entries() if e.problem == problem_name and e.expect != "pass"}


def problem(name: str):
    """The problem ``name`` (a copy that keeps its answers between the set's checks)."""
    from gpsaccel.check import problems

    if name == "wind":
        sys.path.insert(0, str(HERE))
        try:
            from wind_problem import WIND  # type: ignore[import-not-found]
        finally:
            sys.path.remove(str(HERE))
        p = WIND
    else:
        p = problems.get(name)
    kept = copy.copy(p)
    kept.forget = lambda: None  # the answers are trusted here: the set's own files
    return kept


def classify(entry: Entry, report) -> str:
    codes = report.codes
    if entry.expect == "pass":
        return "right" if report.passed else "false fail"
    if report.passed:
        return "false pass"
    if codes == [entry.expect]:
        return "named"
    if set(codes) <= GENERIC | set(entry.accept):
        return "generic"
    return "wrong name"


def check(entry: Entry, kept: dict, seed: int = SEED, n_runs: int = RUNS):
    from gpsaccel import check as chk

    if entry.problem not in kept:
        kept[entry.problem] = problem(entry.problem)
    return chk.submission(entry.path, problem=kept[entry.problem], n_runs=n_runs, seed=seed,
                          sandbox="basic")


def main(argv: list[str]) -> int:
    seed = int(argv[argv.index("--seed") + 1]) if "--seed" in argv else SEED
    runs = int(argv[argv.index("--runs") + 1]) if "--runs" in argv else RUNS
    verbose = "-v" in argv
    kept: dict = {}
    table = {p: dict.fromkeys(CLASSES, 0) for p in PROBLEMS}
    t0 = time.process_time()
    for e in entries():
        report = check(e, kept, seed, runs)
        c = classify(e, report)
        table[e.problem][c] += 1
        if verbose:
            print(f"{c:<11} {e.name:<40} expect {e.expect:<28} got {','.join(report.codes) or '-'}")
    print(f"\nheld-out set, seed {seed}, {runs} runs per check ({time.process_time() - t0:.0f} CPU s "
          f"in this process)")
    print(f"{'problem':<12}" + "".join(f"{c:>12}" for c in CLASSES))
    total = dict.fromkeys(CLASSES, 0)
    for p in PROBLEMS:
        print(f"{p:<12}" + "".join(f"{table[p][c]:>12}" for c in CLASSES))
        for c in CLASSES:
            total[c] += table[p][c]
    print(f"{'all':<12}" + "".join(f"{total[c]:>12}" for c in CLASSES))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
