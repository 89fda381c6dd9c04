"""Grading throughput: ``gpsaccel grade`` (the sandbox) side by side with ``otter run``, same class.

The class: calibration notebooks made from the master (honest, and with the mistakes of
tests/assignments: a wrong Φ element, a summed NEES), N for the sandboxed grader and M of the
same for ``otter run`` with the autograder zip of ``otter assign`` (one ``otter run`` per notebook,
as the former grader ran it, two at a time).  Both run in this process's children, so the CPU
seconds are theirs (RUSAGE_CHILDREN); the wall time is at two notebooks at once.  The goal of
issue 19: 100 calibration notebooks in under 5 minutes on a 2-core machine.

Usage: python benchmarks/grading.py [--notebooks N] [--otter M]
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gpsaccel.assignments import generate, grade  # noqa: E402
from tests.assignments.conftest import write_variant  # noqa: E402
from tests.assignments.test_grading import MEAN, PHI  # noqa: E402

KINDS = [[], [(PHI, PHI.replace("-dt**2", "+dt**2"))], [(MEAN, MEAN.replace("np.mean", "np.sum"))]]


def make_class(folder: Path, n: int) -> list[Path]:
    return [write_variant("calibration", folder / f"student {i:03d}" / "calibration.ipynb",
                          KINDS[i % len(KINDS)]) for i in range(n)]


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def sandboxed(folder: Path, out: Path) -> tuple[float, float, list]:
    c0, t0 = cpu(), time.perf_counter()
    grades = grade(folder, "calibration", out=out, jobs=2, seed=1, secret=b"benchmark-secret-16b")
    return time.perf_counter() - t0, cpu() - c0, grades


def otter(notebooks: list[Path], zip_path: Path, work: Path) -> tuple[float, float, list[int]]:
    def one(i_nb):
        i, nb = i_nb
        out = work / f"otter{i}"
        out.mkdir()
        return subprocess.run([sys.executable, "-m", "otter", "run", "--no-logo", "-a",
                               str(zip_path), "-o", str(out), str(nb)], capture_output=True,
                              timeout=900).returncode

    c0, t0 = cpu(), time.perf_counter()
    with ThreadPoolExecutor(max_workers=2) as pool:
        codes = list(pool.map(one, enumerate(notebooks)))
    return time.perf_counter() - t0, cpu() - c0, codes


def main(argv: list[str]) -> int:
    n = int(argv[argv.index("--notebooks") + 1]) if "--notebooks" in argv else 20
    m = int(argv[argv.index("--otter") + 1]) if "--otter" in argv else 3
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-grade-") as tmp:
        tmp = Path(tmp)
        nbs = make_class(tmp / "class", n)
        print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; calibration "
              f"notebooks ({len(KINDS)} kinds)")
        wall, cpu_s, grades = sandboxed(tmp / "class", tmp / "grades")
        totals = sorted({g.total for g in grades})
        print(f"{'grader':<22}{'notebooks':>10}{'wall s':>9}{'CPU s':>9}{'CPU s/nb':>10}"
              f"{'100 nb, min':>13}")
        print(f"{'gpsaccel grade':<22}{n:>10}{wall:>9.1f}{cpu_s:>9.1f}{cpu_s / n:>10.2f}"
              f"{wall / n * 100 / 60:>13.1f}   totals {totals}")
        if m:
            dist = generate("calibration", tmp / "dist", run_tests=False)
            wall_o, cpu_o, codes = otter(nbs[:m], dist.autograder, tmp)
            print(f"{'otter run (2 at once)':<22}{m:>10}{wall_o:>9.1f}{cpu_o:>9.1f}"
                  f"{cpu_o / m:>10.2f}{wall_o / m * 100 / 60:>13.1f}   exit codes {codes}")
            print(f"ratio (CPU per notebook, otter / sandbox): {cpu_o / m / (cpu_s / n):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
