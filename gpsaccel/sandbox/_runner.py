"""Run named functions of a student's submission on given arrays, inside a sandbox.

Usage (by :mod:`gpsaccel.sandbox`, not by hand)::

    python -I -S -B _runner.py CONTROL_DIR SUBMISSION_DIR RESULT_FD [GO_FD]

It is started as a script in isolated mode (``-I``: no environment variables, no user site, its
own folder not on ``sys.path``) without the ``site`` module (``-S``: no ``.pth`` file runs, so an
editable install of gpsaccel is not on the path).  It imports only the standard library before it
has read its plan, then numpy, then the student's file.

CONTROL_DIR holds ``plan.json`` (written by the sandbox)::

    {"entry": "filter.py",                 # the student's file, relative to SUBMISSION_DIR
     "sys_path": [...],                    # site-packages folders (numpy, scipy, filterpy)
     "block": ["gpsaccel"],                # packages the submission may not import
     "calls": [{"function": "kalman_filter", "n_args": 1,
                "outputs": [{"name": "x_hat", "shape": [151, 3], "dtype": "float64",
                             "column": true}, ...]}]}   # column: [151, 3, 1] is taken too

and ``inputs.npz`` with the arguments of call ``i`` as ``c{i}_{j}``.  The runner imports the
student's file as a module (its ``if __name__ == "__main__":`` block does not run), makes each call
in order, and stops at the first problem: one broken call says everything a student needs.

What comes back goes over the pipe RESULT_FD as frames: a 4-byte big-endian length, a JSON
header, and for a ``result`` frame the declared arrays' bytes (C order, native byte order, the
declared dtype).  The parent reads them against the shapes it declared itself and refuses
anything else (:class:`gpsaccel.sandbox.FrameReader`), so nothing the student's code does
to this process (patching numpy, writing to the pipe) can hand back more than an answer of the
declared size.  Frames: ``uses-checker`` (an import of a blocked package was attempted),
``imported``, ``forked`` (the student's code forked this process: the call it was in, sent once,
before that call's own frame), ``result`` (one per call), ``problem`` (the first problem; the
runner stops) and ``done``.

Only the runner's own process speaks (:func:`_send`).  A process the student's code forked
(``os.fork()`` in a notebook's cell, a ``multiprocessing`` worker) is a copy of the runner in the
middle of a call: left alone it would go on with the plan and send that call's frames, and the
following ones, a second time, interleaved with the runner's, and the parent would refuse the
channel and with it the answers still to come (issue 43: 4/10 for ``import os; os.fork()``).  So
the copy's channel is /dev/null from the fork on (``os.register_at_fork``: a frame the runner was
writing when a signal handler forked is not finished by the copy), and the copy ends
(``os._exit(0)``) where it would send its first frame, so it never runs the rest of the plan.
The runner itself says once that a fork happened (``forked``), so the feedback can tell the
student.  This guards an honest student's accident, not against a hostile one: the student's code
runs in the runner's process and can write any bytes to the channel itself, fork or no fork, which
the parent reads as untrusted (:class:`gpsaccel.sandbox.FrameReader` says why that is safe).

Nothing here trusts the student's code: every call into it is wrapped, ``SystemExit`` included.
The limits (time, memory, processes, files, output) are the sandbox's.
"""

from __future__ import annotations

import errno
import importlib.abc
import importlib.util
import json
import os
import struct
import sys
import time
import traceback
from pathlib import Path

#: Frames of the student's traceback kept in a problem (the last lines, nearest the error).
TRACEBACK_LINES = 12

_FD = -1
#: The runner's pid (:func:`main`), and ``os.getpid`` as it was before the student's code ran
_PID = -1
_getpid = os.getpid
#: The call the runner is making (-1: importing the student's file), and the call during which
#: the student's code first forked the runner (None: it has not), not yet said when ``_TOLD``.
_AT = -1
_FORKED: int | None = None
_TOLD = False


#: Longest text field sent (the parent refuses longer ones: sandbox.MAX_TEXT).
MAX_TEXT = 4000


