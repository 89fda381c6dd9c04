"""What the homework checker's sandbox costs per check, per backend, side by side in one run.

A trivial submission (``f(z)`` returns ``z``) is run in a box with 1 call and with 200 calls (a
check's usual number of runs), alternating the backends, 7 times each; the table shows the median
wall time, and, as the floor any checker that runs students in a separate Python pays, a bare
``python -I -S -c "import numpy"`` (one BLAS thread, as in a box).  The sandbox's overhead is a
box's time minus that floor.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gpsaccel.check import sandbox as sb

REPEATS = 7


def _bare() -> float:
    code = f"import sys; sys.path.extend({sb._site_dirs()!r}); import numpy"
    t = time.perf_counter()
    subprocess.run([sys.executable, "-I", "-S", "-B", "-c", code], check=True,
                   env={"OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    return time.perf_counter() - t


def main() -> None:
    backends = ["basic"] + (["bwrap"] if sb.bwrap_path() else [])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "student.py"
        path.write_text("def f(z):\n    return z\n")
        sub = sb.load_submission(path, "f")
        z = np.zeros((151, 2))
        calls = {n: [sb.Call("f", (z,), (sb.Output("z", (151, 2)),))] * n for n in (1, 200)}
        times: dict[str, list[float]] = {"bare python + numpy": []}
        for b in backends:
            for n in calls:
                times[f"{b}, {n} call(s)"] = []
        for _ in range(REPEATS):
            times["bare python + numpy"].append(_bare())
            for b in backends:
                for n, c in calls.items():
                    t = time.perf_counter()
                    box = sb.run(sub, c, backend=b)
                    times[f"{b}, {n} call(s)"].append(time.perf_counter() - t)
                    assert box.failure is None, box
    floor = statistics.median(times["bare python + numpy"])
    print(f"{'':28} {'median ms':>10} {'overhead ms':>12}   ({REPEATS} repeats, alternated)")
    for name, ts in times.items():
        med = statistics.median(ts)
        over = "" if name.startswith("bare") else f"{1e3 * (med - floor):12.0f}"
        print(f"{name:28} {1e3 * med:10.0f} {over:>12}")


if __name__ == "__main__":
    main()
