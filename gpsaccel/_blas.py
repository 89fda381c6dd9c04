"""Run a block of small matrix products with single-threaded BLAS, then restore the thread count.

The Monte Carlo engine multiplies many small matrices (3x3 by 3 x 1000) and one medium one
(302 x 1000 by its transpose) per block.  OpenBLAS threads the larger products, and its worker
threads then spin between calls; on a machine with 2 cores that are also busy, that makes the
whole block several times slower than one thread.
Parallelism belongs to the executor's workers instead.

:func:`single_threaded_blas` finds the OpenBLAS libraries loaded in this process (numpy's and
scipy's bundled ``scipy_openblas``, or a system ``openblas``), sets them to one thread, and restores
the previous counts when the last concurrent user leaves (a counter under a lock, so overlapping
users in threads of one process are safe).  Where no such library is found (another BLAS, another
operating system) it does nothing.  This is what ``threadpoolctl`` does, for the one library kind
gpsaccel meets, without adding a dependency.
"""

from __future__ import annotations

import ctypes
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import lru_cache

_SYMBOLS = (  # (set, get) pairs, as exported by the OpenBLAS builds numpy and scipy ship
    ("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
    ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
    ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
    ("openblas_set_num_threads", "openblas_get_num_threads"),
)

_lock = threading.Lock()
_depth = 0
_saved: list[tuple[Callable[[int], None], int]] = []


@lru_cache(maxsize=1)
def _controls() -> tuple[tuple[Callable[[int], None], Callable[[], int]], ...]:
    """(set, get) functions of every OpenBLAS loaded in this process (Linux: /proc/self/maps)."""
    import numpy  # noqa: F401  (load numpy's BLAS before looking for it)

    if not sys.platform.startswith("linux"):
        return ()
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
            paths = sorted({line.split()[-1] for line in maps
                            if "openblas" in line.lower() and line.split()[-1].startswith("/")})
    except OSError:
        return ()
    found = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for set_name, get_name in _SYMBOLS:
            if hasattr(lib, set_name) and hasattr(lib, get_name):
                setter, getter = getattr(lib, set_name), getattr(lib, get_name)
                setter.argtypes, setter.restype = [ctypes.c_int], None
                getter.argtypes, getter.restype = [], ctypes.c_int
                found.append((setter, getter))
                break
    return tuple(found)


@contextmanager
def single_threaded_blas() -> Iterator[None]:
    """Within the block, OpenBLAS uses one thread; the previous counts come back afterwards."""
    global _depth, _saved
    with _lock:
        if _depth == 0:
            _saved = [(setter, int(getter())) for setter, getter in _controls()]
            for setter, _ in _saved:
                setter(1)
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                for setter, n in _saved:
                    setter(n)
                _saved = []


def blas_threads() -> list[int]:
    """The current thread count of each OpenBLAS found (for tests and diagnostics)."""
    return [int(getter()) for _, getter in _controls()]
