"""Run every benchmark script in this folder (``make bench``), one subprocess each, in name order.

Each script prints its own table; this runner adds a header per script and its wall time, and
exits non-zero if any script failed.  Arguments after ``--only`` restrict to scripts whose file
name contains one of them (``python benchmarks/run.py --only montecarlo``).
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parent
    only = argv[argv.index("--only") + 1:] if "--only" in argv else []
    scripts = sorted(p for p in here.glob("*.py") if p.name != Path(__file__).name
                     and not p.name.startswith("_"))
    if only:
        scripts = [p for p in scripts if any(o in p.name for o in only)]
    failed = []
    for script in scripts:
        print(f"=== {script.name} " + "=" * max(0, 70 - len(script.name)), flush=True)
        t0 = time.perf_counter()
        rc = subprocess.call([sys.executable, str(script)], cwd=here.parent)
        print(f"--- {script.name}: exit {rc}, {time.perf_counter() - t0:.1f} s wall\n", flush=True)
        if rc != 0:
            failed.append(script.name)
    if failed:
        print(f"failed: {', '.join(failed)}")
        return 1
    print(f"{len(scripts)} benchmark script(s) done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
