"""Grading throughput: ``gpsaccel grade`` (the sandbox) side by side with ``otter run``, same class.

The class: calibration notebooks made from the master (honest, and with the mistakes of
tests/assignments: a wrong Φ element, a summed NEES), every student's filter (q2's
``kalman_filter.py``) written with filterpy's ``KalmanFilter``, as students do; N for the sandboxed
grader and M of the same for ``otter run`` with the autograder zip of ``otter assign`` (one ``otter
run`` per notebook, as the former grader ran it, two at a time).  CPU seconds count this process
and its children (RUSAGE_SELF + RUSAGE_CHILDREN: the forked notebook processes, the boxes, otter's
processes); the wall time is at two notebooks at once.  The sandboxed grader's CPU is broken down
into the boxes' (the students' code: every ``gpsaccel.sandbox.run``, measured in the process that
calls it) and the grader's own (the rest: parsing, preparing, checking, writing; the goal of issue
27 is under 2 CPU s per notebook).  The load average is printed before and after each row.  The
goal of issue 19: 100 calibration notebooks in under 5 minutes on a 2-core machine.

``--cold`` adds a row for the grader as it was before the parent's warm-up
(:func:`gpsaccel.assignments.grading.warm` made a no-op: every notebook's process imports IPython's
transformer and the problems again), in the same run.

``--profile`` instead breaks one calibration notebook's CPU down, side by side in one run (the
median of ``--repeats`` R, alternated): a box that imports nothing (bwrap, Python, the runner;
the runner imports numpy), one that imports scipy.stats, one gpsaccel; the notebook's own box
with and without the module's audit hook; the box of the file question (q2); and the grader's
own CPU for the notebook, cold and warm.

``--warm-boxes`` instead grades the same class with every box started cold (exec'd, as by
default) and warm (``grade(..., warm_boxes=True)``: forked from a zygote that has imported numpy,
scipy.stats and filterpy), alternated ``--repeats`` R times in one run: CPU seconds of this process
and its children (the zygotes are this process's children, reaped when the class ends, so their
start and every warm box count), wall seconds, the load average before and after each row, and
whether both gave the same grades.

Usage: python benchmarks/grading.py [--notebooks N] [--otter M] [--cold]
       python benchmarks/grading.py --profile [--repeats R]
       python benchmarks/grading.py --warm-boxes [--notebooks N] [--repeats R]
"""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import nbformat  # noqa: E402
import numpy as np  # noqa: E402

from gpsaccel import sandbox as sb  # noqa: E402
from gpsaccel.assignments import boxcalls, generate, grading, scoring  # noqa: E402
from gpsaccel.assignments import notebook as nbm  # noqa: E402
from gpsaccel.classrun import grade  # noqa: E402
from tests.assignments.conftest import write_variant  # noqa: E402
from tests.assignments.test_grading import MEAN, PHI  # noqa: E402

KINDS = [[], [(PHI, PHI.replace("-dt**2", "+dt**2"))], [(MEAN, MEAN.replace("np.mean", "np.sum"))]]
#: The student's filter of q2, written with filterpy (tests/submissions/correct_filterpy.py).
FILTERPY = (ROOT / "tests" / "submissions" / "correct_filterpy.py").read_text(encoding="utf-8")
WRITEFILE = "%%writefile kalman_filter.py\n"


def make_class(folder: Path, n: int) -> list[Path]:
    """n notebooks, of the kinds in turn, each with q2's filter written with filterpy."""
    out = []
    for i in range(n):
        path = write_variant("calibration", folder / f"student {i:03d}" / "calibration.ipynb",
                             KINDS[i % len(KINDS)])
        nb = nbformat.read(str(path), as_version=4)
        cells = [c for c in nb.cells if c.cell_type == "code" and c.source.startswith(WRITEFILE)]
        assert len(cells) == 1, "q2's %%writefile cell moved: update the benchmark's class"
        cells[0].source = WRITEFILE + FILTERPY
        nbformat.write(nb, str(path))
        out.append(path)
    return out


