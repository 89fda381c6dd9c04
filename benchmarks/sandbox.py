"""What the homework checker's sandbox costs per check, per backend, in CPU seconds, side by side.

A trivial submission (``f(z)`` returns ``z``) is run in a box with 1 call and with 200 calls (a
check's usual number of runs), alternating the backends, ``--repeats`` times each (7).  Each box is
measured in CPU seconds, children included: the box's processes (bwrap, the runner: this process's
children, RUSAGE_CHILDREN) plus the supervising checker's own (RUSAGE_SELF).  The floor any
checker that runs students in a separate Python pays is a bare ``python -I -S -c "import numpy"``
(one BLAS thread, as in a box), measured the same way.  The sandbox's overhead is a box's CPU
minus that floor.  CPU, not wall time: on a shared machine the wall time measures the other
users (an earlier wall-clock version printed negative overheads under load); the load average
before and after is printed with the table.

``--before DIR`` also measures an earlier version (DIR holds its ``gpsaccel/``, e.g. ``git archive
main gpsaccel | tar -x -C DIR``): this script is run again in a child Python with DIR first on
its path, right after this one, and its table printed below (a version with the sandbox layer,
``gpsaccel.sandbox``).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from gpsaccel import sandbox as sb
from gpsaccel.sandbox.confinement import _site_dirs  # the box's own path, for the numpy floor


def cpu() -> float:
    """CPU seconds of this process and its reaped children."""
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


def _bare() -> float:
    code = f"import sys; sys.path.extend({_site_dirs()!r}); import numpy"
    c0 = cpu()
    subprocess.run([sys.executable, "-I", "-S", "-B", "-c", code], check=True,
                   env={"OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    return cpu() - c0


def measure(repeats: int) -> None:
    backends = ["basic"] + (["bwrap"] if sb.bwrap_path() else [])
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "student.py"
        path.write_text("def f(z):\n    return z\n")
        z = np.zeros((151, 2))
        times: dict[str, list[float]] = {"bare python + numpy": []}
        for b in backends:
            for n in (1, 200):
                times[f"{b}, {n} call(s)"] = []
        for _ in range(repeats):
            times["bare python + numpy"].append(_bare())
            for b in backends:
                for n in (1, 200):
                    sub = sb.load_submission(path, "f")
                    calls = [sb.Call("f", (z,), (sb.Output("z", (151, 2)),))] * n
                    c0 = cpu()
                    box = sb.run(sub, calls, sb.Limits(), b)
                    times[f"{b}, {n} call(s)"].append(cpu() - c0)
                    assert box.failure is None, box
    floor = statistics.median(times["bare python + numpy"])
    print(f"{sb.__name__}: {os.cpu_count()} CPUs, load average {load0:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after; median of {repeats} (alternated), CPU ms children "
          f"included")
    print(f"{'':30} {'CPU ms':>8} {'overhead ms':>12} {'ratio':>6}")
    for name, ts in times.items():
        med = statistics.median(ts)
        over = "" if name.startswith("bare") else f"{1e3 * (med - floor):12.0f} {med / floor:6.2f}"
        print(f"{name:30} {1e3 * med:8.0f} {over}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--before", metavar="DIR", default=None,
                        help="a folder holding an earlier gpsaccel/ to measure after this one")
    parser.add_argument("--repeats", type=int, default=7, help="boxes per row (default 7)")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    if args.before and not (Path(args.before) / "gpsaccel" / "__init__.py").is_file():
        parser.error(f"--before: {args.before} holds no gpsaccel/ package")
    measure(args.repeats)
    if args.before:
        print(f"\nbefore ({args.before}):", flush=True)
        env = {**os.environ, "PYTHONPATH": os.path.abspath(args.before)}
        subprocess.run([sys.executable, __file__, "--repeats", str(args.repeats)], check=True,
                       env=env, cwd=args.before)


if __name__ == "__main__":
    main()
