"""The ``gpsaccel`` command: ``run`` (the main job), ``compare``, ``figures`` and the others.

Each sub-command is a small function here that calls the package; the work lives in the modules.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

import numpy as np

from gpsaccel import _validation as _v


def _dask_spec(value: str | None) -> str | None:
    """``--dask local|tcp://host:port`` as an executor spec of :mod:`gpsaccel.executors`."""
    if value is None:
        return None
    if value != "local" and not value.startswith("tcp://"):
        raise ValueError(f"--dask must be 'local' or tcp://host:port, got {value!r}")
    return "dask-local" if value == "local" else value


def _cmd_run(args: argparse.Namespace) -> int:
    """Simulate one realization on report 000's defaults, filter it, summarise, draw."""
    from gpsaccel.calibration.model import STATE_NAMES, STATE_UNITS
    from gpsaccel.figures import write_figures
    from gpsaccel.figures._shared import single_run

    single = single_run("000", args.seed)  # computed once: printed here, drawn below
    model, run, res = single
    names = zip(STATE_NAMES, STATE_UNITS, strict=True)
    print(f"gpsaccel run: one realization (seed {args.seed}, truth error-model), "
          f"{model.n_steps} accelerometer steps, {model.n_gps} GPS fixes")
    print(f"final estimates at t = {res.t_gps[-1]:g} s (truth, estimate ± 1σ):")
    for i, (name, unit) in enumerate(names):
        print(f"  {name:>2} = {run.x_gps[-1, i]: .6g} {unit:<5} x̂ = {res.x_hat[-1, i]: .6g} "
              f"± {res.sigma[-1, i]:.3g}")
    print(f"  p̂ = {run.p_c[-1] + res.x_hat[-1, 0]:.3f} m (true {run.p[-1]:.3f} m), "
          f"v̂ = {run.v_c[-1] + res.x_hat[-1, 1]:.4f} m/s (true {run.v[-1]:.4f} m/s)")
    with np.printoptions(precision=4, suppress=False):
        print(f"P at t = {res.t_gps[-1]:g} s:")
        print(res.P[-1])
    mc = _run_ensemble(args.runs, args.seed)  # prints the verdict table
    paths = write_figures(["000"], args.out, runs=args.runs, seed=args.seed,
                          results={"000": {"single": single, "mc": mc}})
    print(f"wrote {len(paths)} figures and index.html to {args.out}/")
    return 0


def _run_ensemble(runs: int | None, seed: int):
    """Report 000's Monte Carlo (its DEFAULT_RUNS, 10,000, unless ``runs``), the ensemble its
    figures draw; prints the verdict table and returns it."""
    import time

    from gpsaccel.figures import r000
    from gpsaccel.figures._shared import report_ensemble

    runs = r000.DEFAULT_RUNS if runs is None else runs
    t0 = time.perf_counter()
    mc = report_ensemble("000", runs, seed)
    print(f"\nMonte Carlo (report 000's experiment): {mc.n_runs:,} runs, truth error-model, "
          f"seed {seed}, {time.perf_counter() - t0:.2f} s")
    print(mc.consistency())
    return mc


