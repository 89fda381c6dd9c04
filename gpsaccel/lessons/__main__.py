"""``python -m gpsaccel.lessons release|measure|check [NN ...]``: the lessons' maintenance."""

from __future__ import annotations

from gpsaccel.lessons.measurement import measure
from gpsaccel.lessons.numbers import number_problems
from gpsaccel.lessons.release import masters, release, released


def main(argv: list[str] | None = None) -> int:
    """``python -m gpsaccel.lessons release|measure|check [NN ...]``."""
    import argparse

    p = argparse.ArgumentParser(prog="python -m gpsaccel.lessons", description=main.__doc__)
    p.add_argument("command", choices=("release", "measure", "check"),
                   help="release: write lessons/ and lessons/solutions/ from lessons/masters/; "
                        "measure: run each master at full size (time, printed text, answers), then "
                        "release; check: exit 1 if a released file differs from its master, or a "
                        "number its text states is neither printed by it nor given")
    p.add_argument("only", nargs="*", metavar="NN", help="only the masters starting with these")
    p.add_argument("--runs", type=int, default=None,
                   help="measure: runs per ensemble (default: each lesson's full size)")
    p.add_argument("--max-load", type=float, default=None, metavar="L",
                   help="measure: refuse to start when the 1-minute load average is above L "
                        "(default: the number of CPUs); the time it writes into each lesson's "
                        "header is what a student is told to expect")
    args = p.parse_args(argv)
    if args.command == "measure":
        busy = _busy(args.max_load)
        if busy:
            p.error(busy)
        for stem, s in measure(args.only, runs=args.runs).items():
            print(f"{stem:<40} {s:6.1f} s")
    if args.command in ("release", "measure"):
        print(f"wrote {len(release(args.only))} notebooks")
        return 0
    stale = [str(t) for m in masters(args.only) for t, text in released(m).items()
             if not t.exists() or t.read_text(encoding="utf-8") != text]
    print("\n".join(stale) or "every released lesson matches its master")
    numbers = [p for m in masters(args.only) for p in number_problems(m)]
    print("\n".join(numbers) or "every number the lessons state is tagged and printed, or given")
    return 1 if stale or numbers else 0


def _busy(max_load: float | None) -> str:
    """Why the machine is too busy to measure on ("" if it is not): a lesson measured at load 20
    told students "about 6 minutes" for a 30-second lesson."""
    import os

    limit = float(os.cpu_count() or 1) if max_load is None else max_load
    if not limit > 0:
        return f"--max-load must be > 0, got {max_load!r}"
    load = os.getloadavg()[0]
    if load <= limit:
        return ""
    return (f"the machine is busy (1-minute load {load:.1f} > {limit:g}): the times measure writes "
            f"into the lessons' headers and docs/lessons.md would be this load's; measure on a "
            f"quiet machine, or raise --max-load to accept it")


if __name__ == "__main__":
    raise SystemExit(main())
