"""``gpsaccel check``: students' submissions for one problem, each in a sandbox."""

from __future__ import annotations

import argparse
from pathlib import Path

from gpsaccel import _validation as _v
from gpsaccel.cli._flags import BOXES, add_boxes, dask_spec


def _cmd_check(args: argparse.Namespace) -> int:
    """Check students' submissions for one problem, each in a sandbox; table on stdout, --json
    for the details.  Every file is written before anything is printed, and a reader that goes
    away (``| head``) stops nothing (:func:`gpsaccel.classrun.writing.terminal`)."""
    import time

    from gpsaccel._interrupt import exit_status as stopped_status
    from gpsaccel.check.own import is_file_spec, load_problem
    from gpsaccel.classrun.checking import plan_check
    from gpsaccel.classrun.running import Interrupted, hidden_from_boxes, warm_of
    from gpsaccel.classrun.writing import appender, log_path, table, terminal, write_json

    if is_file_spec(args.problem) and args.dask is not None:
        raise ValueError("--dask: a problem from a file of your own is known to this process "
                         "only, not to Dask's workers; leave out --dask (or register it in a "
                         "module the workers import)")
    args.problem = load_problem(args.problem)  # the instructor's file run, its problem registered
    spec = dask_spec(args.dask) or "processes"  # a process per check, even with --workers 1
    plan = plan_check(args.paths, problem=args.problem, n_runs=args.runs, seed=args.seed,
                      timeout=args.timeout, sandbox=args.sandbox, limits=_limits(args),
                      allow_gpsaccel=args.allow_gpsaccel,
                      allow_unsafe_basic=args.allow_unsafe_basic)
    # a flag it cannot honour: an error before any box
    warm = warm_of(BOXES[args.boxes], spec, len(plan.entries))
    with terminal() as term:
        for note in plan.notes:
            term.err(note)
        if not plan.entries:
            raise ValueError("paths: no .py file or submission folder was found")
        term.err(f"sandbox: {plan.backend}" + (
            " (bubblewrap not available: apt-get install bubblewrap)"
            if plan.backend != "bwrap" and args.sandbox == "auto" else "")
            + f", boxes {'warm' if warm else 'cold'}")
        log = appender(log_path(args.json)) if args.json is not None else None
        from tqdm.auto import tqdm

        bar = tqdm(total=len(plan.entries), desc="check", unit="submission", leave=False,
                   disable=None)  # on stderr, when it is a terminal

        def on_result(result: dict) -> None:
            bar.update()
            if log is not None:
                log(result)

        t0 = time.perf_counter()
        # the --json file and its log hold the seed and every classmate's findings: their folder
        # is hidden from the boxes as the class's are (left visible where it holds the
        # interpreter: the files are the owner's alone all the same, writing.PRIVATE)
        out = {"--json": None if args.json is None else Path(args.json).resolve().parent}
        try:
            with bar, hidden_from_boxes(plan.backend, out, optional=("--json",)):
                results = plan.run(spec, args.workers, on_result, warm)
        except Interrupted as exc:
            done = [r for r in exc.results if r is not None]
            if args.json is not None:  # first: the terminal may be gone
                write_json(done, args.json, interrupted=True, **plan.settings)
            if done:
                term.out(table(done))
            if args.json is not None:
                term.out(f"wrote {args.json} ({len(done)} of {len(plan.entries)} checked)")
            term.err("gpsaccel check: interrupted")
            return stopped_status(exc)  # 130 for Ctrl-C, 128 + SIGTERM's or SIGHUP's number
        return _check_report(args, term, results, plan, time.perf_counter() - t0)


def _limits(args: argparse.Namespace):  # noqa: ANN202 - a gpsaccel.sandbox.Limits
    """The limits of ``gpsaccel check``'s flags; a bad one is named by its flag."""
    from gpsaccel import sandbox

    try:
        return sandbox.Limits(memory=int(args.memory * 2**20), time=args.timeout,
                              file_size=int(args.max_file_size * 2**20),
                              processes=args.max_processes, output=int(args.max_output * 2**20))
    except ValueError as exc:
        raise ValueError(str(exc).replace("limits.", "--")) from None


#: What the student's first look (one file, no ``-v``) says ``-v`` adds ({path}: as given).
MORE = ("gpsaccel check -v {path} prints the whole report: the comparison with the optimal "
        "filter, the mistake the catalogue matched, the consistency tables.")