def _cmd_montecarlo(args: argparse.Namespace) -> int:
    """The reports' Monte Carlo: verdict table, the report-style numbers, figures in --out."""
    import time

    from gpsaccel import plots
    from gpsaccel.calibration.model import CalibrationModel
    from gpsaccel.calibration.montecarlo import BLOCK_RUNS, monte_carlo, whole_blocks
    from gpsaccel.executors import resolve_executor

    resolved = resolve_executor(_dask_spec(args.dask))
    with resolved as ex:
        t0 = time.perf_counter()
        mc = monte_carlo(CalibrationModel(), args.runs, seed=args.seed, truth=args.truth,
                         chunk_size=args.chunk_size, executor=ex,
                         progress=not args.no_progress, max_lag=args.max_lag)
        seconds = time.perf_counter() - t0
    print(f"gpsaccel montecarlo: {mc.n_runs:,} runs, truth {mc.truth}, seed {mc.seed}, "
          f"{seconds:.2f} s ({resolved.description})")
    if args.chunk_size is not None and whole_blocks(args.chunk_size) != args.chunk_size:
        print(f"note: --chunk-size {args.chunk_size} rounded up to {whole_blocks(args.chunk_size)}, "
              f"a whole number of random blocks ({BLOCK_RUNS} runs drawn together)")
    print(mc.consistency(alpha=args.alpha))
    print()
    print(mc.summary())
    from gpsaccel._atomic import savefig

    args.out.mkdir(parents=True, exist_ok=True)
    figures = {
        "pave-minus-p": plots.pave_minus_p(mc, grid=False),
        "pave-minus-p-grid": plots.pave_minus_p(mc, grid=True),
        "ensemble-mean-error": plots.ensemble_mean_error(mc, sigma=True),
        "orthogonality": plots.orthogonality(mc),
    }
    for slug, fig in figures.items():
        savefig(fig, args.out / f"montecarlo-{mc.truth}-{slug}.png", dpi=110)
    print(f"wrote {len(figures)} figures to {args.out}/ (montecarlo-{mc.truth}-*.png)")
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    """Forms and files against the exact answer; with --sweep, the conditioning sweep(s) and figure."""
    from gpsaccel import plots
    from gpsaccel._atomic import savefig
    from gpsaccel.calibration.compare import compare, sweep
    from gpsaccel.calibration.forms import FORMS

    forms = [c for c in args.filters if c in FORMS]
    files = [c for c in args.filters if c not in FORMS]
    for c in files:
        if not c.endswith(".py") or not Path(c).is_file():
            raise ValueError(f"{c!r} is neither a filter form ({', '.join(FORMS)}) nor a .py file")
    if args.sweep:
        if files:
            raise ValueError("--sweep runs the built-in forms only (a student's file is written "
                             "for report 000's numbers, the sweep changes them)")
        sweeps = []
        for kind in args.sweep:
            sw = sweep(kind, forms=forms or None, seed=args.seed, truth=args.truth)
            print(sw, end="\n\n")
            sweeps.append(sw)
        args.out.mkdir(parents=True, exist_ok=True)
        path = args.out / f"compare-sweep-{'-'.join(args.sweep)}.png"
        savefig(plots.form_sweep(sweeps), path, dpi=110)
        print(f"wrote {path}")
        return 0
    from gpsaccel.check import student_filter

    filters = {Path(c).name: student_filter(c, timeout=args.timeout, repeat=args.repeat)
               for c in files}
    print(compare(*forms, seed=args.seed, truth=args.truth, filters=filters or None,
                  repeat=args.repeat))
    return 0


def _cmd_figures(args: argparse.Namespace) -> int:
    from gpsaccel.figures import available_reports, write_figures

    reports = available_reports() if args.report == "all" else [args.report]
    paths = write_figures(reports, args.out, runs=args.runs, seed=args.seed, progress=True)
    print(f"wrote {len(paths)} figures and index.html to {args.out}/")
    return 0


def _cmd_lessons(args: argparse.Namespace) -> int:
    """Execute the lessons top to bottom; with --html also render them (figures embedded); with
    --copy DIR only copy them (and their solutions) where a student edits them."""
    import time

    from gpsaccel.lessons import execute, lessons_dir, render_html, solutions_dir

    if args.copy is not None:
        return _copy_lessons(args.copy, only=args.only, html=args.html)
    paths = sorted(lessons_dir().glob("*.ipynb"))
    if not paths:
        raise ValueError(f"no lesson found in {lessons_dir()}")
    if args.only:
        paths = [p for p in paths if any(p.name.startswith(o) for o in args.only)]
    if not paths:
        raise ValueError(f"--only: no lesson in {lessons_dir()} starts with "
                         f"{' or '.join(args.only)}")
    total = 0.0
    for path in paths:
        t0 = time.perf_counter()
        if args.html:   # the solutions version, solutions collapsed (as on the docs site)
            solved = solutions_dir() / path.name
            target = render_html([solved if solved.exists() else path], args.html,
                                 runs=args.runs)[0]
        else:
            execute(path, runs=args.runs)
            target = None
        seconds = time.perf_counter() - t0
        total += seconds
        print(f"{path.name:<40} {seconds:6.1f} s" + (f"  -> {target}" if target else ""))
    print(f"{len(paths)} lessons executed in {total:.1f} s")
    return 0


def _copy_lessons(folder: Path, only=None, html=None) -> int:
    """``lessons --copy DIR``: the lessons and solutions/ into DIR; a file already there is kept."""
    from gpsaccel.lessons import copy_lessons

    if only or html is not None:
        raise ValueError("--copy copies every lesson and executes none: give it without "
                         "--only and --html")
    copied, kept = copy_lessons(folder)
    print(f"copied {len(copied)} notebooks into {folder}/"
          + (f"; kept {len(kept)} already there (your edits are never overwritten)" if kept else ""))
    print(f"open them with: gpsaccel lab {folder}")
    return 0


