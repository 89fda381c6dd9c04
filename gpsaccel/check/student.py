"""Call named functions of a student's file on numpy inputs; get validated arrays back.

The one place the problem checkers (:mod:`gpsaccel.check.problems`) reach the student's code::

    calls = [Call("ekf", (y, Q, R), (Output("x_hat", (1001, 6)), Output("P", (1001, 6, 6))))]
    got = call_functions("alice.py", calls, timeout=60)
    got.results[0]["x_hat"]       # float64 (1001, 6), or got.failure / got.problem

The interface is the sandbox's (:mod:`gpsaccel.check.sandbox`: ``Call``, ``Output``, a result
with ``results``, ``failure``, ``problem``, ``output``).  When the sandbox module is present this
function runs the calls in it; until then it runs them in a plain child process
(:mod:`gpsaccel.check._call_runner`: a fresh Python started with ``-P`` in an empty temporary
folder, killed with its whole process group at the time limit), which isolates crashes, endless
loops and prints but is not a security boundary.

Which functions a file defines is read with :mod:`ast` before anything runs (:func:`defines`),
so a problem whose contract accepts either of two functions (coop: ``ekf`` and/or ``lkf``) calls
only those the file has.
"""

from __future__ import annotations

import ast
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

RUNNER = Path(__file__).with_name("_call_runner.py")

#: Characters of the student's printed output kept.
OUTPUT_KEEP = 1500


@dataclass(frozen=True)
class Output:
    """One array a call must return: its name and shape (float64)."""

    name: str
    shape: tuple[int, ...]


@dataclass(frozen=True)
class Call:
    """Call ``function(*args)`` of the student's file; it must return ``outputs`` (one array, or a
    tuple of them in order)."""

    function: str
    args: tuple[np.ndarray, ...]
    outputs: tuple[Output, ...]


@dataclass
class StudentCalls:
    """What came back.

    results : one dict per completed call (output name -> float64 array of the declared shape).
    failure : None when every call returned; else ``timeout``, ``crashed``, or the runner's kind
        (``import-error``, ``no-function``, ``exception``, ``return-value``, ``not-numeric``,
        ``wrong-shape``).
    problem : the runner's account of the first problem (call index, traceback, shapes).
    returned : type and shape of each output the first call of each function returned.
    output : the tail of what the student printed; output_chars : its full length.
    seconds : wall-clock time; backend : ``"process"`` or the sandbox's backend.
    detail : the sandbox's short account of a limit hit or a refused result.
    """

    results: list[dict[str, np.ndarray]] = field(default_factory=list)
    failure: str | None = None
    problem: dict | None = None
    returned: dict = field(default_factory=dict)
    output: str = ""
    output_chars: int = 0
    seconds: float = 0.0
    backend: str = "process"
    detail: str = ""


def defines(path: str | os.PathLike, function: str) -> bool:
    """Whether the file defines ``function`` at top level (read with ast, never executed)."""
    try:
        tree = ast.parse(Path(path).read_bytes(), filename=str(path))
    except (SyntaxError, ValueError, OSError):
        return False
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == function:
            return True
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == function
                                                for t in node.targets):
            return True
        if isinstance(node, (ast.Import, ast.ImportFrom)) and any(
                (a.asname or a.name) == function for a in node.names):
            return True
    return False


def call_functions(path: str | os.PathLike, calls: Sequence[Call], timeout: float,
                   sandbox: str = "auto", limits: object = None,
                   allow_gpsaccel: bool = False) -> StudentCalls:
    """Make ``calls`` on the student's file ``path`` in a child process; see the module docstring.

    ``sandbox`` (backend), ``limits`` (a ``sandbox.Limits``; its time is set to ``timeout``) and
    ``allow_gpsaccel`` are the sandbox's.  Never raises for anything the student's code does.
    """
    sb = _sandbox()
    if sb is not None:
        return _in_sandbox(sb, Path(path).resolve(), list(calls), timeout, sandbox, limits,
                           allow_gpsaccel)
    return _in_process(Path(path).resolve(), list(calls), timeout)


def _sandbox():
    """The sandbox module if it is installed with the interface this module uses, else None."""
    try:
        from gpsaccel.check import sandbox
    except ImportError:
        return None
    needed = ("Call", "Output", "Limits", "run", "load_submission", "SubmissionError")
    return sandbox if all(hasattr(sandbox, n) for n in needed) else None


