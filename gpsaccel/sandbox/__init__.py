"""Run one student's submission in a box: isolated, limited, and emptied before anything is trusted.

The interface is generic (any checker of this package uses it) and this module's names are all of
it (nothing outside the layer uses a private name of it; ``tests/test_layout.py``)::

    from gpsaccel import sandbox
    sub = sandbox.load_submission("alice/", function="kalman_filter")   # a .py file or a folder
    calls = [sandbox.Call("kalman_filter", (z[r],),
                          (sandbox.Output("x_hat", (151, 3)), sandbox.Output("P", (151, 3, 3))))
             for r in range(n_runs)]
    box = sandbox.run(sub, calls, sandbox.Limits(time=60), backend="auto")
    box.results[r]["x_hat"]        # float64 (151, 3), exactly the declared shape, or box.failure

Each call names a function of the submission, its positional numpy arguments and the arrays it must
return (one :class:`Output` = the function returns that array; several = a tuple of them, in
order).  A class's items (one check, one notebook each) run through the one pool of
:mod:`gpsaccel.sandbox.pool` (:func:`run_items`: fork per item, deadline, subreaper, sweep, Ctrl-C;
or Dask with the same deadlines).  The student's code runs in a separate Python
(``_runner.py``); whatever it returns comes back over a pipe as frames the parent reads against
the shapes and dtypes *it* declared (:class:`FrameReader`): a result of another shape, a larger
one, or bytes that are not a frame are refused (``result-refused``), never loaded.  Nothing the
student wrote to a file is read.

Backends (the threat model, what each isolates and what not: ``docs/sandbox.md``)
--------
``bwrap`` (bubblewrap; ``apt-get install bubblewrap``)
    New user, PID, network, IPC, UTS and cgroup namespaces; inside, uid 65534 with no
    capabilities.  The file system is the interpreter's folders (``/usr``, the Python prefix, the
    site-packages) read-only, the checker's own package hidden under an empty tmpfs (or, for a
    box that may import gpsaccel, the folders its caller hides, ``run(..., hide=...)``, under
    empty folders), ``/proc`` of the box's PID namespace only (the checker's
    memory and environment are not in it), and three small writable tmpfs: the working
    directory ``/box`` (holding a copy of the submission's own files, nothing else), ``/tmp`` and
    ``/dev/shm``, each of at most ``Limits.file_size`` bytes; the root, ``/dev`` and the folders
    made for the binds are remounted read-only.  No network.
    ``--die-with-parent``: when the checker goes, the box goes; when the box's first process is
    killed, the kernel kills every process of its PID namespace.
``basic`` (any Linux; the isolation that needs no tool)
    A fresh session; resource limits set before exec (address space, CPU time, file size,
    processes, open files, no core files); an environment of ``PATH``, ``HOME`` (the box) and
    ``LANG`` only; a private temporary working directory holding a copy of the submission only;
    the checker made non-dumpable while the student runs.  The package (or the folders its
    caller hides) fenced by the kernel: Landlock, else (root) a mount namespace, else (root)
    folders closed to other users, else, as root, no box (:mod:`gpsaccel.sandbox.fence`); so
    are the folders of a class its caller hides, ``with hiding({"submissions": ...}):``
    (:mod:`gpsaccel.sandbox.outside`); everything else the student reads as other users may.
    Not run as root it is not safe for grading (the student is the checker's user:
    :func:`refuse_unsafe_basic`).
``auto`` is ``bwrap`` when a trial box starts on this machine, else ``basic``.

As root, under both backends, the student runs as a uid of its own that owns nothing and that
nothing else runs as, with no capability and no new privileges (:mod:`gpsaccel.sandbox._boxuser`;
bwrap itself runs as that uid): it cannot write into the package or the environment (a ``.pth``),
nor signal the checker, and everything the uid runs is killed at the end, wherever it is in the
process tree.  Where the machine allows it, a cgroup per box (:mod:`gpsaccel.sandbox._cgroup`:
cgroup v2, else v1) limits the memory (processes, tmpfs files and memfds together), the processes
and the CPU of the whole box; else the per-process rlimits are the limits
(:attr:`BoxResult.limit_backend` says which).

Every run ends with a checked kill: the checker is a child subreaper while the box runs (a
``setsid`` daemon is re-parented to it, not to init), every process of the box (the descendants of
its first process, the orphans adopted meanwhile, its cgroup's and its uid's) is killed with
SIGKILL until a scan finds none alive, and they are reaped; what the student left running is
counted first, while the runner waits after its last frame (:attr:`BoxResult.killed`).  Then the
cgroup and the box folder are removed (a folder or cgroup left by a killed checker is removed by
the next box: :func:`sweep_stale_boxes`).  Only then does :func:`run` return, so a caller that
computes the reference answer afterwards never holds it while a student process lives.

Limits (:class:`Limits`) and what exceeding them gives (:attr:`BoxResult.failure`): ``timeout``
(the box's own time, not its waits for a CPU on a busy machine: :mod:`.clock`; past the clock's
backstop without it, ``machine-busy``, the machine's problem, not the student's),
``memory-limit`` (address space, or the box's cgroup; a ``MemoryError`` or a process killed at
it), ``output-limit`` (printed bytes; the box is stopped at the limit), ``file-limit`` (one file,
or a box tmpfs, full), ``process-limit``, ``uses-checker`` (an import of gpsaccel was attempted),
``result-refused`` (see :class:`FrameReader`), ``link-refused`` (see :func:`load_submission`),
``crashed`` (the process ended without saying ``done``), and the runner's own: ``import-error``,
``no-function``, ``exception``, ``return-value``, ``not-numeric``, ``wrong-shape``.

Host-side work on a student's files that is not the student's code (parsing a notebook) runs under
limits in a forked child: :func:`in_child` (:mod:`.child`), the one way to do so.

Layout (each module under 500 lines): :mod:`.spec` (what to run, what comes back),
:mod:`.submission` (a student's files, walked and checked), :mod:`.channel` (the result channel),
:mod:`.confinement` (the backends, what a box sees, box folders), :mod:`.fence` (what a basic box
may not read), :mod:`.outside` (a class's own folders hidden from every box), :mod:`.limits`
(rlimits, the box's cgroup and uid: :mod:`._cgroup`, :mod:`._boxuser`), :mod:`.procs` (prctl,
the process table: /proc on Linux, psutil elsewhere; the checked kill), :mod:`.box` (one box
run and supervised), :mod:`.launch` (its first process started, cold or warm), :mod:`.clock`
(its fair deadline), :mod:`.pool` (a class's items),
:mod:`.child` (host-side work under limits).  The layer imports nothing of gpsaccel above it
and names none of it: it knows neither the checks nor the homework, and its callers say what
their boxes may not read.
"""

