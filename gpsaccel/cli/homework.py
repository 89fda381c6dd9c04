"""The homework: ``assignment`` (otter assign, one notebook per student) and ``grade`` (a class)."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from gpsaccel import _validation as _v
from gpsaccel.cli._flags import BOXES, Registered, add_boxes, registered_assignments

if TYPE_CHECKING:  # the command loads them when it runs
    from gpsaccel.classrun.grading import Graded
    from gpsaccel.classrun.writing import Terminal


def _cmd_assignment(args: argparse.Namespace) -> int:
    """``otter assign`` a homework (the package's or a folder of the instructor's own): the
    student notebook and the autograder zip; with ``--roster`` one notebook per student carrying
    that student's variant.  Every flag is checked before the minutes of ``otter assign``.
    ``--example DIR`` only writes the example homework (core install: no otter needed);
    ``NAME --copy DIR`` only copies a packaged homework into a private folder."""
    if args.example is not None:
        return _write_example(args)
    if args.copy is not None:
        return _copy(args)
    import time

    from tqdm.auto import tqdm

    from gpsaccel.assignments.generate import generate, personalize, resolve
    from gpsaccel.assignments.grading import read_secret
    from gpsaccel.assignments.roster import read_roster

    if args.name is None:
        raise ValueError("give the homework NAME and --out DIR (or --example DIR to write the "
                         "example of a homework of your own)")
    if args.out is None:
        raise ValueError(f"--out: give the folder to write ({args.name}'s student notebook and "
                         f"autograder)")
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
    from gpsaccel.assignments.gradescope import build, unmatched, unmatched_message

    lost = unmatched(students)  # no zip that would give them 0: said, before otter runs

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
        gradescope = (f"no zip written: {unmatched_message(lost)}" if lost else
                      f"{build(name, g.out, students, secret)} (scores computed outside the "
                      f"sandbox; otter's own zip: {g.autograder.name})")
        bar.update()
    # the grader recomputes each student's variant from the same roster and secret
    variant_flags = (f" --roster {shlex.quote(str(args.roster))} --secret-file "
                     f"{shlex.quote(str(args.secret_file))}" if students is not None else "")
    print(f"hand out:  {g.student}\ngrade with: gpsaccel grade SUBMISSIONS --assignment "
          f"{args.name}{variant_flags}\nGradescope: {gradescope}\nsolution:  {g.solution}")
    if students is not None:
        print(f"per student: {folder}/<id>/{name}.ipynb ({len(students)} students)")
    if name == args.name:  # a homework of the package: its solutions ship with it
        print(f"public:    the solutions of {name} are in every install of gpsaccel and in its "
              f"repository; for graded work hand out a private copy you changed: gpsaccel "
              f"assignment {name} --copy DIR (docs/grading.md, \"Integrity\")")
    print(f"{time.perf_counter() - t0:.1f} s")
    return 0


def _write_example(args: argparse.Namespace) -> int:
    """``--example DIR``: the example homework written into DIR/cv2d, nothing else (any other
    argument is an error, never ignored)."""
    given = [flag for flag, value in (("NAME", args.name), ("--out", args.out),
                                      ("--roster", args.roster),
                                      ("--secret-file", args.secret_file),
                                      ("--no-run-tests", args.no_run_tests or None),
                                      ("--copy", args.copy))
             if value is not None]
    if given:
        raise ValueError(f"--example writes the example and does nothing else: leave out "
                         f"{', '.join(given)}")
    from gpsaccel.homework import write_example

    folder = write_example(args.example)
    here = shlex.quote(str(folder))
    print(f"wrote {folder}: {folder.name}.ipynb (the master), graded.py (its graded questions), "
          f"problems.py (its problem)\nhand out:  gpsaccel assignment {here} --out hw/"
          f"{folder.name}\ngrade with: gpsaccel grade SUBMISSIONS --assignment {here}")
    return 0


def _copy(args: argparse.Namespace) -> int:
    """``assignment NAME --copy DIR``: the packaged homework into a private folder of yours."""
    from gpsaccel.assignments.homework import copy_homework

    if args.name is None:
        raise ValueError("--copy: give the packaged homework NAME to copy")
    extra = [f for f, v in (("--out", args.out), ("--roster", args.roster),
                            ("--secret-file", args.secret_file),
                            ("--no-run-tests", args.no_run_tests)) if v]
    if extra:
        raise ValueError(f"--copy only copies the homework; {', '.join(extra)} belong to handing "
                         f"out the copy afterwards (gpsaccel assignment DIR --out ...)")
    master = copy_homework(args.name, args.copy)
    folder = shlex.quote(str(master.parent))
    print(f"copied {args.name} into {master.parent} (the master {master.name}, with its "
          f"solutions, and graded.py): keep this folder private.\nchange what is asked (numbers, "
          f"questions, graded.py's checks: docs/grading.md, \"Integrity\"), then\nhand out: "
          f"gpsaccel assignment {folder} --out DIR\ngrade:    gpsaccel grade SUBMISSIONS "
          f"--assignment {folder}")
    return 0


def _cmd_grade(args: argparse.Namespace) -> int:
    """Grade a class in the sandbox: grades.csv, feedback/, summary.csv/png in --out; with
    --roster the LMS gradebook files; the similarity report.  :func:`gpsaccel.classrun.grade`
    writes every file; only then is anything printed, and a reader that goes away (``| head``)
    stops nothing (:func:`gpsaccel.classrun.writing.terminal`).  A file the file system refused
    (a full disk) is named, with the ``--from-grades`` command that writes it once there is
    room, and the command exits 2."""
    from gpsaccel.assignments.generate import resolve
    from gpsaccel.assignments.grading import read_secret
    from gpsaccel.assignments.scoring import TIMEOUT
    from gpsaccel.classrun.grading import default_out, grade_class, rewrite_class
    from gpsaccel.classrun.writing import grade_mistakes, grades_table, terminal

    if args.compare_with is not None and args.no_similarity:
        raise ValueError("--compare-with: the comparison is the similarity report's; leave out "
                         "--no-similarity")
    name = resolve(args.assignment)
    if args.dask is not None and name != args.assignment:
        raise ValueError("--dask: a homework from a folder of your own is known to this process "
                         "only, not to Dask's workers; leave out --dask")
    if args.from_grades:
        _only_class_wide(args)
    roster, hint = _roster(args)
    out = args.out if args.out is not None else default_out(args.submissions)
    with terminal() as term:
        if args.from_grades:
            graded = rewrite_class(args.submissions, name, out, roster,
                                   similarity=not args.no_similarity,
                                   canvas_column=args.canvas_column)
        else:
            graded = grade_class(args.submissions, name, out=out, jobs=args.jobs,
                                 timeout=args.timeout or TIMEOUT, seed=args.seed,
                                 secret=None if args.secret_file is not None
                                 or args.no_variants else read_secret(None),
                                 secret_file=args.secret_file, student=args.student,
                                 dask=args.dask, sandbox=args.sandbox, progress=True,
                                 roster=roster, similarity=not args.no_similarity,
                                 export=args.export, regrade=args.regrade,
                                 compare_with=args.compare_with,
                                 canvas_column=args.canvas_column,
                                 warm_boxes=BOXES[args.boxes],
                                 no_variants=args.no_variants)
            if graded.grades:  # a rerun that kept every grade has no table (its line says so)
                term.out(grades_table(graded.grades))
            for line in grade_mistakes(graded.grades):
                term.out(line)
        _wrote(term, args, out, graded)
        if hint:
            term.out(hint)
    return 2 if graded.missing else 0


def _roster(args: argparse.Namespace) -> tuple[list | None, str]:
    """The students of ``--roster`` (None without one), ``--canvas-column`` checked against its
    assignment columns, and the line that names the column to pass when a Canvas gradebook
    export has exactly one and none was given ("" else)."""
    from gpsaccel.assignments.roster import FORMS, read

    if args.roster is None:
        if args.canvas_column is not None:
            raise ValueError("--canvas-column names a column of --roster (Canvas's gradebook "
                             "export): give --roster")
        return None, ""
    roster = read(args.roster)
    column = args.canvas_column
    if column is not None and column not in roster.assignments:
        has = (f"its assignment columns are {', '.join(map(repr, roster.assignments))}"
               if roster.assignments else f"it has no assignment column (read as "
               f"{FORMS[roster.form]}; Canvas's gradebook export has them: 'Homework 1 (5501)')")
        raise ValueError(f"--canvas-column: {column!r} is not a column of --roster "
                         f"{args.roster}: {has}")
    hint = ""
    if column is None and len(roster.assignments) == 1:
        one = roster.assignments[0]
        hint = (f"canvas.csv: its grade column is the homework's title, which Canvas imports "
                f"as a new assignment; to fill {one!r} of {args.roster}, add --canvas-column "
                f"{shlex.quote(one)}")
    return roster.students, hint


def _wrote(term: Terminal, args: argparse.Namespace, out: Path, graded: Graded) -> None:
    """The lines after a grade: the files written, the class-wide step's lines, and what is
    missing with the ``--from-grades`` command that writes it once there is room."""
    from gpsaccel.classrun.writing import missing_lines

    skip = set(graded.missing) | ({"grades.json", "feedback/"} if args.from_grades else set())
    shown = [f"{out / f}/" if f.endswith("/") else str(out / f) for f in (
        "grades.csv", "grades.json", "feedback/", "summary.csv", "summary.png", "grading.json")
        if f not in skip]
    term.out(f"wrote {', '.join(shown)} (seed in {out / 'grading.json'})")
    for line in graded.classwide:
        term.out(line)
    again = " ".join(shlex.quote(str(a)) for a in (
        "gpsaccel", "grade", args.submissions, "--assignment", args.assignment, "--out", out,
        *(("--roster", args.roster) if args.roster is not None else ()),
        *(("--canvas-column", args.canvas_column) if args.canvas_column is not None else ()),
        *(("--no-similarity",) if args.no_similarity else ()), "--from-grades"))
    for line in missing_lines(graded.missing, again):
        term.err(line)


#: The flags of a grade that ``--from-grades`` (no notebook graded) cannot honour, and their
#: defaults.
_GRADING_ONLY = {"student": None, "seed": None, "jobs": None, "timeout": None,
                 "secret_file": None, "dask": None, "sandbox": "auto", "export": "auto",
                 "regrade": False, "compare_with": None, "boxes": "auto",
                 "no_variants": False}


def _only_class_wide(args: argparse.Namespace) -> None:
    """Refuse a grading flag with ``--from-grades``, which grades nothing."""
    given = [f"--{k.replace('_', '-')}" for k, default in _GRADING_ONLY.items()
             if getattr(args, k) != default]
    if given:
        raise ValueError(f"--from-grades writes the class-wide files from the recorded grades "
                         f"and grades no notebook: leave out {', '.join(given)}")


def _existing_dir(text: str) -> Path:
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is not a folder")
    return path


def add_assignment(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("assignment", help="otter assign a homework: student notebook + autograder")
    p.add_argument("name", choices=Registered(registered_assignments), metavar="NAME", nargs="?",
                   help="the homework: %(choices)s, or a folder of your own holding NAME.ipynb "
                        "(the master) and graded.py (its questions)")
    p.add_argument("--example", type=Path, default=None, metavar="DIR",
                   help="write the example of a homework of your own into DIR/cv2d (master, "
                        "graded.py, problems.py: docs/grading.md) and do nothing else")
    p.add_argument("--out", type=_v.output_dir, default=None,
                   help="folder to write (replaced); required with NAME")
    p.add_argument("--copy", type=_v.output_dir, default=None, metavar="DIR",
                   help="copy the packaged homework NAME (master with solutions, graded.py) into "
                        "DIR, a new folder you keep private, to change and hand out as your own")
    p.add_argument("--no-run-tests", action="store_true",
                   help="do not execute the solution against its tests first (faster)")
    p.add_argument("--roster", type=Path, default=None,
                   help="the class: one student id a line, a CSV file with an id column, or "
                        "the LMS's roster file (docs/grading.md): one notebook each, with its "
                        "variant")
    p.add_argument("--secret-file", type=Path, default=None,
                   help="the instructor's secret (default $GPSACCEL_GRADING_SECRET)")
    p.set_defaults(func=_cmd_assignment)


def add_grade(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("grade", help="grade a class of homework notebooks in the sandbox")
    p.add_argument("submissions", type=Path,
                   help="LMS export: a folder per student (or one .ipynb per student)")
    p.add_argument("--assignment", required=True, choices=Registered(registered_assignments),
                   metavar="NAME", help="the homework: %(choices)s, or a folder of your own "
                                        "holding NAME.ipynb and graded.py")
    p.add_argument("--roster", type=Path, default=None,
                   help="the class roster as the LMS downloads it (Canvas's gradebook export, "
                        "Moodle's participants, grades or grading worksheet, Gradescope's "
                        "roster), one id a line, or a CSV file with an id column: maps each "
                        "submission to its student and writes canvas.csv, moodle.csv and "
                        "Gradescope's CSV files too (docs/grading.md)")
    p.add_argument("--canvas-column", default=None, metavar="COLUMN",
                   help="name canvas.csv's grade column as this assignment column of --roster "
                        "(Canvas's gradebook export, e.g. 'Homework 1 (5501)'), so Canvas's "
                        "import fills it (default: the homework's title, a new assignment)")
    p.add_argument("--export", choices=("auto", "plain", "canvas", "moodle", "gradescope"),
                   default="auto",
                   help="how SUBMISSIONS was downloaded (default auto: told from the names; "
                        "plain: a folder or notebook per roster id)")
    p.add_argument("--no-similarity", action="store_true",
                   help="skip the similarity report (similarity.csv, similarity.html)")
    p.add_argument("--compare-with", type=_existing_dir, default=None, metavar="DIR",
                   help="earlier submissions (an export as graded, e.g. last year's) each answer "
                        "is compared with too")
    p.add_argument("--out", type=_v.output_dir, default=None,
                   help="folder for grades.csv, feedback/, summary (default SUBMISSIONS-grades)")
    p.add_argument("--jobs", type=_v.flag_int(minimum=1), default=None,
                   help="notebooks graded at once (default: CPUs, at most 4)")
    p.add_argument("--timeout", type=_v.flag_float(0.0, open_min=True), default=None,
                   help="time limit of one notebook's box, s (default 120)")
    p.add_argument("--seed", type=_v.flag_seed, default=None,
                   help="seed of the fresh data (default: random; recorded in grading.json)")
    p.add_argument("--secret-file", type=Path, default=None,
                   help="the instructor's secret for per-student variants (default "
                        "$GPSACCEL_GRADING_SECRET; none: no variants, refused where the "
                        "notebooks declare variants: docs/grading.md)")
    p.add_argument("--no-variants", action="store_true",
                   help="grade every notebook on the public notebook's numbers, although they "
                        "declare variants of their own (no secret read)")
    p.add_argument("--student", nargs="+", default=None, metavar="ID",
                   help="regrade these students only (the roster's id, the name as found, or "
                        "the id grades.csv shows), with the recorded seed")
    p.add_argument("--regrade", action="store_true",
                   help="grade every notebook again (default: a rerun into the same --out "
                        "without --seed keeps the recorded grade of each unchanged notebook)")
    p.add_argument("--dask", default=None,
                   help="grade on Dask: 'dask-local' or a scheduler address tcp://host:port")
    p.add_argument("--sandbox", choices=("auto", "bwrap", "basic"), default="auto",
                   help="isolation of each notebook (default auto: bwrap where it works)")
    p.add_argument("--from-grades", action="store_true",
                   help="grade nothing: write grades.csv, the summary, the gradebooks (with "
                        "--roster) and the similarity report again from --out's grades.json "
                        "(after a run that could not write them: a full disk)")
    add_boxes(p)
    p.set_defaults(func=_cmd_grade)
