"""Where parallel work runs: in-process, a local process pool, or a Dask cluster.

Every parallel entry point of gpsaccel (the Monte Carlo engine, the homework checkers) takes an
``executor`` and submits plain functions to it through the :class:`concurrent.futures.Executor`
interface, so one mechanism serves one laptop and a cluster alike.  :func:`resolve_executor` turns
what a user typed into such an executor and remembers whether it opened it, so that leaving the
``with`` block closes only what it opened::

    from gpsaccel.executors import resolve_executor
    with resolve_executor("processes", max_workers=2) as ex:
        futures = [ex.submit(pow, 2, k) for k in range(4)]
        print([f.result() for f in futures])

Accepted specifications
-----------------------
=============================  ==========================================================
``None``, ``"inprocess"``      :class:`InProcessExecutor`: runs each call at ``submit``, in
                               this process, in submission order (the default; no pool).
``"threads"``                  :class:`concurrent.futures.ThreadPoolExecutor`.
``"processes"``, ``"local"``   :class:`concurrent.futures.ProcessPoolExecutor`.
``"dask-local"``               a ``dask.distributed.LocalCluster`` on this machine and its
                               ``Client``'s executor (both closed on exit).
``"tcp://host:port"``          a ``Client`` connected to a running Dask scheduler (the
                               client is closed on exit, the cluster is left running).
a ``concurrent.futures``       used as is and *not* shut down on exit (its owner does that);
``Executor``                   ``dask.distributed.Client(...).get_executor()`` is one.
a ``dask.distributed.Client``  its ``get_executor()``; the client is not closed on exit.
=============================  ==========================================================

Dask is an optional extra (``pip install gpsaccel[dask]``); asking for a Dask specification
without it raises a ValueError that says so.  Functions submitted to a process pool or a Dask
cluster must be picklable: module-level functions with picklable arguments.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import threading
from collections.abc import Callable
from typing import Any, TypeGuard

#: The string specifications :func:`resolve_executor` understands (besides ``tcp://host:port``).
NAMED_SPECS = ("inprocess", "threads", "processes", "local", "dask-local")


class InProcessExecutor(cf.Executor):
    """An executor with no workers: ``submit`` runs the call at once and returns a done Future.

    Exceptions raised by the call are stored in the Future (as a pool would), so code written
    for a real pool behaves the same with this one.  Submitting after :meth:`shutdown` raises
    ``RuntimeError`` like the standard executors.
    """

    def __init__(self) -> None:
        self._shutdown = False
        self._lock = threading.Lock()

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        with self._lock:
            if self._shutdown:
                raise RuntimeError("cannot schedule new futures after shutdown")
        future: cf.Future = cf.Future()
        future.set_running_or_notify_cancel()
        try:
            result = fn(*args, **kwargs)
        except BaseException as exc:  # stored, re-raised by future.result()
            future.set_exception(exc)
        else:
            future.set_result(result)
        return future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        with self._lock:
            self._shutdown = True

    def __repr__(self) -> str:
        return "InProcessExecutor()"


class ResolvedExecutor:
    """An executor together with what must be closed when the work is done.

    Attributes
    ----------
    executor : the :class:`concurrent.futures.Executor` to submit to.
    description : a short human-readable name (``"in-process"``, ``"dask tcp://..."``, ...).
    owned : True when :func:`resolve_executor` created it (it is then shut down by :meth:`close`).
    max_workers : the number of parallel workers when known, else None.

    Use it as a context manager; :meth:`close` is idempotent.
    """

    def __init__(self, executor: cf.Executor, description: str, owned: bool,
                 max_workers: int | None = None,
                 closers: list[Callable[[], None]] | None = None) -> None:
        self.executor = executor
        self.description = description
        self.owned = owned
        self.max_workers = max_workers
        self._closers = list(closers or [])
        self._closed = False

    def close(self) -> None:
        """Shut down what was opened here (pool, Dask client, LocalCluster), in reverse order."""
        if self._closed:
            return
        self._closed = True
        errors = []
        for closer in reversed(self._closers):
            try:
                closer()
            except Exception as exc:  # close everything, then report the first failure
                errors.append(exc)
        if errors:
            raise errors[0]

    def __enter__(self) -> cf.Executor:
        return self.executor

    def __exit__(self, exc_type: type | None, *exc_info: object) -> None:
        if (exc_type is not None and issubclass(exc_type, KeyboardInterrupt) and self.owned
                and isinstance(self.executor, cf.ThreadPoolExecutor | cf.ProcessPoolExecutor)):
            # interrupted: drop the queued tasks instead of running them before shutting down
            self.executor.shutdown(wait=False, cancel_futures=True)
        self.close()

    def __repr__(self) -> str:
        return f"ResolvedExecutor({self.description!r}, owned={self.owned})"


_IN_TASK = False  # per worker process: is a task running?


def _worker_sigint(signum: int, frame: object) -> None:
    """SIGINT in a pool worker: interrupt the task it runs (its ``finally`` blocks run, e.g. the
    checker kills the student's process), ignore it between tasks (where a KeyboardInterrupt
    would kill the worker with a traceback)."""
    if _IN_TASK:
        raise KeyboardInterrupt


def _worker_init() -> None:
    import signal

    signal.signal(signal.SIGINT, _worker_sigint)


def _in_task(fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Any:
    global _IN_TASK
    _IN_TASK = True
    try:
        return fn(*args, **kwargs)
    finally:
        _IN_TASK = False


class _InterruptiblePool(cf.ProcessPoolExecutor):
    """A process pool for Ctrl-C: it reaches the whole process group, so every worker gets SIGINT
    too.  A worker running a task stops it (the KeyboardInterrupt comes back through the task's
    Future, as any exception does); an idle worker ignores it.  The parent handles it alone: one
    "interrupted" line, no traceback per worker, no task left running."""

    def __init__(self, max_workers: int | None = None) -> None:
        super().__init__(max_workers=max_workers, initializer=_worker_init)

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        return super().submit(_in_task, fn, *args, **kwargs)


def is_executor(obj: object) -> TypeGuard[cf.Executor]:
    """True for a :class:`concurrent.futures.Executor` (a Dask ``ClientExecutor`` is one)."""
    return isinstance(obj, cf.Executor)


def resolve_executor(spec: object = None, max_workers: int | None = None) -> ResolvedExecutor:
    """Turn ``spec`` (see the module docstring) into a :class:`ResolvedExecutor`.

    ``max_workers`` sizes the pools this function creates (threads, processes, the workers of a
    Dask LocalCluster); default: the number of CPUs (``os.cpu_count()``).  It is ignored for an
    executor, a client or a ``tcp://`` address, whose size someone else chose.

    Raises ValueError naming ``executor`` for anything else (an unknown string, a non-executor
    object) and for a Dask specification when Dask is not installed.
    """
    if max_workers is not None:
        from gpsaccel import _validation as _v

        max_workers = _v.integer("max_workers", max_workers, minimum=1)
    if spec is None or spec == "inprocess":
        ex = InProcessExecutor()
        return ResolvedExecutor(ex, "in-process", True, 1, [ex.shutdown])
    if is_executor(spec):
        return ResolvedExecutor(spec, type(spec).__name__, False, _known_workers(spec))
    if _is_dask_client(spec):
        client: Any = spec
        return ResolvedExecutor(client.get_executor(), f"dask client "
                                f"{client.scheduler.address}", False, _dask_workers(client))
    if not isinstance(spec, str):
        raise ValueError(
            f"executor must be None, a concurrent.futures.Executor, a dask.distributed.Client, "
            f"one of {', '.join(map(repr, NAMED_SPECS))} or 'tcp://host:port'; "
            f"got {type(spec).__name__}"
        )
    n = max_workers or os.cpu_count() or 1
    if spec == "threads":
        threads = cf.ThreadPoolExecutor(max_workers=n)
        return ResolvedExecutor(threads, f"{n} threads", True, n, [threads.shutdown])
    if spec in ("processes", "local"):
        pool = _InterruptiblePool(max_workers=n)
        return ResolvedExecutor(pool, f"{n} processes", True, n, [pool.shutdown])
    if spec == "dask-local":
        distributed = _import_distributed()
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=None)
        try:
            client = distributed.Client(cluster)
        except Exception:
            cluster.close()
            raise
        return ResolvedExecutor(client.get_executor(), f"dask LocalCluster ({n} workers)", True,
                                n, [cluster.close, client.close])
    if spec.startswith("tcp://"):
        distributed = _import_distributed()
        try:
            client = distributed.Client(spec, timeout=30)
        except OSError as exc:
            raise ValueError(f"executor: cannot reach the Dask scheduler at {spec}: {exc}") from None
        return ResolvedExecutor(client.get_executor(), f"dask {spec}", True,
                                _dask_workers(client), [client.close])
    raise ValueError(
        f"executor must be one of {', '.join(map(repr, NAMED_SPECS))}, 'tcp://host:port', an "
        f"Executor or None; got {spec!r}"
    )


def _known_workers(ex: cf.Executor) -> int | None:
    if isinstance(ex, InProcessExecutor):
        return 1
    n = getattr(ex, "_max_workers", None)
    return n if isinstance(n, int) else None


def _is_dask_client(obj: object) -> bool:
    cls = type(obj)
    return cls.__name__ == "Client" and cls.__module__.startswith("distributed")


def _dask_workers(client: Any) -> int | None:
    try:
        return max(1, sum(client.nthreads().values()))
    except Exception:  # a scheduler that does not answer now; the work will tell
        return None


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ValueError(
            "executor: Dask is not installed; install the optional extra "
            "(pip install 'gpsaccel[dask]') or use 'processes'"
        ) from None
    return distributed