def _cut(value: object) -> object:
    """Strings (at any depth) cut to MAX_TEXT characters: a student's names and messages may be
    of any length."""
    if isinstance(value, str):
        return value if len(value) <= MAX_TEXT else value[:MAX_TEXT - 1] + "…"
    if isinstance(value, dict):
        return {_cut(k): _cut(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_cut(v) for v in value]
    return value


def _send(header: dict, payload: bytes = b"") -> None:
    """One frame down the channel, from the runner's process only: a process the student's code
    forked ends here instead (module docstring).  A fork the runner has not said yet is said
    first."""
    global _TOLD
    if _getpid() != _PID:
        os._exit(0)
    if _FORKED is not None and not _TOLD:
        _TOLD = True
        _send({"t": "forked"} if _FORKED < 0 else {"t": "forked", "call": _FORKED})
    data = json.dumps(_cut(header)).encode()
    blob = struct.pack(">I", len(data)) + data + payload
    view = memoryview(blob)
    while view:
        if _getpid() != _PID:  # a signal handler of the student's forked mid-frame
            os._exit(0)
        n = os.write(_FD, view)
        view = view[n:]


def _forked_parent() -> None:
    """After a fork, in the runner: remember the first call that forked."""
    global _FORKED
    if _FORKED is None and _getpid() == _PID:
        _FORKED = _AT


def _forked_child() -> None:
    """After a fork, in the copy: its channel is /dev/null (closed where /dev/null cannot be
    opened), so not even a frame the runner was writing is finished by it."""
    if _getpid() == _PID or _FD < 0:
        return
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, _FD, inheritable=False)
        os.close(null)
    except OSError:
        try:
            os.close(_FD)
        except OSError:
            pass


class _Blocker(importlib.abc.MetaPathFinder):
    """Refuse (and report) imports of the checker's own package."""

    def __init__(self, names: list[str]) -> None:
        self.names = tuple(names)
        self.reported = False

    def find_spec(self, fullname, path=None, target=None):  # noqa: ANN001, ANN201
        top = fullname.partition(".")[0]
        if top in self.names:
            if not self.reported:
                self.reported = True
                _send({"t": "uses-checker", "module": fullname})
            raise ModuleNotFoundError(
                f"{top} is not available to submissions during a check: compute the answer "
                f"with your own code", name=fullname)
        return None


def path_test(dirs: tuple[str, ...]):  # noqa: ANN201 - a closure
    """``is_under(path)``: whether ``path`` (str, bytes or os.PathLike) resolves under one of
    ``dirs`` (real paths ending in "/"); a path that cannot be resolved counts as under (it is
    not let through).  Resolved real paths: '//path/to/gpsaccel', 'a/../gpsaccel' or a symlink to
    it is the folder as much as its own name.  It binds what it uses here (patching os later
    does not change it)."""
    import os as _os

    realpath, fspath = _os.path.realpath, _os.fspath

    def is_under(path: object) -> bool:
        try:
            p = fspath(path)  # type: ignore[call-overload]  # anything the student passes
        except TypeError:
            return False
        if isinstance(p, bytes):
            p = p.decode(errors="replace")
        if not isinstance(p, str):
            return False
        try:
            return (realpath(p) + "/").startswith(dirs)
        except (OSError, ValueError):
            return True

    return is_under


def _audit_hook(names: list[str], dirs: list[str]):  # noqa: ANN202
    """An audit hook (it cannot be removed once added) that reports, then refuses, an import of
    a blocked package or an open of a file under a blocked folder, even after the student's code
    took the import blocker off ``sys.meta_path``.  It uses only objects bound here, so patching
    modules (json, os, this runner) does not silence it."""
    names_t = tuple(names)
    dirs_t = tuple(dict.fromkeys(os.path.realpath(d).rstrip("/") + "/" for d in dirs))
    data = json.dumps({"t": "uses-checker", "module": "gpsaccel"}).encode()
    frame = struct.pack(">I", len(data)) + data
    write, fd = os.write, _FD
    sent: list[bool] = []
    blocked = path_test(dirs_t)

    def hook(event: str, args: tuple) -> None:
        hit = False
        if event == "import" and args and isinstance(args[0], str):
            hit = args[0].partition(".")[0] in names_t
        elif event in ("open", "os.symlink", "os.link", "shutil.copyfile", "os.listdir",
                       "os.scandir") and args:
            hit = blocked(args[0])
        if hit:
            if not sent:
                sent.append(True)
                try:
                    write(fd, frame)
                except OSError:
                    pass
            raise PermissionError(f"{args[0]!r}: the checker's package is not available to "
                                  f"submissions during a check")

    return hook


