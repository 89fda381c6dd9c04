"""A class of 100 by-hand 200 Hz calibration filters through ``gpsaccel check``, on this machine.

The class: 100 files copied from the by-hand fixtures of tests/submissions that step at 200 Hz
(covariance, Joseph and information forms, and mistakes of the catalogue), checked by
:func:`gpsaccel.classrun.check_many` with local processes (one per CPU), as the CLI does.
Prints the wall time of the whole class at the checker's default n_runs, and, side by side in
the same run, a 10-file slice at the default and at the former default of 200 runs (the ratio is
what fewer runs buys).

``--warm-boxes`` instead checks N files (default 10) with every box started cold and warm
(``check_many(..., warm_boxes=True)``: forked from a zygote that has imported numpy, scipy.stats
and filterpy), alternated ``--repeats`` R times (default 2) in one run: CPU seconds of this process
and its children (the zygote's start and every warm box included), wall seconds, the load average
before and after each row, and whether both gave the same results.

``--shared`` checks three classes of N files (default 10): calibration's correct files, its
mistaken ones (whose diagnosis reads every candidate filter of the catalogue) and coop's EKF/LKF
fixtures, with the part every file shares (report 000's catalogue and its candidate filters,
built and not run; coop's nominal trajectory) built once before the boxes
(:meth:`gpsaccel.check.problem.Problem.prepare`, as ``gpsaccel check`` does) and, as before it
was shared, again in every file's process (:func:`rebuilt_per_file`), alternated ``--repeats``
R times in one run: CPU seconds of this process and its children per file, wall seconds, the
load average before and after each row, and whether both gave byte-identical results (every
field but the seconds).

Usage: python benchmarks/check_class.py [--files N]
       python benchmarks/check_class.py --warm-boxes [--files N] [--repeats R]
       python benchmarks/check_class.py --shared [--files N] [--repeats R]
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

from gpsaccel.check.problems.calibration import DEFAULT_RUNS
from gpsaccel.classrun import check_many

HERE = Path(__file__).resolve().parents[1] / "tests" / "submissions"
BY_HAND_200HZ = ["correct_covariance.py", "correct_joseph.py", "correct_information.py",
                 "mutant_phi_sign.py", "mutant_m0_order.py", "mutant_std_as_variance.py",
                 "mutant_x0_total_state.py", "mutant_first_update_skipped.py",
                 "mutant_w_value.py", "mutant_returns_a_priori.py"]


def make_class(folder: Path, n: int) -> list[Path]:
    paths = []
    for i in range(n):
        src = HERE / BY_HAND_200HZ[i % len(BY_HAND_200HZ)]
        dst = folder / f"student{i:03d}_{src.name}"
        shutil.copyfile(src, dst)
        paths.append(dst)
    return paths


def timed(paths: list[Path], n_runs: int) -> tuple[float, int]:
    t0 = time.perf_counter()
    results = check_many(paths, n_runs=n_runs, seed=0, timeout=120, executor="processes")
    return time.perf_counter() - t0, sum(r["passed"] for r in results)


def cpu() -> float:
    """CPU seconds of this process and its reaped children."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def warm_vs_cold(n: int, repeats: int) -> None:
    """The class checked with cold and with warm boxes, alternated (module docstring)."""
    with tempfile.TemporaryDirectory(prefix="gpsaccel-class-") as tmp:
        paths = make_class(Path(tmp), n)
        check_many(paths[:1], n_runs=2, seed=0, timeout=120)  # this process's imports, once
        print(f"{os.cpu_count()} CPUs; {n} by-hand 200 Hz filters ({len(BY_HAND_200HZ)} kinds), "
              f"n_runs = {DEFAULT_RUNS}, one process per CPU")
        print(f"{'boxes':<7}{'run':>4}{'wall s':>9}{'CPU s':>9}{'CPU s/file':>12}{'load':>14}")
        rows: dict[bool, list[float]] = {False: [], True: []}
        seen: dict[bool, list] = {}
        for r in range(repeats):
            for warm in (False, True):
                load0 = os.getloadavg()[0]
                c0, t0 = cpu(), time.perf_counter()
                results = check_many(paths, n_runs=DEFAULT_RUNS, seed=0, timeout=120,
                                     warm_boxes=warm)
                wall, spent = time.perf_counter() - t0, cpu() - c0
                rows[warm].append(spent)
                seen[warm] = [(x["passed"], x["codes"]) for x in results]
                print(f"{'warm' if warm else 'cold':<7}{r + 1:>4}{wall:>9.1f}{spent:>9.1f}"
                      f"{spent / n:>12.2f}{load0:>7.1f} ->{os.getloadavg()[0]:>4.1f}")
        cold, warm_cpu = statistics.median(rows[False]), statistics.median(rows[True])
        print(f"median CPU s per file: cold {cold / n:.2f}, warm {warm_cpu / n:.2f} "
              f"({warm_cpu / cold:.2f} of cold); same verdicts and codes: "
              f"{seen[False] == seen[True]}")


