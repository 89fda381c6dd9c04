"""Fingerprints of answer code (gpsaccel.assignments.pruning and .fingerprint): what a copier changes
(names, layout, order, dead padding) changes nothing; what an honest answer computes is kept."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gpsaccel.assignments import fingerprint as fp
from gpsaccel.assignments.pruning import prune

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import _similarity_classes as sc  # noqa: E402

FILTER = '''
import numpy as np

def kalman_filter(z):
    """The filter."""
    dt = 0.005
    Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
    Gamma = -np.array([[dt**2 / 2], [dt], [0.0]])
    Q = Gamma @ Gamma.T * 0.02**2
    H = np.eye(2, 3)
    V = np.diag([1.0, 0.04**2])
    x, P = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    xs, Ps = np.zeros((len(z), 3)), np.zeros((len(z), 3, 3))
    for k in range(len(z)):
        if k > 0:
            for _ in range(40):
                x = Phi @ x
                P = Phi @ P @ Phi.T + Q
        S = H @ P @ H.T + V
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z[k] - H @ x)
        P = (np.eye(3) - K @ H) @ P
        xs[k], Ps[k] = x, P
    return xs, Ps
'''

# the same filter with every kind of dead code the pruner drops, and names changed
PADDED = '''
import numpy as np

def kalman_filter(meas):
    "a docstring"
    step = 0.005
    junk = step * 3
    junk2 = junk + 1          # only read by dead code: dead too
    scratch = []
    scratch.append(junk2)     # mutates a dead local
    table = {}
    table["k"] = 1
    A = np.array([[1.0, step, -step**2 / 2], [0.0, 1.0, -step], [0.0, 0.0, 1.0]])
    B = -np.array([[step**2 / 2], [step], [0.0]])
    pass
    "a string statement"
    step + 1
    Qd = B @ B.T * 0.02**2
    if False:
        Qd = None
    while 0:
        A = None
    for _unused in range(0):
        pass
    C = np.eye(2, 3)
    R = np.diag([1.0, 0.04**2])
    est, cov = np.zeros(3), np.diag([100.0, 1.0, 0.01])
    out1, out2 = np.zeros((len(meas), 3)), np.zeros((len(meas), 3, 3))
    for i in range(len(meas)):
        counter = 0
        counter += 1
        if i > 0:
            for _ in range(40):
                est = A @ est
                cov = A @ cov @ A.T + Qd
        S = C @ cov @ C.T + R
        G = cov @ C.T @ np.linalg.inv(S)
        est = est + G @ (meas[i] - C @ est)
        cov = (np.eye(3) - G @ C) @ cov
        out1[i], out2[i] = est, cov
    return out1, out2
    print("never runs")
    out1 = None
'''


def toks(code: str) -> list[int]:
    return fp.answer_tokens(ast.parse(code).body)


def test_dead_code_and_names_change_nothing():
    assert toks(PADDED) == toks(FILTER)


def test_a_real_change_changes_the_tokens():
    assert toks(FILTER.replace("P = (np.eye(3) - K @ H) @ P", "P = P - K @ S @ K.T")) != \
        toks(FILTER)
    # a value computed and used is never dropped, however it is spelled
    assert toks(FILTER.replace("x = x + K @ (z[k] - H @ x)",
                               "r = z[k] - H @ x\n        x = x + K @ r")) != toks(FILTER)


def test_swapping_independent_statements_or_functions_changes_nothing():
    a = "def f(x):\n    a = x + 1\n    b = x * 2\n    return a - b\n\ndef g(y):\n    return y\n"
    b = "def g(y):\n    return y\n\ndef f(x):\n    b = x * 2\n    a = x + 1\n    return a - b\n"
    assert toks(a) == toks(b)
    # swapping statements that depend on each other is not a reordering: different code
    c = "def f(x):\n    a = x + 1\n    a = a * 2\n    return a\n"
    d = "def f(x):\n    a = a * 2\n    a = x + 1\n    return a\n"
    assert toks(c) != toks(d)


def test_what_leaves_the_function_is_kept():
    """Writes into a parameter, a global, a returned list; a function calling locals()."""
    code = ("def f(P, out):\n    global G\n    G = 3\n    P[0] = 1\n    acc = []\n"
            "    acc.append(2)\n    out.append(acc)\n    return None\n")
    pruned = prune(ast.parse(code).body)
    assert ast.unparse(pruned[0]).count("\n") == code.count("\n") - 1  # every statement kept
    dyn = "def f():\n    x = 1\n    return locals()\n"
    assert len(prune(ast.parse(dyn).body)[0].body) == 2


def test_no_honest_answer_collapses():
    """Every generated honest answer and the masters' solutions keep their returns, calls into
    what is returned and at least 85 % of their tokens (docstrings, unused helpers' variables
    and the like are what goes)."""
    rng = np.random.default_rng(0)
    answers = [g(rng) for _ in range(60) for g in (sc.q2, sc.q3)]
    answers.append(FILTER)
    for code in answers:
        full = fp.tokens(ast.parse(code).body)
        kept = toks(code)
        assert len(kept) >= 0.85 * len(full), code
        returns = sum(isinstance(n, ast.Return) for n in ast.walk(ast.parse(code)))
        assert sum(isinstance(n, ast.Return) for s in prune(ast.parse(code).body)
                   for n in ast.walk(s)) == returns


def test_fingerprints_agree_across_processes():
    """Token ids are CRC-32s and k-gram hashes are hashes of int tuples: no process salt
    (PYTHONHASHSEED) changes them, so records made in other processes compare."""
    script = ("import ast,sys; from gpsaccel.assignments import fingerprint as fp; "
              "print(sorted(fp.kgrams(fp.answer_tokens(ast.parse(sys.stdin.read()).body)))"
              "[:20])")
    outs = set()
    for seed in ("1", "2"):
        proc = subprocess.run([sys.executable, "-c", script], input=FILTER, text=True,
                              capture_output=True, env=dict(os.environ, PYTHONHASHSEED=seed),
                              timeout=60, check=True)
        outs.add(proc.stdout)
    assert len(outs) == 1
    assert outs == {str(sorted(fp.kgrams(toks(FILTER)))[:20]) + "\n"}


def test_literal_matrices_are_one_token():
    """A model matrix written out says nothing about who wrote it: one token, whatever its
    entries and their spelling."""
    a = toks("Phi = np.array([[1.0, dt, -dt**2 / 2], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])")
    b = toks("Phi = np.array([[1, dt, -0.5 * dt * dt], [0, 1, -dt], [0, 0, 1]])")
    assert a == b and len(a) == 6


@pytest.mark.parametrize("code", ["x = " + "(" * 90 + "1" + ")" * 90, "x = " + "-" * 900 + "1",
                                  "\n".join(f"a{i} = a{i - 1}" for i in range(1, 3000))])
def test_deep_or_long_code_is_tokenized_in_bounds(code):
    out = toks(code)
    assert 0 < len(out) <= fp.MAX_TOKENS
