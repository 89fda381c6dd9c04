"""The reports' experiments: ``run``, ``compare``, ``figures``, ``coop``, ``montecarlo``, ``ship``.

Each command is a small function that calls the package; its parser is built by its ``add_…``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from gpsaccel import _validation as _v
from gpsaccel.cli._flags import dask_spec


def _cmd_run(args: argparse.Namespace) -> int:
    """Simulate one realization on report 000's defaults, filter it, summarise, draw."""
    import numpy as np

    from gpsaccel.calibration.model import STATE_NAMES, STATE_UNITS
    from gpsaccel.figures import write_figures
    from gpsaccel.figures.runs import single_run

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
    from gpsaccel.figures.runs import report_ensemble

    runs = r000.DEFAULT_RUNS if runs is None else runs
    t0 = time.perf_counter()
    mc = report_ensemble("000", runs, seed)
    print(f"\nMonte Carlo (report 000's experiment): {mc.n_runs:,} runs, truth error-model, "
          f"seed {seed}, {time.perf_counter() - t0:.2f} s")
    print(mc.consistency())
    return mc


def _cmd_montecarlo(args: argparse.Namespace) -> int:
    """The reports' Monte Carlo: verdict table, the report-style numbers; with --out, figures."""
    import time

    from gpsaccel.calibration.model import CalibrationModel
    from gpsaccel.calibration.montecarlo import BLOCK_RUNS, monte_carlo, whole_blocks
    from gpsaccel.executors import resolve_executor

    resolved = resolve_executor(dask_spec(args.dask))
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
    if args.out is None:  # the verdicts are the answer; figures cost more than the ensemble
        print("\nno figures drawn: --out DIR writes them (montecarlo-TRUTH-*.png)")
        return 0
    paths = _montecarlo_figures(mc, args.out)
    print(f"wrote {len(paths)} figures to {args.out}/ (montecarlo-{mc.truth}-*.png)")
    return 0


def _montecarlo_figures(mc, out: Path) -> list[Path]:  # noqa: ANN001
    """The ensemble's figures, each drawn, written whole and let go before the next."""
    from gpsaccel import plots
    from gpsaccel._atomic import savefig

    out.mkdir(parents=True, exist_ok=True)
    figures = {
        "pave-minus-p": lambda: plots.pave_minus_p(mc, grid=False),
        "pave-minus-p-grid": lambda: plots.pave_minus_p(mc, grid=True),
        "ensemble-mean-error": lambda: plots.ensemble_mean_error(mc, sigma=True),
        "orthogonality": lambda: plots.orthogonality(mc),
    }
    return [savefig(draw(), out / f"montecarlo-{mc.truth}-{slug}.png", dpi=110)
            for slug, draw in figures.items()]


def _cmd_compare(args: argparse.Namespace) -> int:
    """Forms and files against the exact answer; with --sweep, the conditioning sweep(s) and figure."""
    from gpsaccel import plots
    from gpsaccel._atomic import savefig
    from gpsaccel.calibration.compare import compare, sweep
    from gpsaccel.kalman.factory import FORMS

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


def add_run(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="the main job: one realization, its filter and figures")
    p.add_argument("--seed", type=_v.flag_seed, default=0,
                   help="seed of the realization (default 0)")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="Monte Carlo runs for the ensemble figures (default: the report's)")
    p.add_argument("--out", type=_v.output_dir, default="out", help="folder for figures (out/)")
    p.set_defaults(func=_cmd_run)


def add_compare(sub: argparse._SubParsersAction) -> None:
    from gpsaccel.calibration.truths import TRUTHS

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


def add_figures(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("figures", help="write every figure of a report as PNG + index.html")
    p.add_argument("--report", default="all", help="000, 001, 003, ... or all (default)")
    p.add_argument("--out", type=_v.output_dir, default="out")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=None,
                   help="Monte Carlo runs (report's default)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.set_defaults(func=_cmd_figures)


def add_coop(sub: argparse._SubParsersAction) -> None:
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


def add_montecarlo(sub: argparse._SubParsersAction) -> None:
    from gpsaccel.calibration.truths import TRUTHS

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
    p.add_argument("--out", type=_v.output_dir, default=None, metavar="DIR",
                   help="draw the ensemble's four figures into DIR (default: none, the table only)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_montecarlo)


def add_ship(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("ship", help="the ship (report 004): RMSE/NEES of monorate, multirate, "
                                    "zeroed gain; wind states")
    p.add_argument("--runs", type=_v.flag_int(minimum=2), default=200,
                   help="Monte Carlo runs (default 200)")
    p.add_argument("--seed", type=_v.flag_seed, default=0)
    p.set_defaults(func=_cmd_ship)