def _cmd_lab(args: argparse.Namespace) -> int:
    """Open the lessons in JupyterLab: DIR's copy, made first when DIR holds no notebook.

    JupyterLab replaces this process (exec), so Ctrl-C and its shutdown question reach it alone.
    """
    import os

    from gpsaccel.lessons import copy_lessons, lab_command

    cmd = lab_command(args.folder, port=args.port, browser=not args.no_browser)
    if not any(args.folder.glob("*.ipynb")):
        copied, _ = copy_lessons(args.folder)
        print(f"copied {len(copied)} notebooks into {args.folder}/", file=sys.stderr)
    print(" ".join(cmd), file=sys.stderr, flush=True)
    sys.stdout.flush()
    os.execv(cmd[0], cmd)
    return 0  # only where execv is replaced (the tests)


def _cmd_coop(args: argparse.Namespace) -> int:
    """Report 002: NEES/NIS of the LKF, EKF and UKF over Monte Carlo sets, and the course log."""
    from gpsaccel.coop.montecarlo import summary

    print(summary(n_runs=args.runs, n_sets=args.sets, seed=args.seed, alpha=args.alpha,
                  progress=not args.no_progress))
    return 0


def _cmd_ship(args: argparse.Namespace) -> int:
    """Report 004: RMSE and NEES of the ship's monorate, multirate and zeroed-gain filters."""
    from tqdm.auto import tqdm

    from gpsaccel.ship.comparison import compare_ship_filters, compare_wind

    # the two tables, each a Monte Carlo of its own: a bar of the two on stderr (a terminal only)
    with tqdm(total=2, desc="ship", unit="table", leave=False, disable=None) as bar:
        filters = compare_ship_filters(n_runs=args.runs, seed=args.seed)
        bar.update()
        wind = compare_wind(n_runs=args.runs, seed=args.seed)
        bar.update()
    print(filters)
    print()
    print(wind)
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    """Check students' submissions for one problem, each in a sandbox; table on stdout, --json
    for the details."""
    import time

    from gpsaccel import sandbox
    from gpsaccel._untrusted import json_safe
    from gpsaccel.check.batch import (
        Interrupted,
        appender,
        check_many,
        find_submissions,
        log_path,
        secret_seed,
        table,
        write_json,
    )
    from gpsaccel.check.own import is_file_spec, load_problem

    if is_file_spec(args.problem) and args.dask is not None:
        raise ValueError("--dask: a problem from a file of your own is known to this process "
                         "only, not to Dask's workers; leave out --dask (or register it in a "
                         "module the workers import)")
    args.problem = load_problem(args.problem)  # the instructor's file run, its problem registered
    # the notes and the count only: check_many expands the same raw paths itself, once
    files, notes = find_submissions(args.paths)
    for note in notes:
        print(note, file=sys.stderr)
    if not files:
        raise ValueError("paths: no .py file or submission folder was found")
    spec = _dask_spec(args.dask)
    if spec is None:
        spec = "processes"  # a process per check, even with --workers 1
    limits, backend, seed, settings = _check_settings(args, sandbox, secret_seed)
    print(f"sandbox: {backend}" + (" (bubblewrap not available: apt-get install bubblewrap)"
                                   if backend != "bwrap" and args.sandbox == "auto" else ""),
          file=sys.stderr)
    log = appender(log_path(args.json)) if args.json is not None else None
    from tqdm.auto import tqdm

    bar = tqdm(total=len(files), desc="check", unit="submission", leave=False,
               disable=None)  # on stderr, when it is a terminal

    def on_result(result: dict) -> None:
        bar.update()
        if log is not None:
            log(json_safe(result))

    t0 = time.perf_counter()
    try:
        with bar:
            results = check_many(args.paths, n_runs=args.runs, seed=seed, timeout=args.timeout,
                                 executor=spec, max_workers=args.workers, sandbox=backend,
                                 limits=limits, allow_gpsaccel=args.allow_gpsaccel,
                                 on_result=on_result, problem=args.problem,
                                 allow_unsafe_basic=args.allow_unsafe_basic)
    except Interrupted as exc:
        done = json_safe([r for r in exc.results if r is not None])
        if args.json is not None:  # first: the terminal may be gone
            write_json(done, args.json, interrupted=True, **settings)
        if done:
            print(table(done))
        if args.json is not None:
            print(f"wrote {args.json} ({len(done)} of {len(files)} checked)")
        print("gpsaccel check: interrupted", file=sys.stderr)
        return 130
    return _check_report(args, results, settings, time.perf_counter() - t0)