from __future__ import annotations

from gpsaccel.sandbox.box import run
from gpsaccel.sandbox.channel import (
                                      FRAME_COUNTS,
                                      FRAME_FIELDS,
                                      MAX_HEADER,
                                      MAX_TEXT,
                                      FrameReader,
                                      Refused,
)
from gpsaccel.sandbox.child import ChildResult, in_child
from gpsaccel.sandbox.confinement import (
                                      BACKENDS,
                                      BOX_PREFIX,
                                      PACKAGE_DIR,
                                      basic_is_safe,
                                      bwrap_path,
                                      refuse_unsafe_basic,
                                      resolve_backend,
                                      sweep_stale_boxes,
)
from gpsaccel.sandbox.fence import NoFence
from gpsaccel.sandbox.outside import hiding
from gpsaccel.sandbox.pool import Lost, run_items
from gpsaccel.sandbox.spec import BoxResult, Call, Limits, Output
from gpsaccel.sandbox.submission import (
                                      MAX_BYTES,
                                      MAX_DEPTH,
                                      MAX_ENTRIES,
                                      MAX_FILES,
                                      Submission,
                                      SubmissionError,
                                      defines,
                                      load_submission,
)
from gpsaccel.sandbox.zygote import COURSE_IMPORTS, Warm, warm_boxes

__all__ = [
    "BACKENDS", "BOX_PREFIX", "COURSE_IMPORTS", "FRAME_COUNTS", "FRAME_FIELDS", "MAX_BYTES",
    "MAX_DEPTH", "MAX_ENTRIES", "MAX_FILES", "MAX_HEADER", "MAX_TEXT", "PACKAGE_DIR",
    "BoxResult", "Call", "ChildResult", "FrameReader", "Limits", "Lost", "NoFence", "Output",
    "Refused", "Submission", "SubmissionError", "Warm", "basic_is_safe", "bwrap_path",
    "defines", "hiding", "in_child", "load_submission", "refuse_unsafe_basic", "resolve_backend", "run",
    "run_items", "sweep_stale_boxes", "warm_boxes",
]
