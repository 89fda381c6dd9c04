"""Run every benchmark script in this folder (``make bench``), one subprocess each, in name order.

Each script prints its own table; this runner adds a header per script and its wall time, and
exits non-zero if any script failed.  Arguments after ``--only`` restrict to scripts whose file
name contains one of them (``python benchmarks/run.py --only montecarlo``).  ``--markdown DIR``
(``make bench`` gives ``docs/benchmarks``) also writes each script's output to ``DIR/NAME.txt``
under a line saying when, where and at what load it was measured; the documentation's benchmark
page is made of these files, so no table there is typed by hand.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

#: Scripts run on their own, not by ``make bench``: suite_cost.py runs the whole test suite;
#: lessons.py runs notebooks for many minutes and writes docs/benchmarks/lessons.txt itself (--write);
#: suite_per_test.py is a pytest plugin and the table of two of its runs.
SEPARATE = ("suite_cost.py", "lessons.py", "suite_per_test.py")


def _header(script: Path, seconds: float) -> str:
    import datetime
    import os
    import platform

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"`python benchmarks/{script.name}`, {datetime.date.today().isoformat()}, Python "
            f"{platform.python_version()}, {os.cpu_count()} CPUs, load average {load:.1f} at the "
            f"end, {seconds:.0f} s wall")


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parent
    markdown = None
    if "--markdown" in argv:
        i = argv.index("--markdown")
        markdown = Path(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
        markdown.mkdir(parents=True, exist_ok=True)
    only = argv[argv.index("--only") + 1:] if "--only" in argv else []
    scripts = sorted(p for p in here.glob("*.py") if p.name != Path(__file__).name
                     and not p.name.startswith("_") and p.name not in SEPARATE)
    if only:
        scripts = [p for p in scripts if any(o in p.name for o in only)]
    failed = []
    for script in scripts:
        print(f"=== {script.name} " + "=" * max(0, 70 - len(script.name)), flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, str(script)], cwd=here.parent, text=True,
                              stdout=subprocess.PIPE if markdown else None)
        rc = proc.returncode
        seconds = time.perf_counter() - t0
        if markdown is not None:
            print(proc.stdout, end="", flush=True)
            if rc == 0:
                (markdown / f"{script.stem}.txt").write_text(
                    _header(script, seconds) + "\n" + proc.stdout, encoding="utf-8")
        print(f"--- {script.name}: exit {rc}, {seconds:.1f} s wall\n", flush=True)
        if rc != 0:
            failed.append(script.name)
    if failed:
        print(f"failed: {', '.join(failed)}")
        return 1
    print(f"{len(scripts)} benchmark script(s) done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