def _check_settings(args: argparse.Namespace, sandbox, secret_seed) -> tuple:  # noqa: ANN001
    """The limits, backend and seed of ``gpsaccel check``, and the settings its JSON records;
    a bad limit is named by its flag."""
    try:
        limits = sandbox.Limits(memory=int(args.memory * 2**20), time=args.timeout,
                                file_size=int(args.max_file_size * 2**20),
                                processes=args.max_processes,
                                output=int(args.max_output * 2**20))
    except ValueError as exc:
        raise ValueError(str(exc).replace("limits.", "--")) from None
    backend = sandbox.resolve_backend(args.sandbox)
    sandbox.refuse_unsafe_basic(backend, args.allow_unsafe_basic)
    # a class is graded on secret data unless a seed is given; the seed is in the JSON
    seed = secret_seed() if args.seed is None else args.seed
    settings = {"problem": args.problem, "runs": args.runs, "seed": seed,
                "seed_drawn": args.seed is None,
                "timeout": args.timeout,
                "sandbox": backend, "allow_gpsaccel": args.allow_gpsaccel,
                "limits": {k: v for k, v in vars(limits).items()}}
    return limits, backend, seed, settings


def _check_report(args: argparse.Namespace, results: list, settings: dict, seconds: float) -> int:
    """The JSON first (printing can fail), then the table and the one-line summary; exit 0 when
    every submission passed."""
    from gpsaccel._untrusted import json_safe
    from gpsaccel.check.batch import printable, table, write_json

    seed, backend = settings["seed"], settings["sandbox"]
    results = json_safe(results)  # a name that is not UTF-8 written \xNN, never a crash
    if args.json is not None:  # first: printing can fail (a closed terminal), the file must not
        path = write_json(results, args.json, **settings)
    if args.verbose:
        for r in results:
            print(printable(r["text"], keep_newlines=True), end="\n\n")
    print(table(results))
    runs = results[0]["details"].get("n_runs", args.runs) if results else args.runs
    print(f"{len(results)} submissions, problem {args.problem}, {runs} runs each (seed "
          f"{seed}{', drawn' if args.seed is None else ''}), sandbox {backend}, {seconds:.1f} s")
    if args.json is not None:
        print(f"wrote {path}")
    return 0 if all(r["passed"] for r in results) else 1