def _check_report(args: argparse.Namespace, term, results: list, plan,  # noqa: ANN001
                  seconds: float) -> int:
    """The JSON first (printing can fail), then what the reader needs and the one-line summary:
    one file is a student's first look (each finding's line and the lesson that teaches its
    fix, :func:`gpsaccel.check.report.brief`); a class is the instructor's table and which
    lesson teaches each mistake it made.  The exit status is :func:`exit_status`'s."""
    from gpsaccel.classrun.writing import brief, check_mistakes, reports, table, write_json

    if args.json is not None:  # first: printing can fail (a closed terminal), the file must not
        path = write_json(results, args.json, **plan.settings)
    if args.verbose:
        term.out(reports(results), end="")
    if len(results) == 1 and not args.verbose:
        term.out(brief(results[0], MORE.format(path=" ".join(map(str, args.paths)))))
    else:
        term.out(table(results))
        for line in check_mistakes(results):
            term.out(line)
    runs = results[0]["details"].get("n_runs", args.runs) if results else args.runs
    term.out(f"{len(results)} submission{'' if len(results) == 1 else 's'}, problem "
             f"{args.problem}, {runs} runs each (seed {plan.seed}"
             f"{', drawn' if plan.seed_drawn else ''}), sandbox {plan.backend}, {seconds:.1f} s")
    if args.json is not None:
        term.out(f"wrote {path}")
    return exit_status(results)


#: ``gpsaccel check``'s exit status: every submission passed; one failed (its code);
#: 2 is argparse's (a bad argument, before any work); none failed but some gave no verdict
#: (the machine or the checker: run those again); 130 interrupted (143 by SIGTERM, 129 by SIGHUP).
PASSED, FAILED, NO_VERDICT = 0, 1, 3


def exit_status(results: list[dict]) -> int:
    """0 when every submission passed, 1 when one failed, 3 when none failed but a check gave no
    verdict (:func:`gpsaccel.check.report.no_verdict`): a script can tell "a student's code is
    wrong" from "check these again" without parsing the table."""
    from gpsaccel.check.report import no_verdict

    failed = [r for r in results if r["passed"] is not True]
    if not failed:
        return PASSED
    if all(no_verdict(False, list(r["codes"])) for r in failed):
        return NO_VERDICT
    return FAILED


def _problem_flag(value: str) -> str:
    """--problem: a registered problem's name, or FILE.py:NAME (the file exists; it is run by
    the command, not by the parser)."""
    import gpsaccel.problems  # noqa: F401 - declares the problems and their titles (not the checker)
    from gpsaccel import registry

    if registry.is_file_spec(value):
        if not Path(value.rpartition(":")[0]).is_file():
            raise argparse.ArgumentTypeError(f"{value.rpartition(':')[0]} is not a file "
                                             f"(expected FILE.py:NAME)")
        return value
    names = registry.problem_titles()  # importing no problem: the parser does not wait for numpy
    if value not in names:
        raise argparse.ArgumentTypeError(f"invalid choice: {value!r} (choose from "
                                         f"{', '.join(names)}, or FILE.py:NAME)")
    return value


def add_check(sub: argparse._SubParsersAction) -> None:
    import gpsaccel.problems  # noqa: F401 - declares the problems and their titles (not the checker)
    from gpsaccel import registry

    titles = registry.problem_titles()
    p = sub.add_parser("check", help="check students' homework files (" + ", ".join(titles) + ")",
                       epilog="exit status: 0 every submission passed; 1 one failed; 2 a bad "
                              "argument (nothing was checked); 3 none failed but some checks "
                              "gave no verdict (the machine or the checker: check those again); "
                              "130 interrupted (143 by SIGTERM, 129 by SIGHUP)")
    p.add_argument("paths", nargs="+", type=Path,
                   help="submission files, or folders whose every top-level .py file or "
                        "sub-folder is one submission")
    p.add_argument("--problem", type=_problem_flag, default="calibration",
                   metavar="NAME|FILE.py:NAME",
                   help="the problem (default calibration), one of gpsaccel.registry's: " +
                        "; ".join(f"{name}: {title}" for name, title in titles.items()) +
                        "; or FILE.py:NAME, a problem of your own defined in FILE.py "
                        "(check.Problem.linear(NAME, ...)), run in this process as trusted "
                        "code: never a file a student handed in")
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
    add_boxes(p)
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
