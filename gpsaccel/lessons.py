"""Running the Jupyter lessons: their ensemble size, executing them, rendering them to HTML.

A lesson reads its Monte Carlo size with :func:`lesson_runs`, so the test suite can execute every
notebook quickly (``GPSACCEL_LESSON_RUNS=50``) while a student gets the report's full size.
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

from gpsaccel._atomic import write_text

#: The environment variable that overrides every lesson's ensemble size.
RUNS_VARIABLE = "GPSACCEL_LESSON_RUNS"


def lesson_runs(default: int) -> int:
    """The lesson's Monte Carlo size: ``$GPSACCEL_LESSON_RUNS`` if set, else ``default``."""
    raw = os.environ.get(RUNS_VARIABLE)
    if raw is None or raw == "":
        return default
    try:
        n = int(raw)
    except ValueError:
        raise ValueError(f"{RUNS_VARIABLE} must be an integer, got {raw!r}") from None
    if n < 2:
        raise ValueError(f"{RUNS_VARIABLE} must be >= 2, got {n}")
    return n


def lessons_dir() -> Path:
    """The ``lessons/`` folder of a source checkout."""
    return Path(__file__).resolve().parent.parent / "lessons"


def execute(path: Path | str, timeout: int = 600, runs: int | None = None):
    """Execute a notebook top to bottom in its own folder; returns the executed ``NotebookNode``.

    ``runs`` sets ``GPSACCEL_LESSON_RUNS`` for the kernel.  A cell that raises raises
    ``nbclient.exceptions.CellExecutionError`` here.
    """
    import nbformat
    from nbclient import NotebookClient

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    env_before = os.environ.get(RUNS_VARIABLE)
    if runs is not None:
        os.environ[RUNS_VARIABLE] = str(runs)
    os.environ.setdefault("MPLBACKEND", "Agg")
    try:
        with _local_kernel() as km:
            NotebookClient(nb, km=km, timeout=timeout, kernel_name="python3",
                           resources={"metadata": {"path": str(path.parent)}}).execute()
    finally:
        if runs is not None:
            if env_before is None:
                os.environ.pop(RUNS_VARIABLE, None)
            else:
                os.environ[RUNS_VARIABLE] = env_before
    return nb


@contextmanager
def _local_kernel():
    """A kernel manager whose kernel talks over Unix sockets in a private temporary folder.

    The default TCP transport makes every kernel warn "Kernel is running over TCP without
    encryption" on the terminal of ``gpsaccel lessons``; the kernel runs on this machine only, so
    IPC sockets (readable by this user alone) are both quieter and safer.  The kernel is shut down
    and the folder removed on exit.
    """
    from jupyter_client.manager import KernelManager

    with tempfile.TemporaryDirectory(prefix="gpsaccel-kernel-") as folder:
        km = KernelManager(kernel_name="python3", transport="ipc", ip=os.path.join(folder, "kernel"))
        try:
            yield km
        finally:
            if km.has_kernel:
                km.shutdown_kernel(now=True)


def render_html(paths: list[Path], out: Path | str, runs: int | None = None) -> list[Path]:
    """Execute ``paths`` and write each as HTML (figures embedded) into ``out``."""
    from nbconvert import HTMLExporter

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for path in paths:
        nb = execute(path, runs=runs)
        body, _ = HTMLExporter().from_notebook_node(nb)
        target = out / (Path(path).stem + ".html")
        write_text(target, body)  # whole or not at all
        written.append(target)
    return written
