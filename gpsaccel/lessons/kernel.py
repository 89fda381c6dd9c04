"""Executing a lesson top to bottom in a kernel of its own, as nobody's front end.

The kernel talks over Unix sockets in a private folder (:func:`_local_kernel`) and is told, through
:data:`~gpsaccel.lessons.HEADLESS_VARIABLE`, that no slider can move.  Its temporary folder
(``TMPDIR``) is a private one too, looked at once the kernel has stopped: what a lesson left there
is recorded in the executed notebook (:data:`LEFT`), so a test can hold every lesson to leaving
nothing behind in a student's ``/tmp``, and then removed.
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

from gpsaccel.lessons import HEADLESS_VARIABLE, RUNS_VARIABLE

#: The kernel's command-line setting that saves inline figures uncropped (``crop_figures=False``).
UNCROPPED = "--InlineBackend.print_figure_kwargs={'bbox_inches': None}"
#: The kernel's start-up line that draws inline figures without their layout engine
#: (:func:`draw_without_layout`); it binds no name in the lesson's namespace.
UNLAID = ("--IPKernelApp.exec_lines="
          "__import__('gpsaccel.lessons.kernel').lessons.kernel.draw_without_layout()")

#: Where :func:`execute` records what the lesson left in its temporary folder once its kernel
#: stopped: ``nb.metadata["gpsaccel"]["left_in_tmp"]``, the names (none for a lesson that cleans
#: up after itself).
LEFT = "left_in_tmp"

#: Kept in a temporary folder on purpose, by the sandbox of a lesson that runs the checker: the
#: lock files of its box users (:mod:`gpsaccel.sandbox`), shared by every check of the machine.
KEPT_IN_TMP = ("gpsaccel-uids",)


def execute(path: Path | str, timeout: int = 600, runs: int | None = None,
            crop_figures: bool = True):
    """Execute a notebook top to bottom in its own folder; returns the executed ``NotebookNode``.

    ``runs`` sets ``GPSACCEL_LESSON_RUNS`` for the kernel; ``GPSACCEL_HEADLESS`` tells slider cells
    that nobody can move them (:func:`sliders`).  A cell that raises raises
    ``nbclient.exceptions.CellExecutionError`` here.

    ``crop_figures=False`` saves each inline figure uncropped (IPython's ``bbox_inches="tight"``
    draws every figure twice: once to measure, once to save) and without running its layout
    engine (:func:`draw_without_layout`): every artist of every figure is still drawn, so a
    label that cannot be drawn still raises, at a fraction of a figure's cost (constrained
    layout measures every tick label of every axes).  For a run whose pictures nobody looks
    at (the test suite's); the pages and JupyterLab show the laid-out, cropped ones.

    The kernel's ``TMPDIR`` is a fresh folder, and the kernel is stopped as JupyterLab stops it
    (a shutdown request, so its clean-up runs); whatever is left there is listed in
    ``nb.metadata["gpsaccel"]["left_in_tmp"]`` (:data:`LEFT`) and then removed.
    """
    import nbformat
    from nbclient import NotebookClient

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    env_before = os.environ.get(RUNS_VARIABLE)
    headless_before = os.environ.get(HEADLESS_VARIABLE)
    if runs is not None:
        os.environ[RUNS_VARIABLE] = str(runs)
    os.environ[HEADLESS_VARIABLE] = "1"
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        with tempfile.TemporaryDirectory(prefix="gpsaccel-lesson-tmp-") as scratch:
            with _local_kernel() as km:
                NotebookClient(nb, km=km, timeout=timeout, kernel_name="python3",
                               resources={"metadata": {"path": str(path.parent)}},
                               extra_arguments=[] if crop_figures else [UNCROPPED, UNLAID]
                               ).execute(env=dict(os.environ, TMPDIR=scratch))
            left = sorted(set(os.listdir(scratch)) - set(KEPT_IN_TMP))
    finally:
        if runs is not None:
            if env_before is None:
                os.environ.pop(RUNS_VARIABLE, None)
            else:
                os.environ[RUNS_VARIABLE] = env_before
        if headless_before is None:
            os.environ.pop(HEADLESS_VARIABLE, None)
        else:
            os.environ[HEADLESS_VARIABLE] = headless_before
    nb.metadata.setdefault("gpsaccel", {})[LEFT] = left
    return nb


def draw_without_layout() -> None:
    """In this kernel, draw every inline figure with no layout engine.

    IPython saves an inline figure through ``IPython.core.pylabtools.print_figure``, which
    ``%matplotlib inline`` binds when it runs (after this, a kernel start-up line): this wraps
    it to take the figure's layout engine away for the save and give it back after, so the
    figure itself is unchanged.  Not even a placeholder engine: matplotlib draws a figure that
    has any engine twice (once, rendering nothing, to lay it out).  Only for :func:`execute`
    with ``crop_figures=False``.
    """
    import matplotlib
    from IPython.core import pylabtools

    original = pylabtools.print_figure
    no_default = {"figure.autolayout": False, "figure.constrained_layout.use": False}

    def print_figure(fig, *args, **kwargs):
        engine = fig.get_layout_engine()
        if engine is None:
            return original(fig, *args, **kwargs)
        with matplotlib.rc_context(no_default):
            fig.set_layout_engine(None)                   # None: the rc default, here none
        try:
            return original(fig, *args, **kwargs)
        finally:
            fig.set_layout_engine(engine)

    pylabtools.print_figure = print_figure


@contextmanager
def _local_kernel():
    """A kernel manager whose kernel talks over Unix sockets in a private temporary folder.

    The default TCP transport makes every kernel warn "Kernel is running over TCP without
    encryption" on the terminal of ``gpsaccel lessons``; the kernel runs on this machine only, so
    IPC sockets (readable by this user alone) are both quieter and safer.  The kernel is shut down
    as a front end shuts it down (a request it answers by running its exit handlers: a lesson's
    ``tempfile.TemporaryDirectory`` is removed then; killed only if it does not stop within
    jupyter_client's wait) and the folder removed on exit.
    """
    from jupyter_client.manager import KernelManager

    with tempfile.TemporaryDirectory(prefix="gpsaccel-kernel-") as folder:
        km = KernelManager(kernel_name="python3", transport="ipc", ip=os.path.join(folder, "kernel"))
        try:
            yield km
        finally:
            if km.has_kernel:
                km.shutdown_kernel()
