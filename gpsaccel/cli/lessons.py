"""The lessons: ``lessons`` (execute, render to HTML, or copy them) and ``lab`` (JupyterLab)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gpsaccel import _validation as _v


def _cmd_lessons(args: argparse.Namespace) -> int:
    """Execute the lessons top to bottom; with --html also render them (figures embedded); with
    --copy DIR only copy them (and their solutions) where a student edits them."""
    import time

    from gpsaccel.lessons import lessons_dir, solutions_dir
    from gpsaccel.lessons.kernel import execute
    from gpsaccel.lessons.render import render_html

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
    from gpsaccel.lessons.lab import copy_lessons

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

    from gpsaccel.lessons.lab import copy_lessons, lab_command, lab_environment

    cmd = lab_command(args.folder, port=args.port, browser=not args.no_browser)
    if not any(args.folder.glob("*.ipynb")):
        copied, _ = copy_lessons(args.folder)
        print(f"copied {len(copied)} notebooks into {args.folder}/", file=sys.stderr)
    print(" ".join(cmd), file=sys.stderr, flush=True)
    sys.stdout.flush()
    os.execve(cmd[0], cmd, lab_environment())  # the news prompt off (lessons.lab.LAB_CONFIG)
    return 0  # only where execve is replaced (the tests)


def add_lessons(sub: argparse._SubParsersAction) -> None:
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



def add_lab(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("lab", help="open the lessons in JupyterLab (a copy in DIR, made first "
                                   "when DIR holds none)")
    p.add_argument("folder", nargs="?", type=_v.output_dir, default="gpsaccel-lessons",
                   metavar="DIR", help="folder of your copy (default gpsaccel-lessons)")
    p.add_argument("--port", type=_v.flag_int(minimum=1, maximum=65535), default=None,
                   help="port of the server (default: JupyterLab's, 8888)")
    p.add_argument("--no-browser", action="store_true", help="print the address, open no browser")
    p.set_defaults(func=_cmd_lab)