def _student_traceback(exc: BaseException, root: Path) -> str:
    """The traceback from the first frame in the student's files on, last lines only."""
    tb: list[traceback.FrameSummary] = list(traceback.extract_tb(exc.__traceback__))
    for i, frame in enumerate(tb):
        if not frame.filename.startswith("<") and \
                Path(frame.filename).resolve().is_relative_to(root):
            tb = tb[i:]
            break
    else:  # not in the student's code (a SyntaxError, say): leave out the runner and importlib
        here = Path(__file__).resolve()
        tb = [f for f in tb if not f.filename.startswith("<frozen")
              and Path(f.filename).resolve() != here]
    lines = traceback.format_list(tb) + traceback.format_exception_only(type(exc), exc)
    text = "".join(lines).rstrip("\n").splitlines()
    return "\n".join(text[-TRACEBACK_LINES:])


def _limit_hit(exc: BaseException | None) -> str | None:
    """Which limit of the sandbox an exception (or its cause) comes from, if any."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, MemoryError):
            return "memory"
        if isinstance(exc, OSError):
            if exc.errno in (errno.EFBIG, errno.ENOSPC, errno.EDQUOT):
                return "file"
            if exc.errno == errno.EAGAIN and isinstance(exc, BlockingIOError):
                return "process"  # fork() refused at RLIMIT_NPROC
            if exc.errno == errno.EMFILE:
                return "open-files"
        exc = exc.__cause__ or exc.__context__
    return None


def _describe(value: object) -> dict:
    """Type and (if it has one) shape of something the student returned; ``None`` is named
    ``None`` (a function without a return statement returns it; "builtins.NoneType" puzzles)."""
    import numpy as np

    if value is None:
        return {"type": "None"}
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


def _problem(kind: str, exc: BaseException | None = None, root: Path | None = None,
             **fields: object) -> None:
    header = {"t": "problem", "kind": kind, **fields}
    if exc is not None:
        header["exception"] = type(exc).__name__
        header["limit"] = _limit_hit(exc)
        header["traceback"] = _student_traceback(exc, root) if root else ""
    _send(header)


def run(control: Path, root: Path) -> None:
    plan = json.loads((control / "plan.json").read_text(encoding="utf-8"))
    sys.path.extend(p for p in plan["sys_path"] if p not in sys.path)  # a warm box has them
    # one BLAS thread: the sandbox's memory limit counts every thread's stack, and the machine is
    # shared; matplotlib never opens a window
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    os.environ["MPLBACKEND"] = "Agg"
    import numpy as np

    with np.load(control / "inputs.npz", allow_pickle=False) as data:
        inputs = {k: data[k] for k in data.files}
    if plan["block"]:
        sys.meta_path.insert(0, _Blocker(plan["block"]))
        sys.addaudithook(_audit_hook(plan["block"], plan["block_dirs"]))
    # only now the student's folder: a numpy.py of theirs must not run before the hook is in
    sys.path.insert(0, str(root))
    t0 = time.perf_counter()
    module = _import_student(root / plan["entry"], root)
    if module is None:
        return
    _send({"t": "imported", "seconds": time.perf_counter() - t0})
    t1 = time.perf_counter()
    for i, call in enumerate(plan["calls"]):
        if not _call(i, call, module, inputs, root):
            return
    _send({"t": "done", "import_seconds": t1 - t0, "run_seconds": time.perf_counter() - t1})


def _import_student(path: Path, root: Path):  # noqa: ANN202 - a module, or None (reported)
    os.chdir(path.parent)
    try:
        spec = importlib.util.spec_from_file_location("student_submission", path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot load {path.name} as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules["student_submission"] = module
        spec.loader.exec_module(module)
    except BaseException as exc:  # noqa: BLE001 - the student's code may raise anything
        _problem("import-error", exc, root)
        return None
    return module


def _call(i: int, call: dict, module, inputs: dict, root: Path) -> bool:  # noqa: ANN001
    """Call ``i`` of the plan; send its result, or its problem (False: the runner stops)."""
    global _AT
    _AT = i
    name = call["function"]
    f = getattr(module, name, None)
    if f is None or not callable(f):
        names = sorted(n for n in vars(module) if not n.startswith("_") and callable(
            getattr(module, n)))
        _problem("no-function", function=name, callables=names[:20],
                 found=None if f is None else _describe(f))
        return False
    args = [inputs[f"c{i}_{j}"].copy() for j in range(call["n_args"])]
    try:
        out = f(*args)
    except BaseException as exc:  # noqa: BLE001
        _problem("exception", exc, root, call=i, function=name)
        return False
    specs = call["outputs"]
    if len(specs) > 1:
        if not isinstance(out, (tuple, list)) or len(out) != len(specs):
            _problem("return-value", call=i, function=name, returned=_describe(out),
                     length=len(out) if isinstance(out, (tuple, list)) else None,
                     expected=len(specs))
            return False
        values = list(out)
    else:
        values = [out]
    payload = _encode(i, name, specs, values)
    if payload is None:
        return False
    _send({"t": "result", "call": i, "returned": {s["name"]: _describe(v) for s, v in
                                                  zip(specs, values, strict=True)}}, payload)
    return True


def _encode(i: int, name: str, specs: list[dict], values: list) -> bytes | None:
    """The declared outputs' bytes, or None (a problem sent) when one is not the declared array."""
    import numpy as np

    payload = []
    for spec_, value in zip(specs, values, strict=True):
        try:
            arr = np.array(value, dtype=spec_["dtype"])
        except BaseException as exc:  # noqa: BLE001 - a student's __array__ may raise anything
            _problem("not-numeric", call=i, function=name, name=spec_["name"],
                     returned=_describe(value), error=str(exc)[:500])
            return None
        want = tuple(spec_["shape"])
        if spec_.get("column") and arr.shape == want + (1,):
            arr = arr[..., 0]  # filterpy's column state; the "returned" shape still says so
        if arr.shape != want:
            _problem("wrong-shape", call=i, function=name,
                     shapes={s["name"]: _describe(v).get("shape")
                             for s, v in zip(specs, values, strict=True)},
                     got=list(arr.shape), name=spec_["name"])
            return None
        payload.append(np.ascontiguousarray(arr).tobytes())
    return b"".join(payload)


