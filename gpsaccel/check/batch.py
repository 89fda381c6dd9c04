"""Check many submissions at once, in parallel, for an instructor (``gpsaccel check PATH ...``).

Each submission is checked by :func:`gpsaccel.check.submission` in a worker of an executor from
:func:`gpsaccel.executors.resolve_executor` — local processes by default, a Dask cluster on
request — and each worker starts the student's code in a child process of its own, as a single
check does.  Results come back as plain dictionaries (:meth:`Report.to_dict` plus the text), so
any executor can carry them.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from gpsaccel import _validation as _v
from gpsaccel._atomic import write_text
from gpsaccel.check.whole_filter import submission
from gpsaccel.executors import resolve_executor


def find_submissions(paths: Iterable[str | os.PathLike]) -> tuple[list[Path], list[str]]:
    """The ``.py`` files named by ``paths`` (files, or folders searched recursively), sorted.

    In a folder every ``.py`` file counts except ``__init__.py``, hidden folders and
    ``__pycache__``: a student who misnamed the function must show up as ``no-kalman-filter``,
    not vanish.  Returns (files, messages about what was skipped).
    """
    files: list[Path] = []
    notes: list[str] = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(f for f in p.rglob("*.py")
                           if not any(part.startswith(".") or part == "__pycache__"
                                      for part in f.relative_to(p).parts))
            for f in found:
                if f.name == "__init__.py":
                    notes.append(f"{f}: skipped (a package's __init__.py)")
                else:
                    files.append(f)
            if not found:
                notes.append(f"{p}: no .py file in this folder")
        else:
            files.append(p)  # a missing file becomes a "not-found" finding, not an error here
    return list(dict.fromkeys(files)), notes


def _check_one(path: str, n_runs: int, seed: int, timeout: float) -> dict:
    report = submission(path, n_runs=n_runs, seed=seed, timeout=timeout)
    out = report.to_dict()
    out["text"] = str(report)
    return out


def check_many(paths: Sequence[str | os.PathLike], n_runs: int = 200, seed: int = 0,
               timeout: float = 60, executor: object = "processes",
               max_workers: int | None = None) -> list[dict]:
    """Check every file of ``paths`` (see :func:`find_submissions`); one dict per file, in order.

    ``executor`` is anything :func:`gpsaccel.executors.resolve_executor` accepts (``None`` runs
    them one after the other in this process).  Every submission sees the same realizations
    (``seed``), so their results are comparable.  ``n_runs``, ``seed`` and ``timeout`` are checked
    here, before any submission runs (a bad one would otherwise fail every check alike).
    """
    n_runs = _v.integer("n_runs", n_runs, minimum=2)
    seed = _v.integer("seed", seed, minimum=0)
    timeout = _v.positive_float("timeout", timeout)
    files, _ = find_submissions(paths)
    with resolve_executor(executor, max_workers=max_workers) as ex:
        futures = [ex.submit(_check_one, str(f), n_runs, seed, timeout) for f in files]
        results = []
        for f, fut in zip(files, futures, strict=True):
            try:
                results.append(fut.result())
            except Exception as exc:  # the checker itself failed: report it, go on
                results.append({"subject": f.name, "passed": False, "codes": ["checker-error"],
                                "findings": [{"code": "checker-error", "severity": "error",
                                              "message": f"{type(exc).__name__}: {exc}"}],
                                "details": {"path": str(f)}, "seconds": 0.0,
                                "text": f"{f.name}: checker error {type(exc).__name__}: {exc}"})
    return results


def table(results: Sequence[dict]) -> str:
    """The instructor's table: submission, passed, codes, seconds."""
    name_w = max([len(r["details"].get("path", r["subject"])) for r in results] + [10])
    head = f"{'submission':<{name_w}}  {'passed':<6}  {'seconds':>7}  codes"
    lines = [head, "-" * max(len(head), 40)]
    for r in results:
        lines.append(f"{r['details'].get('path', r['subject']):<{name_w}}  "
                     f"{'yes' if r['passed'] else 'NO':<6}  {r['seconds']:7.1f}  "
                     f"{', '.join(r['codes']) or '-'}")
    n_pass = sum(r["passed"] for r in results)
    lines.append(f"{n_pass} of {len(results)} passed")
    return "\n".join(lines)


def write_json(results: Sequence[dict], path: str | os.PathLike, **settings: object) -> Path:
    """Write ``{"settings": ..., "results": [...]}`` to ``path`` (UTF-8, indented)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"settings": settings, "results": list(results)}, indent=2,
                                ensure_ascii=False))  # whole or not at all
    return path
