"""Run a student's ``kalman_filter(z)`` on given measurements, in a process of its own.

Usage (by :func:`gpsaccel.check.whole_filter.run_student`, not by hand)::

    python -P path/to/gpsaccel/check/_runner.py SUBMISSION.py INPUT.npz OUTPUT.npz PROGRESS.txt

It is run as a script (``-P``: its own folder is not put on ``sys.path``) and imports only the
standard library and numpy, so the child starts in a fraction of a second and a student's module
named like one of ours (``report.py``) is not shadowed.

INPUT.npz holds ``z`` (n_runs, n_gps, 2).  The runner imports SUBMISSION.py as a module (its
``if __name__ == "__main__":`` block does not run), calls ``kalman_filter(z[r].copy())`` for each
run and writes OUTPUT.npz with ``x`` (n_runs, n_gps, 3) and ``P`` (n_runs, n_gps, 3, 3), NaN
where nothing came back, and ``status``: a JSON text saying how far it got and, at the first
problem, what went wrong (the student's traceback, the types and shapes returned).  It stops at
the first problem: one broken run says everything a student needs.  After every run it appends a
line to PROGRESS.txt, so a caller that has to kill it knows how far it got.

Nothing here trusts the student's code: every call into it is wrapped, ``SystemExit`` included.
The time limit is the caller's (it kills this process).
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import time
import traceback
from pathlib import Path

import numpy as np

#: Frames of the student's traceback kept in a finding (the last ones, nearest the error).
TRACEBACK_LINES = 12


def _student_traceback(exc: BaseException, path: Path) -> str:
    """The traceback from the first frame in the student's file on, last lines only."""
    tb = traceback.extract_tb(exc.__traceback__)
    for i, frame in enumerate(tb):
        if Path(frame.filename).resolve() == path:
            tb = tb[i:]
            break
    else:  # not in the student's code (a SyntaxError, say): leave out the runner and importlib
        here = Path(__file__).resolve()
        tb = [f for f in tb if not f.filename.startswith("<frozen")
              and Path(f.filename).resolve() != here]
    lines = traceback.format_list(tb) + traceback.format_exception_only(type(exc), exc)
    text = "".join(lines).rstrip("\n").splitlines()
    return "\n".join(text[-TRACEBACK_LINES:])


def _describe(value: object) -> dict:
    """Type and (if it has one) shape of something the student returned."""
    out: dict = {"type": type(value).__module__ + "." + type(value).__qualname__}
    if isinstance(value, np.ndarray):
        out["shape"] = list(value.shape)
        out["dtype"] = str(value.dtype)
    elif isinstance(value, (list, tuple)):
        try:
            out["shape"] = list(np.shape(value))
        except ValueError:
            out["shape"] = None  # ragged
    return out


def run(path: Path, z: np.ndarray, progress: Path) -> tuple[np.ndarray, np.ndarray, dict]:
    n_runs, n_gps = z.shape[0], z.shape[1]
    x_all = np.full((n_runs, n_gps, 3), np.nan)
    P_all = np.full((n_runs, n_gps, 3, 3), np.nan)
    status: dict = {"stage": "import", "runs_done": 0, "problem": None}
    t0 = time.perf_counter()
    try:
        sys.path.insert(0, str(path.parent))
        spec = importlib.util.spec_from_file_location("student_submission", path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot load {path.name} as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules["student_submission"] = module
        spec.loader.exec_module(module)
    except BaseException as exc:  # noqa: BLE001 - the student's code may raise anything
        status["problem"] = {"kind": "import-error", "traceback": _student_traceback(exc, path)}
        return x_all, P_all, status
    status["import_seconds"] = time.perf_counter() - t0
    f = getattr(module, "kalman_filter", None)
    if f is None or not callable(f):
        names = sorted(n for n in vars(module) if not n.startswith("_") and callable(
            getattr(module, n)))
        status["problem"] = {"kind": "no-kalman-filter", "callables": names[:20],
                             "found": None if f is None else _describe(f)}
        return x_all, P_all, status
    status["stage"] = "runs"
    t1 = time.perf_counter()
    with open(progress, "a", encoding="utf-8") as prog:
        for r in range(n_runs):
            try:
                out = f(z[r].copy())
            except BaseException as exc:  # noqa: BLE001
                status["problem"] = {"kind": "exception", "run": r,
                                     "traceback": _student_traceback(exc, path)}
                break
            if not isinstance(out, (tuple, list)) or len(out) != 2:
                status["problem"] = {"kind": "return-value", "run": r, "returned": _describe(out),
                                     "length": len(out) if isinstance(out, (tuple, list))
                                     else None}
                break
            x_hat, P = out
            if r == 0:
                status["returned"] = {"x_hat": _describe(x_hat), "P": _describe(P)}
            arrays = []
            for name, value in (("x_hat", x_hat), ("P", P)):
                try:
                    arrays.append(np.array(value, dtype=float))
                except (TypeError, ValueError) as exc:
                    status["problem"] = {"kind": "not-numeric", "run": r, "name": name,
                                         "returned": _describe(value), "error": str(exc)}
                    break
            if status["problem"]:
                break
            xa, Pa = arrays
            if xa.shape != (n_gps, 3) or Pa.shape != (n_gps, 3, 3):
                status["problem"] = {"kind": "wrong-shape", "run": r,
                                     "x_hat": list(xa.shape), "P": list(Pa.shape)}
                break
            x_all[r], P_all[r] = xa, Pa
            status["runs_done"] = r + 1
            prog.write(f"{r + 1}\n")
            prog.flush()
    status["run_seconds"] = time.perf_counter() - t1
    status["stage"] = "done"
    return x_all, P_all, status


def main(argv: list[str]) -> int:
    path, inp, out, progress = (Path(a) for a in argv)
    z = np.load(inp)["z"]
    x, P, status = run(path.resolve(), z, progress)
    tmp = out.with_suffix(".tmp.npz")
    np.savez(tmp, x=x, P=P, status=np.array(json.dumps(status)))
    tmp.replace(out)  # a result file exists only once complete
    return 0


if __name__ == "__main__":
    code = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # do not wait for threads the student's code may have left running
