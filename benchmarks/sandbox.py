"""What the homework checker's sandbox costs per check, per backend, side by side in one run.

A trivial submission (``f(z)`` returns ``z``) is run in a box with 1 call and with 200 calls (a
check's usual number of runs), alternating the backends, 7 times each; the table shows the median
wall time, and, as the floor any checker that runs students in a separate Python pays, a bare
``python -I -S -c "import numpy"`` (one BLAS thread, as in a box).  The sandbox's overhead is a
box's time minus that floor.

``--before DIR`` also times the sandbox of an earlier version, in the same run, alternated with
this one: DIR holds that version's ``gpsaccel/sandbox/`` and ``_runner.py`` (e.g.
``git archive main gpsaccel | tar -x -C DIR``), loaded as a module of its own.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gpsaccel import sandbox as sb
from gpsaccel.sandbox.confinement import _site_dirs

REPEATS = 7


def _bare() -> float:
    code = f"import sys; sys.path.extend({_site_dirs()!r}); import numpy"
    t = time.perf_counter()
    subprocess.run([sys.executable, "-I", "-S", "-B", "-c", code], check=True,
                   env={"OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    return time.perf_counter() - t


def _load(root: str):  # noqa: ANN202 - a module
    spec = importlib.util.spec_from_file_location(
        "sandbox_before", Path(root) / "gpsaccel" / "check" / "sandbox.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", metavar="DIR", default=None,
                        help="a folder holding an earlier gpsaccel/sandbox/ to compare")
    args = parser.parse_args(argv)
    versions = {"now": sb}
    if args.before:
        versions = {"before": _load(args.before), "now": sb}
    backends = ["basic"] + (["bwrap"] if sb.bwrap_path() else [])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "student.py"
        path.write_text("def f(z):\n    return z\n")
        z = np.zeros((151, 2))
        times: dict[str, list[float]] = {"bare python + numpy": []}
        for v in versions:
            for b in backends:
                for n in (1, 200):
                    times[f"{v}: {b}, {n} call(s)"] = []
        for _ in range(REPEATS):
            times["bare python + numpy"].append(_bare())
            for b in backends:
                for n in (1, 200):
                    for v, m in versions.items():
                        sub = m.load_submission(path, "f")
                        calls = [m.Call("f", (z,), (m.Output("z", (151, 2)),))] * n
                        t = time.perf_counter()
                        box = m.run(sub, calls, backend=b)
                        times[f"{v}: {b}, {n} call(s)"].append(time.perf_counter() - t)
                        assert box.failure is None, box
    floor = statistics.median(times["bare python + numpy"])
    print(f"{'':30} {'median ms':>10} {'overhead ms':>12}   ({REPEATS} repeats, alternated)")
    for name, ts in times.items():
        med = statistics.median(ts)
        over = "" if name.startswith("bare") else f"{1e3 * (med - floor):12.0f}"
        print(f"{name:30} {1e3 * med:10.0f} {over:>12}")


if __name__ == "__main__":
    main()