def cpu() -> float:
    """CPU seconds of the reaped children (the processes they reaped included)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def total_cpu() -> float:
    """CPU seconds of this process and its reaped children."""
    return self_cpu() + cpu()


#: CPU seconds of every box run since the start (added by each notebook's forked process).
BOX_CPU = mp.get_context("fork").Value("d", 0.0)


def _counting_boxes():  # noqa: ANN202 - a context that counts every box's CPU into BOX_CPU
    """``gpsaccel.sandbox.run`` wrapped: the children's CPU of the calling process around each
    box (bwrap, the runner, the student's processes) is added to :data:`BOX_CPU`."""
    import contextlib

    real = sb.run

    def run(*args, **kwargs):
        c0 = cpu()
        try:
            return real(*args, **kwargs)
        finally:
            spent = cpu() - c0
            with BOX_CPU.get_lock():
                BOX_CPU.value += spent

    @contextlib.contextmanager
    def counting():
        sb.run = run
        try:
            yield
        finally:
            sb.run = real

    return counting()


def sandboxed(folder: Path, out: Path, cold: bool = False
              ) -> tuple[float, float, float, list]:
    """Wall s, CPU s (all), the boxes' CPU s, the grades of grading the class."""
    warm = grading.warm
    if cold:
        grading.warm = lambda name: None
    try:
        with _counting_boxes():
            b0 = BOX_CPU.value
            c0, t0 = total_cpu(), time.perf_counter()
            grades = grade(folder, "calibration", out=out, jobs=2, seed=1,
                           secret=b"benchmark-secret-16b")
            wall, spent = time.perf_counter() - t0, total_cpu() - c0
            boxes = BOX_CPU.value - b0
    finally:
        grading.warm = warm
    return wall, spent, boxes, grades


def self_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _box_cpu(sub, calls) -> float:
    """Children's CPU seconds of one box (bwrap, the runner and whatever it starts)."""
    limits = sb.Limits(memory=grading.BOX_MEMORY, time=grading.TIMEOUT,
                       processes=grading.BOX_PROCESSES)
    c0 = cpu()
    box = sb.run(sub, calls, limits, backend="auto", allow_gpsaccel=True)
    if box.failure is not None:
        raise RuntimeError(f"the profile's box failed: {box.failure} {box.detail}")
    return cpu() - c0


def _notebook_cpu(nb_path: Path, cold: bool) -> tuple[float, float]:
    """(grader's own CPU, boxes' CPU) of grading one notebook in a forked process, as
    :func:`grade` does (cold: without the parent's warm-up, which this process has done)."""
    import multiprocessing as mp

    def child(conn) -> None:
        if cold:  # undo the warm-up in this child: what it imports is imported again
            import sys as _sys
            for m in [m for m in _sys.modules if m.startswith(("IPython", "gpsaccel.check.problems.tracker",
                                                               "traitlets", "pygments"))]:
                del _sys.modules[m]
        s0, c0 = self_cpu(), cpu()
        grading.grade_notebook(nb_path, "calibration", "s", 1, b"benchmark-secret-16b")
        conn.send((self_cpu() - s0, cpu() - c0))

    recv, send = mp.get_context("fork").Pipe(duplex=False)
    p = mp.get_context("fork").Process(target=child, args=(send,))
    p.start()
    send.close()  # a child that dies gives EOFError here, not a wait for ever
    out = recv.recv()
    p.join()
    return out


def profile(repeats: int) -> None:
    """One calibration notebook's CPU, part by part (module docstring)."""
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-prof-") as tmp:
        tmp = Path(tmp)
        nb_path = make_class(tmp / "class", 1)[0]
        grading.warm("calibration")
        qs = grading.questions_of("calibration")
        variant = grading.student_variant("calibration", "s", b"benchmark-secret-16b")
        run = boxcalls.prepare(nbm.read(nb_path), variant)
        reads = [r for q in qs for r in q.reads(scoring.Draw(
            scoring.question_seed(1, "calibration", q.name, "s"), variant))]
        calls = boxcalls.calls(len(run.cells), reads)
        source = nbm.module_source(run, reads)
        # the module's one call of its audit hook, a line of its own (notebook.py's prelude)
        lines = source.split("\n")
        unhooked = "\n".join(line for line in lines if not line.startswith("_gpsaccel_guard("))
        assert len(unhooked.split("\n")) == len(lines) - 1, \
            "the notebook module's guard call is not one line of its own: update the profile"
        parts: dict[str, tuple] = {}
        one = [sb.Call("f", (np.zeros(1),), (sb.Output("y", (1,)),))]
        for label, head in (("box: bwrap, Python, runner, numpy", ""),
                            ("box: import scipy.stats", "import scipy.stats\n"),
                            ("box: import gpsaccel", "import gpsaccel\n")):
            (tmp / label).mkdir()
            (tmp / label / "s.py").write_text(head + "def f(x):\n    return x\n")
            parts[label] = (sb.load_submission(tmp / label / "s.py", "f"), one)
        for label, text in (("notebook box (cells and reads)", source),
                            ("notebook box, no audit hook", unhooked)):
            (tmp / label).mkdir()
            (tmp / label / "notebook.py").write_text(text)
            parts[label] = (sb.load_submission(tmp / label / "notebook.py", "_gpsaccel_cell"),
                            calls)
        times: dict[str, list[float]] = {k: [] for k in
                                         [*parts, "file box (q2)", "grader, cold", "grader, warm",
                                          "notebook, all boxes"]}
        for _ in range(repeats):
            for label, (sub, c) in parts.items():
                times[label].append(_box_cpu(sub, c))
            for cold in (True, False):
                own, boxes = _notebook_cpu(nb_path, cold)
                times["grader, cold" if cold else "grader, warm"].append(own)
                if not cold:
                    times["notebook, all boxes"].append(boxes)
        times["file box (q2)"] = [a - b for a, b in zip(times["notebook, all boxes"],
                                                        times["notebook box (cells and reads)"],
                                                        strict=True)]
        print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}, sandbox "
              f"{sb.resolve_backend('auto')}; median of {repeats}, CPU s")
        for label, v in times.items():
            print(f"  {label:<34}{statistics.median(v):>7.2f}")