CORRECT = BY_HAND_200HZ[:3]
WRONG = BY_HAND_200HZ[3:]
COOP = ["correct_both.py", "correct_ekf_closed_form.py", "correct_lkf_solve_ivp.py",
        "mutant_process_noise.py", "mutant_no_state_wrap.py", "mutant_lkf_relinearized.py",
        "mutant_std_as_variance.py", "mutant_two_mistakes.py", "mutant_euler.py",
        "mutant_jacobian_point.py"]


@contextmanager
def rebuilt_per_file() -> Iterator[None]:
    """The checker as it was before a class shared its part: nothing prepared before the boxes,
    report 000's catalogue made again at each use and its candidate filters built again by
    every diagnosis, coop's nominal trajectory integrated again by every file's process (each
    forks from this one, so it inherits the change)."""
    from gpsaccel.calibration import mistakes as cat
    from gpsaccel.calibration.model import CalibrationModel
    from gpsaccel.check import linear
    from gpsaccel.check.problems import calibration as wf
    from gpsaccel.check.problems import coop

    saved = (wf._default_catalogue, wf._default_candidate_filters,
             linear.LinearProblem.prepare, coop.CoopProblem.prepare)
    wf._default_catalogue = lambda: cat.CalibrationCatalogue(CalibrationModel())  # type: ignore
    wf._default_candidate_filters = lambda m: linear.candidate_filters(  # type: ignore
        wf._default_catalogue(), m)
    linear.LinearProblem.prepare = coop.CoopProblem.prepare = (  # type: ignore[method-assign]
        lambda self: None)
    try:
        yield
    finally:
        wf._default_catalogue, wf._default_candidate_filters = saved[:2]
        linear.LinearProblem.prepare = saved[2]  # type: ignore[method-assign]
        coop.CoopProblem.prepare = saved[3]  # type: ignore[method-assign]


def _clear_shared() -> None:
    """This process holds no shared part: each row's class builds its own (or none)."""
    from gpsaccel.check.problems import calibration as wf
    from gpsaccel.coop import model

    wf._default_catalogue.cache_clear()
    wf._default_candidate_filters.cache_clear()
    model._NOMINALS.clear()


def _verdicts(results: list[dict]) -> str:
    """The results as JSON, every field but the seconds (the comparison of the two rows)."""
    def strip(r: dict) -> dict:
        r = {k: v for k, v in r.items() if k != "seconds"}
        r["details"] = {k: v for k, v in r.get("details", {}).items() if "seconds" not in k}
        return r
    return json.dumps([strip(r) for r in results], sort_keys=True)


def parts() -> None:
    """CPU seconds of each piece, in this process: what is shared (built once) and what a
    mistaken file's diagnosis still runs after its box (the candidates' first covariances: no
    data in them, but a filter's result, so never kept while a box runs)."""
    from gpsaccel.check import linear_diagnosis as ld
    from gpsaccel.check.linear import COMBINED
    from gpsaccel.check.problems import calibration as wf
    from gpsaccel.coop.model import CoopModel

    _clear_shared()
    t0 = time.process_time()
    catalogue = wf._default_catalogue()
    catalogue.catalogue()
    t1 = time.process_time()
    built = wf._default_candidate_filters(COMBINED)
    t2 = time.process_time()
    ld.Candidates(catalogue, COMBINED, built).head(ld.HEAD)
    t3 = time.process_time()
    CoopModel().nominal()
    t4 = time.process_time()
    print(f"shared, once per class: report 000's catalogue {t1 - t0:.3f} CPU s, its "
          f"{len(built.filters)} candidate filters {t2 - t1:.3f}, coop's nominal trajectory "
          f"{t4 - t3:.3f}; after each mistaken calibration file's box: every candidate's first "
          f"{ld.HEAD} covariances {t3 - t2:.3f}")
    _clear_shared()