def _cmd_assignment(args: argparse.Namespace) -> int:
    """``otter assign`` a homework (the package's or a folder of the instructor's own): the
    student notebook and the autograder zip; with ``--roster`` one notebook per student carrying
    that student's variant.  Every flag is checked before the minutes of ``otter assign``."""
    import time

    from tqdm.auto import tqdm

    from gpsaccel.assignments.generate import generate, personalize, resolve
    from gpsaccel.assignments.grading import read_secret
    from gpsaccel.assignments.roster import read_roster

    name = resolve(args.name)
    if args.roster is None and args.secret_file is not None:
        raise ValueError("--secret-file: the secret makes per-student variants, which need "
                         "--roster (the students to write a notebook for)")
    students, secret = None, None
    if args.roster is not None:
        students = read_roster(args.roster)
        secret = read_secret(args.secret_file)
        if secret is None:
            raise ValueError("--roster: per-student variants need the instructor's secret "
                             "(--secret-file FILE, or $GPSACCEL_GRADING_SECRET)")
    t0 = time.perf_counter()
    from gpsaccel.assignments.gradescope import build

    with tqdm(total=2 + (len(students) if students else 0), desc=name, unit="step",
              leave=False, disable=None) as bar:  # on stderr, when it is a terminal
        bar.set_postfix_str("otter assign" + ("" if args.no_run_tests else " (testing the "
                                                                          "solution)"))
        try:
            g = generate(name, args.out, run_tests=not args.no_run_tests)
        except RuntimeError as exc:  # the master's own tests failed: otter's output says why
            print(f"gpsaccel assignment: error: {exc}", file=sys.stderr)
            return 1
        bar.update()
        if students is not None:
            assert secret is not None
            folder = personalize(name, g.student, [s.id for s in students], secret,
                                 g.out / "students", progress=bar)
        bar.set_postfix_str("Gradescope autograder")
        gradescope = build(name, g.out, students, secret)
        bar.update()
    print(f"hand out:  {g.student}\ngrade with: gpsaccel grade SUBMISSIONS --assignment "
          f"{args.name}\nGradescope: {gradescope} (scores computed outside the sandbox; "
          f"otter's own zip: {g.autograder.name})\nsolution:  {g.solution}")
    if students is not None:
        print(f"per student: {folder}/<id>/{name}.ipynb ({len(students)} students)")
    print(f"{time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_grade(args: argparse.Namespace) -> int:
    """Grade a class in the sandbox; grades.csv, feedback/, summary.csv/png in --out; with
    --roster the LMS gradebook files; the similarity report."""
    from gpsaccel.assignments import grade
    from gpsaccel.assignments.generate import resolve
    from gpsaccel.assignments.grading import default_out, read_secret
    from gpsaccel.assignments.roster import read_roster

    name = resolve(args.assignment)
    if args.dask is not None and name != args.assignment:
        raise ValueError("--dask: a homework from a folder of your own is known to this process "
                         "only, not to Dask's workers; leave out --dask")
    roster = read_roster(args.roster) if args.roster is not None else None
    secret = read_secret(args.secret_file)
    out = args.out if args.out is not None else default_out(args.submissions)
    grades = grade(args.submissions, name, out=out, jobs=args.jobs, timeout=args.timeout,
                   seed=args.seed, secret=secret, student=args.student, dask=args.dask,
                   sandbox=args.sandbox, progress=True)
    if not grades:
        raise ValueError(f"submissions: no student's folder or notebook in {args.submissions}")
    width = max(len(g.student) for g in grades)
    for g in grades:
        print(f"{g.student:<{width}}  {g.total:>5g} / {g.max_total:g}  {g.status:<13} "
              f"{g.seconds:5.1f} s")
    print(f"wrote {out / 'grades.csv'}, {out / 'grades.json'}, {out / 'feedback'}/, "
          f"{out / 'summary.csv'}, {out / 'summary.png'} (seed in {out / 'grading.json'})")
    from gpsaccel.assignments.classwide import after_grading

    for line in after_grading(Path(args.submissions), out, name, roster, secret,
                              similarity=not args.no_similarity):
        print(line)
    return 0


def _add_run(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="the main job: one realization, its filter and figures")
    p.add_argument("--seed", type=_v.flag_seed, default=0,
                   help="seed of the realization (default 0)")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="Monte Carlo runs for the ensemble figures (default: the report's)")
    p.add_argument("--out", type=_v.output_dir, default="out", help="folder for figures (out/)")
    p.set_defaults(func=_cmd_run)