def otter(notebooks: list[Path], zip_path: Path, work: Path) -> tuple[float, float, list[int]]:
    def one(i_nb):
        i, nb = i_nb
        out = work / f"otter{i}"
        out.mkdir()
        # otter run refuses a notebook without its assignment's name (exit 1 before it runs a
        # cell): the name a student notebook of otter assign carries
        copy = nbformat.read(str(nb), as_version=4)
        copy.metadata["otter"] = {"assignment_name": "calibration"}
        nbformat.write(copy, str(out / nb.name))
        return subprocess.run([sys.executable, "-m", "otter", "run", "--no-logo", "-a",
                               str(zip_path), "-o", str(out), str(out / nb.name)],
                              capture_output=True, timeout=900).returncode

    c0, t0 = total_cpu(), time.perf_counter()
    with ThreadPoolExecutor(max_workers=2) as pool:
        codes = list(pool.map(one, enumerate(notebooks)))
    return time.perf_counter() - t0, total_cpu() - c0, codes


def warm_vs_cold(n: int, repeats: int) -> None:
    """The class graded with cold and with warm boxes, alternated (module docstring)."""
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-warm-") as tmp:
        tmp = Path(tmp)
        make_class(tmp / "class", n)
        grading.warm("calibration")  # the parent's own warm-up, outside both rows
        print(f"{os.cpu_count()} CPUs, sandbox {sb.resolve_backend('auto')}; {n} filled "
              f"calibration notebooks ({len(KINDS)} kinds, q2 with filterpy), 2 at once")
        print(f"{'boxes':<7}{'run':>4}{'wall s':>9}{'CPU s':>9}{'CPU s/nb':>10}{'load':>14}"
              f"   totals")
        rows: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
        seen: dict[bool, list] = {}
        for r in range(repeats):
            for warm in (False, True):
                load0 = os.getloadavg()[0]
                c0, t0 = total_cpu(), time.perf_counter()
                grades = grade(tmp / "class", "calibration", out=tmp / f"g{r}{warm}", jobs=2,
                               seed=1, secret=b"benchmark-secret-16b", warm_boxes=warm)
                wall, spent = time.perf_counter() - t0, total_cpu() - c0
                rows[warm].append((wall, spent))
                seen[warm] = [(g.student, g.total, g.status, g.codes) for g in grades]
                print(f"{'warm' if warm else 'cold':<7}{r + 1:>4}{wall:>9.1f}{spent:>9.1f}"
                      f"{spent / n:>10.2f}{load0:>7.1f} ->{os.getloadavg()[0]:>4.1f}   "
                      f"{sorted({g.total for g in grades})}")
        cold = statistics.median(c for _, c in rows[False])
        warm_cpu = statistics.median(c for _, c in rows[True])
        print(f"median CPU s per notebook: cold {cold / n:.2f}, warm {warm_cpu / n:.2f} "
              f"({warm_cpu / cold:.2f} of cold); median wall s: cold "
              f"{statistics.median(w for w, _ in rows[False]):.1f}, warm "
              f"{statistics.median(w for w, _ in rows[True]):.1f}; same grades, codes and "
              f"statuses: {seen[False] == seen[True]}")


