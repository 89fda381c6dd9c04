"""A student's own copy of the lessons, and the command that opens JupyterLab on it
(``gpsaccel lessons --copy DIR``, ``gpsaccel lab DIR``)."""

from __future__ import annotations

import os
from pathlib import Path

from gpsaccel.lessons import lessons_dir, solutions_dir


def copy_lessons(target: Path | str, solutions: bool = True) -> tuple[list[Path], list[Path]]:
    """Copy the lessons (and ``solutions/``) into ``target`` for a student to edit.

    A file already in ``target`` is never overwritten (it may hold the student's work): returns
    ``(copied, kept)``, the paths written and the paths left as they were.
    """
    import shutil

    target = Path(target)
    sources = sorted(lessons_dir().glob("*.ipynb"))
    if not sources:
        raise FileNotFoundError(f"no lesson found in {lessons_dir()}")
    if solutions:
        sources += sorted(solutions_dir().glob("*.ipynb"))
    copied, kept = [], []
    for src in sources:
        dest = target / src.relative_to(lessons_dir())
        if dest.exists():
            kept.append(dest)
            continue
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, dest)
        copied.append(dest)
    return copied, kept


#: A Jupyter config directory whose ``labconfig/default_setting_overrides.json`` sets the defaults
#: of the lab gpsaccel starts: ``fetchNews`` "false", so JupyterLab does not open on "Would you like
#: to get notified about official Jupyter news?" (its setting is "none", ask, by default).
#: jupyterlab_server reads that file from every directory of the Jupyter config path, which
#: ``JUPYTER_CONFIG_PATH`` extends (:func:`lab_environment`); a student's own settings still win.
LAB_CONFIG = Path(__file__).parent / "jupyter-config"


def lab_environment(environ: dict[str, str] | None = None) -> dict[str, str]:
    """``environ`` (this process's) with :data:`LAB_CONFIG` first on ``JUPYTER_CONFIG_PATH``."""
    env = dict(os.environ if environ is None else environ)
    rest = env.get("JUPYTER_CONFIG_PATH", "")
    env["JUPYTER_CONFIG_PATH"] = os.pathsep.join([str(LAB_CONFIG), *([rest] if rest else [])])
    return env


def lab_command(folder: Path | str, port: int | None = None, browser: bool = True) -> list[str]:
    """The command that opens JupyterLab on ``folder`` with this Python (so its kernel has
    gpsaccel); ``--allow-root`` when run as root (Jupyter refuses root otherwise)."""
    import importlib.util
    import sys

    if importlib.util.find_spec("jupyterlab") is None:
        raise ModuleNotFoundError("gpsaccel lab needs JupyterLab", name="jupyterlab")
    cmd = [sys.executable, "-m", "jupyterlab", f"--notebook-dir={folder}"]
    if port is not None:
        cmd.append(f"--port={port}")
    if not browser:
        cmd.append("--no-browser")
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-root")
    return cmd
