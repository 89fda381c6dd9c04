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
    args = p.parse_args(argv)
    if args.command == "measure":
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


if __name__ == "__main__":
    raise SystemExit(main())
