"""Call named functions of a student's file on given arrays, in a process of its own.

Usage (by :func:`gpsaccel.check.student.call_functions`, not by hand)::

    python -P path/to/gpsaccel/check/_call_runner.py SUBMISSION.py WORKDIR

WORKDIR holds ``plan.json`` (``{"calls": [{"function": "ekf", "n_args": 3, "outputs":
[["x_hat", [1001, 6]], ["P", [1001, 6, 6]]]}, ...]}``) and ``inputs.npz`` (call i's arguments as
``c{i}_{j}``).  The runner imports the file as a module (``__main__`` blocks do not run), makes the
calls in order, stops at the first problem, and writes ``outputs.npz`` (call i's outputs as
``c{i}_{name}``, float64 of the declared shape) and ``status.json`` (how far it got; the first
problem: its kind, the call, the student's traceback, the types and shapes returned).  After each
call it appends a line to ``progress.txt`` so a caller that kills it knows how far it got.

This is the checker's stopgap for problems other than the calibration filter until the sandbox
(:mod:`gpsaccel.check.sandbox`) lands; it imports only the standard library and numpy, and trusts
nothing the student's code returns (every call wrapped, ``SystemExit`` included).  The time limit
is the caller's.
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

TRACEBACK_LINES = 12


def _traceback(exc: BaseException, path: Path) -> str:
    tb = traceback.extract_tb(exc.__traceback__)
    for i, frame in enumerate(tb):
        if Path(frame.filename).resolve() == path:
            tb = tb[i:]
            break
    else:
        here = Path(__file__).resolve()
        tb = [f for f in tb if not f.filename.startswith("<frozen")
              and Path(f.filename).resolve() != here]
    lines = traceback.format_list(tb) + traceback.format_exception_only(type(exc), exc)
    return "\n".join("".join(lines).rstrip("\n").splitlines()[-TRACEBACK_LINES:])


def _describe(value: object) -> dict:
    out: dict = {"type": type(value).__module__ + "." + type(value).__qualname__}
    if isinstance(value, np.ndarray):
        out["shape"] = list(value.shape)
        out["dtype"] = str(value.dtype)
    elif isinstance(value, (list, tuple)):
        try:
            out["shape"] = list(np.shape(value))
        except ValueError:
            out["shape"] = None
    return out


def run(path: Path, work: Path) -> None:
    plan = json.loads((work / "plan.json").read_text(encoding="utf-8"))
    with np.load(work / "inputs.npz") as data:
        inputs = {k: data[k] for k in data.files}
    status: dict = {"stage": "import", "calls_done": 0, "problem": None, "returned": {}}
    results: dict[str, np.ndarray] = {}

    def finish() -> None:
        np.savez(work / "outputs.tmp.npz", **results)
        (work / "outputs.tmp.npz").replace(work / "outputs.npz")
        (work / "status.tmp").write_text(json.dumps(status), encoding="utf-8")
        (work / "status.tmp").replace(work / "status.json")

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
        status["problem"] = {"kind": "import-error", "traceback": _traceback(exc, path)}
        finish()
        return
    status["import_seconds"] = time.perf_counter() - t0
    status["stage"] = "calls"
    with open(work / "progress.txt", "a", encoding="utf-8") as prog:
        for i, call in enumerate(plan["calls"]):
            name = call["function"]
            f = getattr(module, name, None)
            if f is None or not callable(f):
                status["problem"] = {"kind": "no-function", "call": i, "function": name,
                                     "callables": sorted(n for n in vars(module)
                                                         if not n.startswith("_")
                                                         and callable(getattr(module, n)))[:20]}
                break
            args = [inputs[f"c{i}_{j}"].copy() for j in range(call["n_args"])]
            try:
                out = f(*args)
            except BaseException as exc:  # noqa: BLE001
                status["problem"] = {"kind": "exception", "call": i, "function": name,
                                     "traceback": _traceback(exc, path)}
                break
            outputs = call["outputs"]
            if len(outputs) > 1:
                if not isinstance(out, (tuple, list)) or len(out) != len(outputs):
                    status["problem"] = {"kind": "return-value", "call": i, "function": name,
                                         "returned": _describe(out),
                                         "length": len(out) if isinstance(out, (tuple, list))
                                         else None}
                    break
                values = list(out)
            else:
                values = [out]
            status["returned"].setdefault(name, {o[0]: _describe(v) for o, v in
                                                 zip(outputs, values, strict=True)})
            arrays = {}
            for (oname, shape), value in zip(outputs, values, strict=True):
                try:
                    arr = np.array(value, dtype=float)
                except (TypeError, ValueError) as exc:
                    status["problem"] = {"kind": "not-numeric", "call": i, "function": name,
                                         "name": oname, "returned": _describe(value),
                                         "error": str(exc)}
                    break
                if list(arr.shape) != list(shape):
                    status["problem"] = {"kind": "wrong-shape", "call": i, "function": name,
                                         "name": oname, "shape": list(arr.shape),
                                         "expected": list(shape)}
                    break
                arrays[oname] = arr
            if status["problem"]:
                break
            for oname, arr in arrays.items():
                results[f"c{i}_{oname}"] = arr
            status["calls_done"] = i + 1
            prog.write(f"{i + 1}\n")
            prog.flush()
    status["stage"] = "done"
    finish()


if __name__ == "__main__":
    run(Path(sys.argv[1]).resolve(), Path(sys.argv[2]))
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)  # do not wait for threads the student's code may have left running
