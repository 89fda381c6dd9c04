"""A process the student's code forks never answers for the runner (issue 43): a copy of the
runner made by ``os.fork()`` in the file's import or in a call ends where it would send a frame,
so the box's results are the runner's own, none is refused, and the box says where the fork was
(``BoxResult.forked``); the checker says it to the student as the warning ``forked``, with the
lesson section under it.  Under every backend, cold and warm."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb
from gpsaccel._taught import NOT_RUN

from .._hostile import SUBMISSIONS

LIMITS = sb.Limits(memory=512 << 20, processes=8, time=20)

#: The student's file, forking in its import (-1) or in call 1.  The copy prints, then goes back
#: into the runner with an answer of its own (99); the runner's process waits until the copy has
#: ended, so the copy has always reached the runner's writer before the runner's own answer: the
#: order that lost the notebook's answers, made certain.  Before the fix the copy went on with the
#: plan (its 99 taken for call 1, its 'done' ending the channel) and the runner's frames were
#: refused.
FORKS = {
    -1: ("import os\n\n"
         "pid = os.fork()\n"
         "if pid == 0:\n"
         "    print('COPY', flush=True)\n"
         "else:\n"
         "    os.waitpid(pid, 0)\n\n\n"
         "def f(i):\n"
         "    return i + 1.0\n"),
    1: ("import os\n\n\n"
        "def f(i):\n"
        "    if i == 1:\n"
        "        pid = os.fork()\n"
        "        if pid == 0:\n"
        "            print('COPY', flush=True)\n"
        "            return 99.0\n"
        "        os.waitpid(pid, 0)\n"
        "    return i + 1.0\n"),
}


@pytest.mark.parametrize("at", list(FORKS), ids=["import", "call"])
def test_a_forked_copy_never_answers_for_the_runner(tmp_path, backend, at):
    (tmp_path / "student.py").write_text(FORKS[at])
    sub = sb.load_submission(tmp_path / "student.py", "f")
    calls = [sb.Call("f", (np.array(float(i)),), (sb.Output("y", ()),)) for i in range(4)]
    box = sb.run(sub, calls, LIMITS, backend)
    assert "COPY" in box.output  # the copy ran, and returned into the runner
    assert box.failure is None, (box.failure, box.detail)
    assert [float(r["y"]) for r in box.results] == [1.0, 2.0, 3.0, 4.0]  # the runner's, not 99
    assert box.forked == at


def test_the_checker_warns_of_a_fork_and_names_the_run(tmp_path, backend):
    """A correct filter that forks in its first call (run 0): it passes, its copy's answer (the same)
    never reaches the checker, and the student is told where, with the section that teaches it."""
    source = (SUBMISSIONS / "correct_joseph.py").read_text(encoding="utf-8")
    assert source.count("def kalman_filter(") == 1
    path = tmp_path / "forks.py"  # the file alone is checked: the filter renamed, in it
    path.write_text(source.replace("def kalman_filter(", "def _filter(") +
                    "\n\nimport os\n\n_calls = []\n\n\n"
                    "def kalman_filter(z):\n"
                    "    _calls.append(os.fork() if not _calls else 0)\n"
                    "    return _filter(z)\n")
    report = check.submission(path, n_runs=3, seed=1, sandbox=backend)
    assert report.passed, report
    (forked,) = [f for f in report.for_student().findings if f.code == "forked"]
    assert forked.severity == "warning"
    assert "forked its process on run 0 " in forked.message, forked.message
    assert forked.see() == f"→ {NOT_RUN.cite()}"
