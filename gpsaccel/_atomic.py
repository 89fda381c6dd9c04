"""Files written whole or not at all.

Every figure, page and JSON file the package writes goes first to a hidden temporary name in the
target's own folder and is renamed onto the target (:func:`os.replace`, atomic on POSIX) only
when it is complete.  An interrupted run (Ctrl-C, a full disk, a crash) therefore leaves either
the previous file or none, never a half-written PNG that a browser shows as broken; the temporary
file is removed on the way out.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def replacing(path: str | os.PathLike, mode: int | None = None) -> Iterator[Path]:
    """Yield a temporary path next to ``path`` (same suffix, so writers that infer the format from
    it still work); on success rename it onto ``path``, on any exception remove it and re-raise.
    ``mode``: the file's permissions (default an ordinary file's, under the umask); 0o600 keeps a
    file that holds a secret (a class's seed) from other users, a box's among them."""
    path = Path(path)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".part{path.suffix}")
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask() if mode is None else mode)  # mkstemp made it 0600
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8",
               mode: int | None = None) -> Path:
    """``Path(path).write_text(text)``, written whole (see the module docstring); ``mode`` as
    :func:`replacing` takes it."""
    with replacing(path, mode) as tmp:
        tmp.write_text(text, encoding=encoding)
    return Path(path)


def savefig(fig, path: str | os.PathLike, **kwargs) -> Path:
    """``fig.savefig(path, **kwargs)``, written whole (see the module docstring)."""
    path = Path(path)
    kwargs.setdefault("format", path.suffix.lstrip(".") or None)
    with replacing(path) as tmp:
        fig.savefig(tmp, **kwargs)
    return path