def _in_sandbox(sb, path: Path, calls: list[Call], timeout: float, backend: str = "auto",
                limits: object = None, allow_gpsaccel: bool = False) -> StudentCalls:
    """The calls in the sandbox; its result in this module's terms."""
    t0 = time.perf_counter()
    try:
        sub = sb.load_submission(path, function=calls[0].function)
    except sb.SubmissionError as exc:
        return StudentCalls(failure=exc.code, problem={"kind": exc.code}, detail=str(exc),
                            seconds=time.perf_counter() - t0, backend="sandbox")
    box = sb.run(sub, [sb.Call(c.function, tuple(np.asarray(a) for a in c.args),
                               tuple(sb.Output(o.name, tuple(o.shape)) for o in c.outputs))
                       for c in calls],
                 sb.Limits(**{**vars(limits or sb.Limits()), "time": timeout}),
                 backend=backend, allow_gpsaccel=allow_gpsaccel)
    problem = dict(box.problem or {}) if box.failure else None
    if problem is not None:
        problem.setdefault("kind", box.failure)
        if box.failure == "wrong-shape" and "call" in problem:
            outs = {o.name: o.shape for o in calls[problem["call"]].outputs}
            problem["shape"] = problem.get("got")
            problem["expected"] = list(outs.get(problem.get("name"), ()))
        if box.failure == "timeout":
            problem["calls_done"] = len(box.results)
    return StudentCalls(results=list(box.results), failure=box.failure, problem=problem,
                        returned={calls[0].function: box.returned or {}}, output=box.output,
                        output_chars=box.output_bytes, seconds=box.seconds,
                        backend=box.backend, detail=box.detail)


def _tail(path: Path, keep: int) -> tuple[str, int]:
    size = path.stat().st_size if path.exists() else 0
    with open(path, "rb") as f:
        if size > keep * 4:
            f.seek(size - keep * 4)
        text = f.read().decode("utf-8", errors="replace")
    return text[-keep:], size


def _kill(proc: subprocess.Popen) -> None:
    if hasattr(os, "killpg"):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    if proc.poll() is None:
        proc.kill()
    proc.wait()


def _in_process(path: Path, calls: list[Call], timeout: float) -> StudentCalls:
    t0 = time.perf_counter()
    out = StudentCalls()
    with tempfile.TemporaryDirectory(prefix="gpsaccel-calls-") as tmp:
        tmp = Path(tmp)
        work, cwd = tmp / "io", tmp / "cwd"
        work.mkdir()
        cwd.mkdir()
        plan = {"calls": [{"function": c.function, "n_args": len(c.args),
                           "outputs": [[o.name, list(o.shape)] for o in c.outputs]}
                          for c in calls]}
        (work / "plan.json").write_text(json.dumps(plan), encoding="utf-8")
        np.savez(work / "inputs.npz", **{f"c{i}_{j}": np.asarray(a)
                                         for i, c in enumerate(calls)
                                         for j, a in enumerate(c.args)})
        (work / "progress.txt").touch()
        env = dict(os.environ, MPLBACKEND="Agg", PYTHONHASHSEED="0", PYTHONIOENCODING="utf-8")
        log = tmp / "output.txt"
        timed_out = False
        with open(log, "wb") as logf:
            proc = subprocess.Popen([sys.executable, "-P", str(RUNNER), str(path), str(work)],
                                    stdout=logf, stderr=subprocess.STDOUT,
                                    stdin=subprocess.DEVNULL, cwd=cwd, env=env,
                                    start_new_session=True)
            try:
                proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                timed_out = True
            _kill(proc)
        out.output, out.output_chars = _tail(log, OUTPUT_KEEP)
        done = len((work / "progress.txt").read_text(encoding="utf-8").split())
        status = None
        if (work / "status.json").exists():
            status = json.loads((work / "status.json").read_text(encoding="utf-8"))
            with np.load(work / "outputs.npz") as data:
                arrays = {k: data[k] for k in data.files}
            for i, c in enumerate(calls[:status["calls_done"]]):
                res = {}
                for o in c.outputs:
                    arr = arrays.get(f"c{i}_{o.name}")
                    if arr is None or arr.shape != tuple(o.shape) or arr.dtype != np.float64:
                        status["problem"] = status["problem"] or {"kind": "crashed", "call": i}
                        break
                    res[o.name] = arr
                else:
                    out.results.append(res)
                    continue
                break
            out.returned = status.get("returned", {})
            out.problem = status.get("problem")
        if timed_out:
            out.failure = "timeout"
            out.problem = {"kind": "timeout", "calls_done": done}
        elif status is None:
            out.failure = "crashed"
            out.problem = {"kind": "crashed", "returncode": proc.returncode}
        elif out.problem:
            out.failure = out.problem["kind"]
    out.seconds = time.perf_counter() - t0
    return out
