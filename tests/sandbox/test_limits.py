"""The per-process limits (gpsaccel.sandbox.limits): set in the order that lets every box start,
whatever the grader that starts it holds."""

from __future__ import annotations

import os

import numpy as np

from gpsaccel import sandbox as sb

LIMITS = sb.Limits(memory=512 << 20, file_size=16 << 20, output=1 << 20, time=20)


def test_a_grader_holding_many_descriptors_still_starts_its_boxes(tmp_path, backend):
    """A long-lived grader (a Jupyter kernel, a Dask worker, a test worker that ran hundreds of
    boxes) may hold more descriptors than a box may open.  They are still open in the child when
    preexec runs (close_fds comes after it): with RLIMIT_NOFILE set before the root-only reveal
    mounts opened their folders, every box of such a grader failed to start."""
    (tmp_path / "student.py").write_text("def f(x):\n    return x + 1.0\n")
    sub = sb.load_submission(tmp_path / "student.py", "f")
    held = [os.open(os.devnull, os.O_RDONLY) for _ in range(LIMITS.open_files + 44)]
    try:
        box = sb.run(sub, [sb.Call("f", (np.ones(2),), (sb.Output("y", (2,)),))], LIMITS,
                     backend)
    finally:
        for fd in held:
            os.close(fd)
    assert box.failure is None, (box.failure, box.detail)
    np.testing.assert_array_equal(box.results[0]["y"], np.full(2, 2.0))
