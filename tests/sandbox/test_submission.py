"""What a submission is (gpsaccel.sandbox.load_submission): a file or a student's folder with
helpers and data, its entry found by the function it defines; what is not one is a SubmissionError
with a code, and a finding when the checker meets it."""

from __future__ import annotations

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel import sandbox as sb


def test_a_students_folder_with_helpers_and_data(tmp_path, backend):
    folder = tmp_path / "bob"
    (folder / "kf").mkdir(parents=True)
    (folder / "kf" / "__init__.py").write_text("")
    (folder / "kf" / "matrices.py").write_text(
        "import numpy as np\n\ndef load():\n"
        "    d = np.load('model.npz')\n    return d['Phi'], d['Q'], d['H'], d['V'], d['M0']\n")
    dt = 0.005
    G = np.array([[-dt**2 / 2], [-dt], [0.0]])
    np.savez(folder / "model.npz", Phi=np.array([[1, dt, -dt**2 / 2], [0, 1, -dt], [0, 0, 1]]),
             Q=G @ G.T * 0.0004, H=np.eye(2, 3), V=np.diag([1.0, 0.04**2]),
             M0=np.diag([100.0, 1.0, 0.01]))
    (folder / "filter.py").write_text(
        "import numpy as np\nfrom kf.matrices import load\n\n"
        "def kalman_filter(z):\n    Phi, Q, H, V, M = load()\n    x = np.zeros(3)\n"
        "    xs, Ps = [], []\n    for k, zk in enumerate(z):\n        if k:\n"
        "            for _ in range(40):\n                x, M = Phi @ x, Phi @ M @ Phi.T + Q\n"
        "        K = M @ H.T @ np.linalg.inv(H @ M @ H.T + V)\n"
        "        x, M = x + K @ (zk - H @ x), (np.eye(3) - K @ H) @ M\n"
        "        xs.append(x)\n        Ps.append(M)\n    return np.array(xs), np.array(Ps)\n")
    (folder / "notes.txt").write_text("my notes")
    (folder / ".git").mkdir()
    (folder / ".git" / "secret").write_text("not copied")
    sub = sb.load_submission(folder, "kalman_filter")
    assert sub.entry == "filter.py"
    assert set(sub.files) == {"filter.py", "kf/__init__.py", "kf/matrices.py", "model.npz",
                              "notes.txt"}
    report = check.submission(folder, n_runs=3, sandbox=backend)
    assert report.passed, report
    assert report.details["entry"] == "filter.py" and report.details["sandbox"] == backend


def test_what_is_not_a_submission(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "helpers.py").write_text("def propagate(x):\n    return x\n")
    with pytest.raises(sb.SubmissionError, match="defines kalman_filter") as e:
        sb.load_submission(tmp_path / "a", "kalman_filter")
    assert e.value.code == "no-function"
    (tmp_path / "a" / "one.py").write_text("def kalman_filter(z):\n    pass\n")
    (tmp_path / "a" / "two.py").write_text("from one import kalman_filter\n")
    with pytest.raises(sb.SubmissionError, match="one.py, two.py") as e:
        sb.load_submission(tmp_path / "a", "kalman_filter")
    assert e.value.code == "ambiguous-entry"
    report = check.submission(tmp_path / "a", n_runs=2)
    assert report.codes == ["ambiguous-entry"], report
    report = check.submission(tmp_path / "missing.py", n_runs=2)
    assert report.codes == ["not-found"], report