def main(argv: list[str]) -> int:
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # a timeout still removes the class
    if "--profile" in argv:
        profile(int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 3)
        return 0
    if "--warm-boxes" in argv:
        warm_vs_cold(int(argv[argv.index("--notebooks") + 1]) if "--notebooks" in argv else 8,
                     int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 2)
        return 0
    n = int(argv[argv.index("--notebooks") + 1]) if "--notebooks" in argv else 20
    m = int(argv[argv.index("--otter") + 1]) if "--otter" in argv else 3
    with tempfile.TemporaryDirectory(prefix="gpsaccel-bench-grade-") as tmp:
        tmp = Path(tmp)
        nbs = make_class(tmp / "class", n)
        print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; calibration "
              f"notebooks ({len(KINDS)} kinds)")
        print(f"{'grader':<22}{'notebooks':>10}{'wall s':>9}{'CPU s':>9}{'CPU s/nb':>10}"
              f"{'boxes/nb':>10}{'grader/nb':>11}{'100 nb, min':>13}")
        for label, cold in ([("gpsaccel grade, cold", True)] if "--cold" in argv else []) + \
                [("gpsaccel grade", False)]:
            load0 = os.getloadavg()[0]
            wall, cpu_s, boxes, grades = sandboxed(tmp / "class", tmp / f"grades-{cold}", cold)
            totals = sorted({g.total for g in grades})
            print(f"{label:<22}{n:>10}{wall:>9.1f}{cpu_s:>9.1f}{cpu_s / n:>10.2f}"
                  f"{boxes / n:>10.2f}{(cpu_s - boxes) / n:>11.2f}"
                  f"{wall / n * 100 / 60:>13.1f}   totals {totals}  load {load0:.1f} -> "
                  f"{os.getloadavg()[0]:.1f}")
        if m:
            dist = generate("calibration", tmp / "dist", run_tests=False)
            wall_o, cpu_o, codes = otter(nbs[:m], dist.autograder, tmp)
            print(f"{'otter run (2 at once)':<22}{m:>10}{wall_o:>9.1f}{cpu_o:>9.1f}"
                  f"{cpu_o / m:>10.2f}{wall_o / m * 100 / 60:>13.1f}   exit codes {codes}  load "
                  f"{os.getloadavg()[0]:.1f}")
            print(f"ratio (CPU per notebook, otter / sandbox): {cpu_o / m / (cpu_s / n):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
