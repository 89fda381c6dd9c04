"""What ``gpsaccel assignment NAME --out DIR`` costs, and how much of it is otter's run of the
solution against every test (what ``--no-run-tests`` skips): CPU (children included: otter's
kernel) and wall, each homework with and without the run, alternated, medians of ``--repeats``.
docs/grading.md quotes the difference."""

from __future__ import annotations

import argparse
import sys
import tempfile

import _cpu

HOMEWORKS = ("calibration", "ship")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args(argv)
    print(f"start: {_cpu.load()}")
    rows = []
    for name in HOMEWORKS:
        got: dict[str, list[_cpu.Sample]] = {"with": [], "without": []}
        for _ in range(args.repeats):
            for case, extra in (("with", []), ("without", ["--no-run-tests"])):
                with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-") as tmp:
                    s = _cpu.run([sys.executable, "-m", "gpsaccel.cli", "assignment", name,
                                  "--out", "hw", *extra], cwd=tmp)
                if s.returncode != 0:
                    raise SystemExit(f"{name} {extra}: exit {s.returncode}\n{s.stdout}")
                got[case].append(s)
        (cw, ww), (co, wo) = _cpu.median(got["with"]), _cpu.median(got["without"])
        rows.append(f"| {name} | {cw:.1f} | {co:.1f} | {cw - co:.1f} | {ww:.1f} | {wo:.1f} | "
                    f"{ww - wo:.1f} |")
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print("| homework | CPU s | CPU s, --no-run-tests | the test run, CPU s | wall s | "
          "wall s, --no-run-tests | the test run, wall s |\n|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