def _not_dumpable() -> None:
    """Close this process's /proc memory to other processes of the same user: under the basic
    sandbox another student's box runs as the same user (the student's own code could undo this
    for itself, never for a classmate's box)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            ctypes.CDLL(None).prctl(4, 0, 0, 0, 0)  # PR_SET_DUMPABLE, 0
        except (OSError, AttributeError):
            pass


def _wait(go: int | None) -> None:
    """After the last frame: wait until the parent has counted the box's processes (it closes
    its end of ``go``), so what a student left running is seen while the runner still lives
    (under bwrap the PID namespace, and every process in it, ends with the runner)."""
    if go is None:
        return
    try:
        os.read(go, 1)
    except OSError:
        pass


def main(argv: list[str]) -> int:
    global _FD, _PID
    _not_dumpable()
    control, root, fd = Path(argv[0]), Path(argv[1]).resolve(), int(argv[2])
    go = int(argv[3]) if len(argv) > 3 else None
    _FD, _PID = fd, _getpid()
    os.register_at_fork(after_in_parent=_forked_parent, after_in_child=_forked_child)
    os.set_inheritable(fd, False)  # a subprocess of the student's does not get the channel
    if go is not None:
        os.set_inheritable(go, False)
    run(control, root)
    _wait(go)
    return 0


if __name__ == "__main__":
    code = main(sys.argv[1:])
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)  # do not wait for threads the student's code may have left running
