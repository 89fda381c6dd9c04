"""check.problem: what every problem's check does with a submission that breaks the contract
(no such function, a wrong shape, NaN, an exception), the problems' names, and the command line
on the coop and ship problems; and that the checker's modules import no circle."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from gpsaccel import check
from gpsaccel.check import problems

SUBS = Path(__file__).resolve().parent.parent / "submissions"
COOP, SHIP = SUBS / "coop", SUBS / "ship"


def test_contract_failures_become_findings(tmp_path):
    calib = SUBS / "correct_covariance.py"  # defines kalman_filter, not ekf/lkf
    report = check.submission(calib, problem="coop", n_runs=2)
    assert report.codes == ["no-function"] and "ekf(y, Q, R)" in str(report)
    bad = tmp_path / "shape.py"
    bad.write_text("import numpy as np\ndef multirate_filter(z, u):\n"
                   "    return np.zeros((999, 9)), np.zeros((999, 9, 9))\n")
    report = check.submission(bad, problem="ship", n_runs=2)
    assert report.codes == ["wrong-shape"] and "1000 rows" in str(report)
    nan = tmp_path / "nan.py"
    nan.write_text("import numpy as np\ndef ekf(y, Q, R):\n"
                   "    return np.full((len(y), 6), np.nan), np.zeros((len(y), 6, 6))\n")
    assert check.submission(nan, problem="coop", n_runs=2).codes == ["nan-output"]
    boom = tmp_path / "boom.py"
    boom.write_text("def lkf(y, Q, R):\n    raise RuntimeError('no nominal')\n")
    report = check.submission(boom, problem="coop", n_runs=2)
    assert report.codes == ["exception"] and "no nominal" in str(report)


def test_problem_names_are_validated():
    with pytest.raises(ValueError, match="problem"):
        check.submission(COOP / "correct_ekf_closed_form.py", problem="rocket")
    assert isinstance(problems.get("ship").describe(), str)
    assert np.isfinite(problems.get("coop").Q("ekf")).all()


def test_cli_check_problem_ship_and_coop(tmp_path, capsys):
    import json

    from gpsaccel.cli import main

    for name in ("correct_covariance.py", "mutant_no_input.py"):
        (tmp_path / name).write_text((SHIP / name).read_text(encoding="utf-8"), encoding="utf-8")
    out = tmp_path / "ship.json"
    rc = main(["check", str(tmp_path), "--problem", "ship", "--runs", "2", "--workers", "1",
               "--json", str(out)])
    assert rc == 1
    text = capsys.readouterr().out
    assert "no-input" in text and "1 of 2 passed" in text and "problem ship" in text
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["settings"]["problem"] == "ship"
    assert {r["subject"]: r["codes"] for r in data["results"]} == {
        "correct_covariance.py": [], "mutant_no_input.py": ["no-input"]}
    rc = main(["check", str(COOP / "correct_ekf_closed_form.py"), "--problem", "coop",
               "--runs", "2", "--workers", "1"])
    assert rc == 0


def _check_imports() -> dict[str, set[str]]:
    """module -> the gpsaccel.check modules it imports (every import, lazy ones too), read with
    ast from gpsaccel/check/."""
    root = Path(check.__file__).resolve().parent
    names = {}
    for p in root.rglob("*.py"):
        parts = ("gpsaccel", "check") + p.relative_to(root).with_suffix("").parts
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    graph: dict[str, set[str]] = {}
    for name, p in names.items():
        found = set()
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                found |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                found |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
        graph[name] = {m for m in found if m in names and m != name}
    return graph


def _circle(graph: dict[str, set[str]]) -> list[str]:
    """One import circle of ``graph`` (the modules in order), or []."""
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(m: str) -> list[str]:
        state[m] = 1
        path.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                return path[path.index(n):] + [n]
            if n not in state and (found := visit(n)):
                return found
        state[m] = 2
        path.pop()
        return []

    for m in sorted(graph):
        if m not in state and (found := visit(m)):
            return found
    return []


def test_the_checker_imports_no_circle():
    """check/linear imported check/problems for the base class while Problem.linear imported
    check/linear (issue 31); the base class is check/problem, and check/problems attaches
    Problem.linear from above both."""
    graph = _check_imports()
    assert "gpsaccel.check.problem" in graph["gpsaccel.check.linear"]
    assert _circle(graph) == []
    assert _circle({**graph, "gpsaccel.check.problem": graph["gpsaccel.check.problem"]
                    | {"gpsaccel.check.linear"}}) != []  # the old one would be found


def test_problem_linear_is_there_on_every_public_path():
    from gpsaccel.check.linear import ModelProblem
    from gpsaccel.check.problems import Problem

    assert check.Problem is Problem
    made = Problem.linear("circle-test", Phi=[[1.0]], Gamma=[[1.0]], W=[[1.0]], H=[[1.0]],
                          V=[[1.0]], M0=[[1.0]], x0=[0.0], every=1, n_epochs=3, register=False)
    assert isinstance(made, ModelProblem) and isinstance(made, Problem)
