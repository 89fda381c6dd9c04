"""What ``gpsaccel assignment NAME --out DIR`` costs, and how much of it is otter's run of the
solution against every test (what ``--no-run-tests`` skips): CPU (children included: otter's
kernel) and wall, each homework with and without the run, alternated, medians of ``--repeats``;
and the command as docs/grading.md gives it, with ``--roster`` (:data:`STUDENTS` ids) and
``--secret-file``, which writes one notebook per student besides.  docs/grading.md quotes the
differences."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import _cpu

HOMEWORKS = ("calibration", "ship")

#: Students on the roster of the ``--roster`` case.
STUDENTS = 8


def _roster(tmp: str) -> list[str]:
    """The flags of the per-student case, their files written into ``tmp``."""
    (Path(tmp) / "roster.txt").write_text("".join(f"s{i:03d}\n" for i in range(STUDENTS)))
    secret = Path(tmp) / "secret"
    secret.write_text("b" * 32)
    os.chmod(secret, 0o600)
    return ["--roster", "roster.txt", "--secret-file", "secret"]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args(argv)
    print(f"start: {_cpu.load()}")
    rows = []
    for name in HOMEWORKS:
        got: dict[str, list[_cpu.Sample]] = {"with": [], "without": [], "roster": []}
        for _ in range(args.repeats):
            for case in got:
                with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-") as tmp:
                    extra = {"with": [], "without": ["--no-run-tests"]}.get(case) or _roster(tmp)
                    s = _cpu.run([sys.executable, "-m", "gpsaccel.cli", "assignment", name,
                                  "--out", "hw", *extra], cwd=tmp)
                if s.returncode != 0:
                    raise SystemExit(f"{name} {extra}: exit {s.returncode}\n{s.stdout}")
                got[case].append(s)
        (cw, ww), (co, wo) = _cpu.median(got["with"]), _cpu.median(got["without"])
        cr, wr = _cpu.median(got["roster"])
        rows.append(f"| {name} | {cw:.1f} | {co:.1f} | {cw - co:.1f} | {ww:.1f} | {wo:.1f} | "
                    f"{ww - wo:.1f} | {cr:.1f} | {wr:.1f} |")
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print("| homework | CPU s | CPU s, --no-run-tests | the test run, CPU s | wall s | "
          "wall s, --no-run-tests | the test run, wall s | "
          f"CPU s, --roster ({STUDENTS} students) --secret-file | wall s, --roster |\n"
          "|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