def _add_compare(sub: argparse._SubParsersAction) -> None:
    from gpsaccel.calibration.simulation import TRUTHS

    p = sub.add_parser("compare", help="filter forms and students' files against the exact "
                                       "answer; --sweep: the conditioning sweeps and their figure")
    p.add_argument("filters", nargs="*", metavar="FORM|FILE",
                   help="standard, joseph, information, filterpy-information, square-root, or a "
                        "student's .py file defining kalman_filter(z) (default: every form)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.add_argument("--truth", choices=TRUTHS, default="error-model")
    p.add_argument("--repeat", type=_v.flag_int(minimum=1), default=3,
                   help="runs timed per filter (best kept)")
    p.add_argument("--timeout", type=_v.flag_float(0.0, open_min=True), default=60.0,
                   help="limit (s) per student file")
    p.add_argument("--sweep", action="append", choices=("prior", "gps"), default=None,
                   help="prior: M0 x 1 .. 1e12; gps: V x 1 .. 1e-12; give both for one figure "
                        "with both (written to --out)")
    p.add_argument("--out", type=_v.output_dir, default="out", help="folder for the sweep figure")
    p.set_defaults(func=_cmd_compare)


def _add_figures(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("figures", help="write every figure of a report as PNG + index.html")
    p.add_argument("--report", default="all", help="000, 001, 003, ... or all (default)")
    p.add_argument("--out", type=_v.output_dir, default="out")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="Monte Carlo runs (report's default)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.set_defaults(func=_cmd_figures)


def _add_lessons(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("lessons", help="execute the Jupyter lessons; --html DIR renders them")
    p.add_argument("--html", type=_v.output_dir, default=None,
                   help="folder for the rendered HTML (the solutions versions, solutions collapsed)")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="ensemble size for every lesson (GPSACCEL_LESSON_RUNS; default: each "
                        "lesson's full size)")
    p.add_argument("--only", nargs="*", default=None, metavar="NN",
                   help="only the lessons whose file name starts with these (e.g. 03 06)")
    p.add_argument("--copy", type=_v.output_dir, default=None, metavar="DIR",
                   help="copy the lessons and their solutions/ into DIR to edit (existing files "
                        "are kept) and execute nothing")
    p.set_defaults(func=_cmd_lessons)



def _add_lab(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("lab", help="open the lessons in JupyterLab (a copy in DIR, made first "
                                   "when DIR holds none)")
    p.add_argument("folder", nargs="?", type=_v.output_dir, default="gpsaccel-lessons",
                   metavar="DIR", help="folder of your copy (default gpsaccel-lessons)")
    p.add_argument("--port", type=_v.flag_int(minimum=1, maximum=65535), default=None,
                   help="port of the server (default: JupyterLab's, 8888)")
    p.add_argument("--no-browser", action="store_true", help="print the address, open no browser")
    p.set_defaults(func=_cmd_lab)


def _add_coop(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("coop", help="cooperative localization (report 002): NEES/NIS table")
    p.add_argument("--runs", type=_v.flag_int(minimum=1), default=50,
                   help="truth runs per set (default 50)")
    p.add_argument("--sets", type=_v.flag_int(minimum=1), default=5,
                   help="independent sets (default 5)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.add_argument("--alpha", type=_v.flag_probability, default=0.05,
                   help="test level (default 0.05)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar (stderr)")
    p.set_defaults(func=_cmd_coop)


def _add_montecarlo(sub: argparse._SubParsersAction) -> None:
    from gpsaccel.calibration.simulation import TRUTHS

    p = sub.add_parser("montecarlo", help="the reports' Monte Carlo validation, with verdicts")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=10_000,
                   help="ensemble size (default 10000)")
    p.add_argument("--truth", choices=TRUTHS, default="error-model",
                   help="error-model (report 000) or kinematic (reports 001/003)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.add_argument("--chunk-size", type=_v.flag_int(minimum=1), default=None,
                   help="runs per task (default 1000, rounded up to whole blocks of 1000); "
                        "does not change the result")
    p.add_argument("--dask", default=None, metavar="local|tcp://host:port",
                   help="run on a Dask LocalCluster or a running scheduler (optional extra)")
    p.add_argument("--alpha", type=_v.flag_probability, default=0.01,
                   help="family-wise false-alarm rate of the verdict table (default 0.01)")
    p.add_argument("--max-lag", type=_v.flag_int(minimum=0), default=50,
                   help="residual products kept and tested up to this lag, in GPS epochs "
                        "(default 50; memory grows with it, linearly)")
    p.add_argument("--out", type=_v.output_dir, default="out", help="folder for figures (out/)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_montecarlo)


def _add_ship(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ship", help="the ship (report 004): RMSE/NEES of monorate, multirate, "
                                    "zeroed gain; wind states")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=200,
                   help="Monte Carlo runs (default 200)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.set_defaults(func=_cmd_ship)


def _problem_flag(value: str) -> str:
    """--problem: a registered problem's name, or FILE.py:NAME (the file exists; it is run by
    the command, not by the parser)."""
    from gpsaccel import registry
    from gpsaccel.check.own import is_file_spec

    if is_file_spec(value):
        if not Path(value.rpartition(":")[0]).is_file():
            raise argparse.ArgumentTypeError(f"{value.rpartition(':')[0]} is not a file "
                                             f"(expected FILE.py:NAME)")
        return value
    if value not in registry.problems():
        raise argparse.ArgumentTypeError(f"invalid choice: {value!r} (choose from "
                                         f"{', '.join(registry.problems())}, or FILE.py:NAME)")
    return value


def _add_check(sub: argparse._SubParsersAction) -> None:
    from gpsaccel import registry

    p = sub.add_parser("check", help="check students' homework files (" +
                       ", ".join(registry.problems()) + ")")
    p.add_argument("paths", nargs="+", type=Path,
                   help="submission files, or folders whose every top-level .py file or "
                        "sub-folder is one submission")
    p.add_argument("--problem", type=_problem_flag, default="calibration",
                   metavar="NAME|FILE.py:NAME",
                   help="the problem (default calibration), one of gpsaccel.registry's: " +
                        "; ".join(f"{name}: {registry.entry(name).title}"
                                  for name in registry.problems()) +
                        "; or FILE.py:NAME, a problem of your own defined in FILE.py "
                        "(check.Problem.linear(NAME, ...))")
    p.add_argument("--json", type=_v.output_file, default=None, metavar="FILE",
                   help="write every finding and number to FILE (e.g. results.json)")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="realizations per check (default: the problem's, see gpsaccel.check)")
    p.add_argument("--seed", type=_v.flag_seed, default=None,
                   help="seed of the realizations (default: drawn with secrets, so no student "
                        "can precompute the answers; recorded in --json to reproduce a verdict)")
    p.add_argument("--timeout", type=_v.flag_float(0.0, open_min=True), default=60.0,
                   help="time limit per submission, s (default 60)")
    p.add_argument("--workers", type=_v.flag_int(minimum=1), default=None,
                   help="parallel local processes (default: one per CPU; 1 = one at a time)")
    p.add_argument("--dask", default=None, metavar="local|tcp://host:port",
                   help="check on a Dask LocalCluster or a running scheduler instead")
    p.add_argument("--sandbox", choices=("auto", "bwrap", "basic"), default="auto",
                   help="isolation of each submission: bwrap (bubblewrap namespaces), basic "
                        "(limits, scrubbed environment, private folder) or auto (bwrap when it "
                        "works; default)")
    p.add_argument("--memory", type=_v.flag_float(256.0), default=1024, metavar="MIB",
                   help="address space per student process, MiB (default 1024)")
    p.add_argument("--max-output", type=_v.flag_float(0.0, open_min=True), default=16,
                   metavar="MIB",
                   help="printed output per submission, MiB (default 16)")
    p.add_argument("--max-file-size", type=_v.flag_float(0.0, open_min=True), default=64,
                   metavar="MIB",
                   help="largest file a submission may write, MiB (default 64)")
    p.add_argument("--max-processes", type=_v.flag_int(minimum=1), default=64,
                   help="processes per submission at once (default 64)")
    p.add_argument("--allow-gpsaccel", action="store_true",
                   help="let submissions import gpsaccel (by default an import is the finding "
                        "uses-checker)")
    p.add_argument("--allow-unsafe-basic", action="store_true",
                   help="accept --sandbox basic (or auto without bubblewrap) when not run as "
                        "root, where it cannot keep a student's code from your files and "
                        "processes (docs/sandbox.md)")
    p.add_argument("-v", "--verbose", action="store_true", help="print every report in full")
    p.set_defaults(func=_cmd_check)


class _Registered:
    """argparse choices read from :mod:`gpsaccel.registry` when first needed (a parse or a
    help text), so building the parser imports no homework module."""

    def __init__(self, names: Callable[[], tuple[str, ...]]) -> None:
        self._names = names

    def __contains__(self, name: object) -> bool:  # or a folder of the instructor's own
        return name in self._names() or (isinstance(name, str) and Path(name).is_dir())

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())


def _registered_assignments() -> tuple[str, ...]:
    from gpsaccel import registry

    return registry.assignments()


def _add_assignment(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("assignment", help="otter assign a homework: student notebook + autograder")
    p.add_argument("name", choices=_Registered(_registered_assignments), metavar="NAME",
                   help="the homework: %(choices)s, or a folder of your own holding NAME.ipynb "
                        "(the master) and graded.py (its questions)")
    p.add_argument("--out", type=_v.output_dir, required=True, help="folder to write (replaced)")
    p.add_argument("--no-run-tests", action="store_true",
                   help="do not execute the solution against its tests first (faster)")
    p.add_argument("--roster", type=Path, default=None,
                   help="the class: one student id a line, or a CSV file with an id column "
                        "(docs/grading.md): one notebook each, with its variant")
    p.add_argument("--secret-file", type=Path, default=None,
                   help="the instructor's secret (default $GPSACCEL_GRADING_SECRET)")
    p.set_defaults(func=_cmd_assignment)


def _add_grade(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("grade", help="grade a class of homework notebooks in the sandbox")
    p.add_argument("submissions", type=Path,
                   help="LMS export: a folder per student (or one .ipynb per student)")
    p.add_argument("--assignment", required=True, choices=_Registered(_registered_assignments),
                   metavar="NAME", help="the homework: %(choices)s, or a folder of your own "
                                        "holding NAME.ipynb and graded.py")
    p.add_argument("--roster", type=Path, default=None,
                   help="the class roster (a CSV file with id, name, email, sis_id, ... "
                        "columns): write canvas.csv, moodle.csv and Gradescope's CSV files too")
    p.add_argument("--no-similarity", action="store_true",
                   help="skip the similarity report (similarity.csv, similarity.html)")
    p.add_argument("--out", type=_v.output_dir, default=None,
                   help="folder for grades.csv, feedback/, summary (default SUBMISSIONS-grades)")
    p.add_argument("--jobs", type=_v.flag_int(minimum=1), default=None,
                   help="notebooks graded at once (default: CPUs, at most 4)")
    p.add_argument("--timeout", type=_v.flag_float(0.0, open_min=True), default=120.0,
                   help="time limit of one notebook's box, s (default 120)")
    p.add_argument("--seed", type=_v.flag_seed, default=None,
                   help="seed of the fresh data (default: random; recorded in grading.json)")
    p.add_argument("--secret-file", type=Path, default=None,
                   help="the instructor's secret for per-student variants (default "
                        "$GPSACCEL_GRADING_SECRET; none: no variants)")
    p.add_argument("--student", default=None, help="regrade this student only")
    p.add_argument("--dask", default=None,
                   help="grade on Dask: 'dask-local' or a scheduler address tcp://host:port")
    p.add_argument("--sandbox", choices=("auto", "bwrap", "basic"), default="auto",
                   help="isolation of each notebook (default auto: bwrap where it works)")
    p.set_defaults(func=_cmd_grade)


#: The sub-commands in the order ``gpsaccel --help`` lists them; each function adds one parser.
SUBCOMMANDS = (
    _add_run,
    _add_compare,
    _add_figures,
    _add_lessons,
    _add_lab,
    _add_coop,
    _add_montecarlo,
    _add_ship,
    _add_check,
    _add_assignment,
    _add_grade,
)


def build_parser() -> argparse.ArgumentParser:
    from gpsaccel._version import __version__

    parser = _Parser(prog="gpsaccel", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for add in SUBCOMMANDS:  # a new sub-command: an _add_NAME function and one line above
        add(sub)
    return parser


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error: ``gpsaccel check: error: argument --runs: must be ...``.

    Every flag's ``type=`` is a validator of :mod:`gpsaccel._validation` (``flag_int``,
    ``flag_float``, ``flag_seed``, ``flag_probability``, ``output_dir``, ``output_file``), so a bad
    number or an unusable output path is refused here, exit 2, before any work; sub-commands
    added later should use the same ones.
    """

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


#: The extra that installs what a sub-command imports beyond the core (pyproject.toml).
_EXTRAS = {"lessons": "lessons", "lab": "lab", "assignment": "grading", "grade": "grading",
           "montecarlo": "dask", "check": "dask"}


def main(argv: Sequence[str] | None = None) -> int:
    """Parse, run, and turn the expected failures into one line on stderr.

    Exit codes: 0 success; 1 a sub-command's own "not all passed" (``check``); 2 bad input
    (ValueError) or a file-system error (OSError: disk full, permission, ...); 130 interrupted
    (Ctrl-C), after which no half-written file is left (:mod:`gpsaccel._atomic`).
    """
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0) or a refused flag (2): returned, for callers in-process
        return exc.code if isinstance(exc.code, int) else 2
    except KeyboardInterrupt:
        print("gpsaccel: interrupted", file=sys.stderr)
        return 130
    try:
        return int(args.func(args) or 0)
    except ModuleNotFoundError as exc:  # an optional part not installed: name the extra
        extra = _EXTRAS.get(args.command, "test")
        print(f"gpsaccel {args.command}: error: {exc.msg}: the module {exc.name} is not "
              f"installed (pip install 'gpsaccel[{extra}]')", file=sys.stderr)
        return 2
    except ValueError as exc:  # bad input: one clear line, not a traceback
        print(f"gpsaccel {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # the file system said no: say what and where, in one line
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        print(f"gpsaccel {args.command}: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"gpsaccel {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