def shared_vs_per_file(n: int, repeats: int) -> None:
    """The classes checked with their shared part built once and per file, alternated (module
    docstring)."""
    kinds = {"calibration, correct": ("calibration", HERE, CORRECT),
             "calibration, mistaken": ("calibration", HERE, WRONG),
             "coop, mixed": ("coop", HERE / "coop", COOP)}
    with tempfile.TemporaryDirectory(prefix="gpsaccel-class-") as tmp:
        classes = {}
        for k, (problem, src, names) in kinds.items():
            folder = Path(tmp) / problem / k.split(", ")[1]
            folder.mkdir(parents=True)
            classes[k] = (problem, [shutil.copyfile(src / names[i % len(names)],
                                                    folder / f"s{i:03d}_{names[i % len(names)]}")
                                    for i in range(n)])
            check_many(classes[k][1][:1], n_runs=2, seed=0, timeout=300, problem=problem)
        parts()
        print(f"{os.cpu_count()} CPUs; {n} files per class: calibration's by-hand 200 Hz "
              f"filters (correct: {len(CORRECT)} kinds; mistaken: {len(WRONG)}, n_runs = "
              f"{DEFAULT_RUNS}), coop's EKF/LKF fixtures ({len(COOP)} kinds, 3 correct, its "
              f"default n_runs); one process per CPU, a process per file")
        print(f"{'class':<23}{'shared part':<13}{'run':>4}{'wall s':>9}{'CPU s':>9}"
              f"{'CPU s/file':>12}{'load':>14}")
        rows: dict[tuple[str, bool], list[float]] = {}
        seen: dict[tuple[str, bool], str] = {}
        for r in range(repeats):
            for k, (problem, paths) in classes.items():
                for shared in (False, True):
                    _clear_shared()
                    load0 = os.getloadavg()[0]
                    with nullcontext() if shared else rebuilt_per_file():
                        c0, t0 = cpu(), time.perf_counter()
                        results = check_many(paths, seed=0, timeout=300, problem=problem)
                        wall, spent = time.perf_counter() - t0, cpu() - c0
                    rows.setdefault((k, shared), []).append(spent)
                    seen[k, shared] = _verdicts(results)
                    print(f"{k:<23}{'once' if shared else 'per file':<13}{r + 1:>4}"
                          f"{wall:>9.1f}{spent:>9.1f}{spent / n:>12.3f}{load0:>7.1f} ->"
                          f"{os.getloadavg()[0]:>4.1f}", flush=True)
        for k in classes:
            before = statistics.median(rows[k, False]) / n
            after = statistics.median(rows[k, True]) / n
            print(f"{k}: median CPU s per file: per file {before:.3f}, once {after:.3f} "
                  f"({after / before:.2f} of before); byte-identical results: "
                  f"{seen[k, False] == seen[k, True]}")


def main(argv: list[str]) -> int:
    if "--shared" in argv:
        shared_vs_per_file(int(argv[argv.index("--files") + 1]) if "--files" in argv else 10,
                           int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 2)
        return 0
    if "--warm-boxes" in argv:
        warm_vs_cold(int(argv[argv.index("--files") + 1]) if "--files" in argv else 10,
                     int(argv[argv.index("--repeats") + 1]) if "--repeats" in argv else 2)
        return 0
    n = int(argv[argv.index("--files") + 1]) if "--files" in argv else 100
    with tempfile.TemporaryDirectory(prefix="gpsaccel-class-") as tmp:
        paths = make_class(Path(tmp), n)
        print(f"{os.cpu_count()} CPUs; {n} by-hand 200 Hz filters "
              f"({len(BY_HAND_200HZ)} kinds, 3 correct)")
        secs, passed = timed(paths, DEFAULT_RUNS)
        print(f"whole class, n_runs = {DEFAULT_RUNS} (default): {secs:6.1f} s wall "
              f"({secs / 60:.2f} min), {passed} passed")
        part = paths[:10]
        s_small, _ = timed(part, DEFAULT_RUNS)
        s_big, _ = timed(part, 200)
        print(f"10-file slice, side by side: n_runs = {DEFAULT_RUNS}: {s_small:6.1f} s; "
              f"n_runs = 200: {s_big:6.1f} s; ratio {s_big / s_small:.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
