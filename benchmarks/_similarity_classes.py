"""Classes of the calibration homework for measuring the similarity report (seeded).

An *honest* student writes each answer in a style drawn from the ways students write it:

* q1 (the model matrices): literals in several spellings, ``np.eye`` and entries, ``np.diag``
  from σ variables, ``np.hstack``, a helper function, in any order;
* q2 (the filter in ``kalman_filter.py``): one step or one GPS interval per propagation (a loop,
  ``matrix_power``), the gain by ``inv`` or ``solve``, the covariance update in three forms,
  preallocated arrays or lists, inline or with predict/update helpers, the model at module level
  or inside, or filterpy's ``KalmanFilter``;
* q3 (NEES): a loop or vectorised (``solve``, ``inv``, ``einsum``, Cholesky, a comprehension),
  the bounds by ``ppf``, ``interval`` or ``isf``;

every name drawn from what students call these things.  A *copy* takes another student's
answer and disguises it (``_similarity_copies``: renamed, reordered, padded with about 90 dead
statements, all three, edited by hand).  A *ring* of k students hands in k disguised copies of
one answer.  The published solution (the master's) is pasted the same ways.

Everything comes from a ``numpy.random.Generator``: the same seed gives the same class.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field

import numpy as np
from _similarity_copies import DISGUISES, pick

# ------------------------------------------------------------------------------ names
NAMES = {
    "dt": ["dt", "T", "h", "Ts", "step", "delta_t", "tau"],
    "x": ["x", "xhat", "x_est", "state", "xk", "x_post", "est"],
    "P": ["P", "Pk", "cov", "P_post", "Sigma", "C"],
    "M": ["M", "P_pred", "Pm", "P_prior", "M_k", "Ppri"],
    "xb": ["x", "x_pred", "xm", "x_prior", "xbar", "xp"],
    "K": ["K", "gain", "Kk", "L", "G"],
    "S": ["S", "Sk", "innov_cov", "S_k", "W_r"],
    "r": ["r", "y", "innov", "nu", "resid", "e"],
    "Phi": ["Phi", "F", "A", "Phi_k", "transition"],
    "Gam": ["Gamma", "G_w", "B", "Gam", "noise_in"],
    "Q": ["Q", "Qd", "Q_k", "proc_noise", "Qw"],
    "H": ["H", "Hm", "C_gps", "meas", "H_k"],
    "V": ["V", "R", "Rk", "meas_noise", "V_gps"],
    "out_x": ["x_hat", "xs", "estimates", "X", "xhist", "x_all"],
    "out_P": ["P_all", "Ps", "covs", "P_hist", "P_out", "PP"],
    "k": ["k", "i", "n", "j", "idx", "step_i"],
    "I": ["I", "I3", "eye3", "Id", "ident"],
    "e": ["e", "err", "d", "delta", "error", "diff"],
    "N": ["N", "n_runs", "runs", "num", "count", "R"],
}


def names(rng: np.random.Generator) -> dict[str, str]:
    """One student's names for each role (distinct)."""
    out: dict[str, str] = {}
    for role, opts in NAMES.items():
        free = [o for o in opts if o not in out.values()] or [f"{opts[0]}_{len(out)}"]
        out[role] = pick(rng, free)
    return out


def _cases(rng, *options: str) -> str:
    return pick(rng, list(options))


# ------------------------------------------------------------------------------ q1
def q1(rng: np.random.Generator) -> str:
    n = names(rng)
    dt = n["dt"]
    half = _cases(rng, f"{dt}**2 / 2", f"0.5 * {dt}**2", f"{dt} * {dt} / 2", f"{dt}**2/2.0")
    lines = {}
    lines["Phi"] = _cases(
        rng,
        f"Phi = np.array([[1.0, {dt}, -{half}], [0.0, 1.0, -{dt}], [0.0, 0.0, 1.0]])",
        f"Phi = np.array([[1, {dt}, -{half}],\n                [0, 1, -{dt}],\n"
        f"                [0, 0, 1]], dtype=float)",
        f"Phi = np.eye(3)\nPhi[0, 1] = {dt}\nPhi[0, 2] = -{half}\nPhi[1, 2] = -{dt}",
        f"def transition({dt}):\n    return np.array([[1, {dt}, -{half}], [0, 1, -{dt}], "
        f"[0, 0, 1]])\nPhi = transition({dt})")
    lines["Gamma"] = _cases(
        rng,
        f"Gamma = -np.array([[{half}], [{dt}], [0.0]])",
        f"Gamma = np.array([[-{half}], [-{dt}], [0]])",
        f"Gamma = np.array([-{half}, -{dt}, 0.0]).reshape(3, 1)",
        f"Gamma = np.array([-{half}, -{dt}, 0])[:, None]",
        f"Gamma = -np.array([{half}, {dt}, 0]).reshape(-1, 1)")
    lines["H"] = _cases(
        rng, "H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])",
        "H = np.hstack([np.eye(2), np.zeros((2, 1))])", "H = np.eye(2, 3)", "H = np.eye(3)[:2]",
        "H = np.array([[1, 0, 0],\n              [0, 1, 0]])")
    sig = rng.random() < 0.4
    lines["V"] = (_cases(rng, "sigma_p, sigma_v = 1.0, 0.04\nV = np.diag([sigma_p**2, sigma_v**2])",
                         "sp = 1.0\nsv = 0.04\nV = np.array([[sp**2, 0], [0, sv**2]])")
                  if sig else _cases(rng, "V = np.diag([1.0**2, 0.04**2])",
                                     "V = np.diag([1.0, 0.0016])",
                                     "V = np.array([[1.0, 0.0], [0.0, 0.04**2]])"))
    lines["W"] = _cases(rng, "W = np.array([[0.02**2]])", "W = np.eye(1) * 0.02**2",
                        "W = np.atleast_2d(0.02**2)", "W = 0.0004 * np.ones((1, 1))",
                        "sigma_w = 0.02\nW = np.array([[sigma_w**2]])")
    lines["M0"] = _cases(rng, "M0 = np.diag([10.0**2, 1.0**2, 0.1**2])",
                         "M0 = np.diag(np.array([10.0, 1.0, 0.1])**2)",
                         "M0 = np.diag([100, 1, 0.01])",
                         "s0 = [10, 1, 0.1]\nM0 = np.diag(np.square(s0))")
    head = _cases(rng, f'{dt} = 1 / VARIANT["rate_hz"]',
                  f"rate = VARIANT['rate_hz']\n{dt} = 1.0 / rate",
                  f'{dt} = 1.0 / VARIANT["rate_hz"]  # s')
    order = list(lines)
    rng.shuffle(order)
    return "\n".join([head] + [lines[k] for k in order]) + "\n"


# ------------------------------------------------------------------------------ q2
class Style:
    """One student's habits, used throughout their answers: how they write a matrix product,
    a transpose, an identity, an update in place."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.prod = pick(rng, ["@", "@", "@", "np.dot", ".dot"])
        self.tr = pick(rng, [".T", ".T", ".T", ".transpose()"])
        self.eye = pick(rng, ["np.eye(3)", "np.eye(3)", "np.identity(3)"])
        self.inplace = rng.random() < 0.3

    def mm(self, *args: str) -> str:
        out = args[0]
        for a in args[1:]:
            if self.prod == "@":
                out = f"{out} @ {a}"
            elif self.prod == "np.dot":
                out = f"np.dot({out}, {a})"
            else:
                out = f"({out}).dot({a})" if " " in out else f"{out}.dot({a})"
        return out

    def t(self, a: str) -> str:
        return f"{a}{self.tr}"

    def add(self, target: str, term: str) -> str:
        return f"{target} += {term}" if self.inplace else f"{target} = {target} + {term}"


def _model(n: dict, st: Style, rng, indent: str) -> list[str]:
    dt, Phi, Gam, Q, H, V = n["dt"], n["Phi"], n["Gam"], n["Q"], n["H"], n["V"]
    half = _cases(rng, f"{dt}**2 / 2", f"0.5 * {dt}**2", f"{dt} * {dt} / 2")
    out = [f"{dt} = {_cases(rng, '0.005', '1 / 200', '1.0 / 200.0')}"]
    out.append(_cases(rng, f"{Phi} = np.array([[1.0, {dt}, -{half}], [0.0, 1.0, -{dt}], "
                           f"[0.0, 0.0, 1.0]])",
                      f"{Phi} = {st.eye}\n{Phi}[0, 1] = {dt}\n{Phi}[0, 2] = -{half}\n"
                      f"{Phi}[1, 2] = -{dt}"))
    out.append(_cases(rng, f"{Gam} = -np.array([[{half}], [{dt}], [0.0]])",
                      f"{Gam} = np.array([-{half}, -{dt}, 0.0]).reshape(3, 1)",
                      f"{Gam} = np.array([[-{half}], [-{dt}], [0]])"))
    sw = _cases(rng, "0.02**2", "0.0004", "4e-4", "sigma_w**2")
    q = _cases(rng, f"{st.mm(Gam, st.t(Gam))} * {sw}", f"{sw} * ({st.mm(Gam, st.t(Gam))})",
               f"np.outer({Gam}, {Gam}) * {sw}")
    out.append(("sigma_w = 0.02\n" if "sigma_w" in sw else "") + f"{Q} = {q}")
    out.append(_cases(rng, f"{H} = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])",
                      f"{H} = np.hstack([np.eye(2), np.zeros((2, 1))])", f"{H} = np.eye(2, 3)",
                      f"{H} = {st.eye}[:2]"))
    out.append(_cases(rng, f"{V} = np.diag([1.0, 0.04**2])",
                      f"{V} = np.diag([1.0**2, 0.04**2])",
                      f"{V} = np.array([[1.0, 0], [0, 0.0016]])",
                      f"sig_p, sig_v = 1.0, 0.04\n{V} = np.diag([sig_p**2, sig_v**2])"))
    return [indent + ln for s in out for ln in s.split("\n")]


def _gain(n: dict, st: Style, rng) -> list[str]:
    M, H, V, K, S = n["M"], n["H"], n["V"], n["K"], n["S"]
    HT = st.t(H)
    return [f"{S} = {st.mm(H, M, HT)} + {V}",
            _cases(rng, f"{K} = {st.mm(M, HT, f'np.linalg.inv({S})')}",
                   f"{K} = {st.t(f'np.linalg.solve({S}, {st.mm(H, M)})')}",
                   f"{K} = {st.mm(M, HT, f'np.linalg.pinv({S})')}",
                   f"{K} = np.linalg.solve({st.t(S)}, {st.t(st.mm(M, HT))}){st.tr}")]


def _covariance(n: dict, st: Style, rng) -> list[str]:
    M, H, V, K, S, P, I = n["M"], n["H"], n["V"], n["K"], n["S"], n["P"], n["I"]
    out = pick(rng, [
        [f"{I} = {st.eye}", f"A = {I} - {st.mm(K, H)}",
         f"{P} = {st.mm('A', M, st.t('A'))} + {st.mm(K, V, st.t(K))}"],
        [f"{P} = {st.mm(f'({st.eye} - {st.mm(K, H)})', M)}"],
        [f"{P} = {M} - {st.mm(K, S, st.t(K))}"],
        [f"{P} = {M} - {st.mm(K, H, M)}"],
    ])
    if rng.random() < 0.2:
        out.append(f"{P} = 0.5 * ({P} + {st.t(P)})")
    return out


def _propagation(n: dict, st: Style, rng, per_interval: bool, indent: str) -> list[str]:
    x, P, Phi, Q = n["x"], n["P"], n["Phi"], n["Q"]
    if per_interval:
        return [f"{indent}{x} = {st.mm('PhiT', x)}",
                f"{indent}{P} = {st.mm('PhiT', P, st.t('PhiT'))} + QT"]
    loop = _cases(rng, "for _ in range(40):", "for _ in range(steps):",
                  f"for _ in range(int(round(0.2 / {n['dt']}))):")
    return [f"{indent}{loop}", f"{indent}    {x} = {st.mm(Phi, x)}",
            f"{indent}    {P} = {st.mm(Phi, P, st.t(Phi))} + {Q}"]


def _interval(n: dict, st: Style, rng) -> list[str]:
    Phi, Q = n["Phi"], n["Q"]
    return pick(rng, [
        [f"PhiT = np.linalg.matrix_power({Phi}, 40)", "QT = np.zeros((3, 3))",
         "for _ in range(40):", f"    QT = {st.mm(Phi, 'QT', st.t(Phi))} + {Q}"],
        [f"PhiT, QT = {st.eye}, np.zeros((3, 3))", "for _ in range(40):",
         f"    PhiT, QT = {st.mm(Phi, 'PhiT')}, {st.mm(Phi, 'QT', st.t(Phi))} + {Q}"],
    ])


def _update(n: dict, st: Style, rng, zk: str, indent: str) -> list[str]:
    x, P, M, K, r, H = n["x"], n["P"], n["M"], n["K"], n["r"], n["H"]
    out = [f"{M} = {P}"] + _gain(n, st, rng)
    out += [f"{r} = {zk} - {st.mm(H, x)}", st.add(x, st.mm(K, n["r"]))]
    out += _covariance(n, st, rng)
    return [indent + ln for ln in out]


def _driver(n: dict, st: Style, rng, per_interval: bool, propagate, update) -> list[str]:
    """The body of ``kalman_filter`` after the model: the prior, the storage, the loop over the
    fixes; ``propagate(indent)`` and ``update(zk, indent)`` give the steps' lines."""
    x, P, k, ox, oP = n["x"], n["P"], n["k"], n["out_x"], n["out_P"]
    lists = rng.random() < 0.4
    size = _cases(rng, "len(z)", "z.shape[0]", "n")
    body: list[str] = []
    if size == "n" or rng.random() < 0.2:
        body += ["    z = np.asarray(z, dtype=float)",
                 f"    n = {_cases(rng, 'len(z)', 'z.shape[0]')}"]
        size = "n"
    if per_interval:
        body += ["    " + ln for ln in _interval(n, st, rng)]
    elif rng.random() < 0.4:
        body += ["    steps = 40"]
    p0 = _cases(rng, "np.diag([100.0, 1.0, 0.01])", "np.diag([10.0**2, 1.0**2, 0.1**2])",
                "np.diag(np.array([10, 1, 0.1]) ** 2)")
    body += _cases(rng, f"    {x} = np.zeros(3)\n    {P} = {p0}",
                   f"    {x}, {P} = np.zeros(3), {p0}").split("\n")
    if lists:
        body += [f"    {ox}, {oP} = [], []"]
    else:
        body += [f"    {ox} = np.zeros(({size}, 3))", f"    {oP} = np.zeros(({size}, 3, 3))"]
    save = ([f"        {ox}.append({x}{_cases(rng, '.copy()', '')})",
             f"        {oP}.append({P}{_cases(rng, '.copy()', '')})"] if lists
            else [f"        {ox}[{k}{_cases(rng, '', ', :')}] = {x}", f"        {oP}[{k}] = {P}"])
    first = rng.integers(3)
    if first == 0:  # propagate at the top of every step but the first
        body += [f"    for {k} in range({size}):",
                 f"        if {_cases(rng, f'{k} > 0', f'{k} != 0', k)}:"]
        body += propagate("            ") + update(f"z[{k}]", "        ") + save
    elif first == 1:  # propagate at the end of a step
        body += [f"    for {k} in range({size}):"] + update(f"z[{k}]", "        ") + save
        body += [f"        if {k} < {size} - 1:"] + propagate("            ")
    else:  # enumerate the measurements
        body += [f"    for {k}, zk in enumerate(z):", f"        if {k}:"]
        body += propagate("            ") + update("zk", "        ") + save
    body += ([f"    return np.array({ox}), np.array({oP})"] if lists
             else [f"    return {ox}, {oP}"])
    return body


def _q2_inline(n: dict, st: Style, rng, model_inside: bool) -> str:
    per_interval = rng.random() < 0.4
    body = _model(n, st, rng, "    ") if model_inside else []
    body += _driver(n, st, rng, per_interval,
                    lambda ind: _propagation(n, st, rng, per_interval, ind),
                    lambda zk, ind: _update(n, st, rng, zk, ind))
    return "\n".join(body)


def _q2_helpers(n: dict, st: Style, rng, model_inside: bool) -> tuple[list[str], str]:
    x, P, Phi, Q, H, V = n["x"], n["P"], n["Phi"], n["Q"], n["H"], n["V"]
    pred = pick(rng, ["predict", "propagate", "time_update", "prop"])
    upd = pick(rng, ["update", "correct", "meas_update", "fuse"])
    per_interval = rng.random() < 0.3
    steps = rng.random() < 0.5 and not per_interval  # the helper loops over the 40 steps
    helpers = [f"def {pred}({x}, {P}, {Phi}, {Q}):"]
    if steps:
        helpers += _propagation(n, st, rng, False, "    ") + [f"    return {x}, {P}"]
    elif rng.random() < 0.5:
        helpers += [f"    return {st.mm(Phi, x)}, {st.mm(Phi, P, st.t(Phi))} + {Q}"]
    else:
        helpers += [f"    {x} = {st.mm(Phi, x)}", f"    {P} = {st.mm(Phi, P, st.t(Phi))} + {Q}",
                    f"    return {x}, {P}"]
    helpers += ["", f"def {upd}({x}, {P}, z_k, {H}, {V}):"]
    helpers += _update(n, st, rng, "z_k", "    ") + [f"    return {x}, {P}"]
    if steps and "steps" in "".join(helpers):
        helpers.insert(1, "    steps = 40")
    args_p = ("PhiT", "QT") if per_interval else (Phi, Q)

    def propagate(ind: str) -> list[str]:
        call = f"{x}, {P} = {pred}({x}, {P}, {args_p[0]}, {args_p[1]})"
        if per_interval or steps:
            return [ind + call]
        return [f"{ind}for _ in range(40):", f"{ind}    {call}"]

    def update(zk: str, ind: str) -> list[str]:
        return [f"{ind}{x}, {P} = {upd}({x}, {P}, {zk}, {H}, {V})"]

    body = _model(n, st, rng, "    ") if model_inside else []
    body += _driver(n, st, rng, per_interval, propagate, update)
    return helpers, "\n".join(body)


def _q2_filterpy(n: dict, st: Style, rng) -> str:
    kf, k, ox, oP = pick(rng, ["kf", "f", "filt", "tracker"]), n["k"], n["out_x"], n["out_P"]
    body = _model(n, st, rng, "    ")
    per_interval = rng.random() < 0.4
    if per_interval:
        body += ["    " + ln for ln in _interval(n, st, rng)]
    body += ["    from filterpy.kalman import KalmanFilter",
             f"    {kf} = KalmanFilter(dim_x=3, dim_z=2)",
             f"    {kf}.F = {'PhiT' if per_interval else n['Phi']}",
             f"    {kf}.Q = {'QT' if per_interval else n['Q']}", f"    {kf}.H = {n['H']}",
             f"    {kf}.R = {n['V']}", f"    {kf}.x = np.zeros(3)",
             f"    {kf}.P = {_cases(rng, 'np.diag([100.0, 1.0, 0.01])', 'np.diag([10.0, 1.0, 0.1]) ** 2')}"]
    lists = rng.random() < 0.5
    body += ([f"    {ox}, {oP} = [], []"] if lists else
             [f"    {ox} = np.zeros((len(z), 3))", f"    {oP} = np.zeros((len(z), 3, 3))"])
    body += [f"    for {k} in range(len(z)):", f"        if {k} > 0:"]
    body += (["            " + kf + ".predict()"] if per_interval else
             ["            for _ in range(40):", f"                {kf}.predict()"])
    body += [f"        {kf}.update(z[{k}])"]
    body += ([f"        {ox}.append({kf}.x.copy())", f"        {oP}.append({kf}.P.copy())",
              f"    return np.array({ox}), np.array({oP})"] if lists else
             [f"        {ox}[{k}] = {kf}.x", f"        {oP}[{k}] = {kf}.P",
              f"    return {ox}, {oP}"])
    return "\n".join(body)


def q2(rng: np.random.Generator) -> str:
    n = names(rng)
    st = Style(rng)
    style = pick(rng, ["inline", "inline", "inline", "helpers", "filterpy"])
    model_inside = style == "filterpy" or rng.random() < 0.6
    head = ["import numpy as np", ""]
    module_model = [] if model_inside else _model(n, st, rng, "") + [""]
    doc = pick(rng, ['    """Multirate Kalman filter (report 000)."""', "    # my filter", ""])
    if style == "helpers":
        helpers, body = _q2_helpers(n, st, rng, model_inside)
        parts = [helpers, ["", "", "def kalman_filter(z):", doc, body]]
        if rng.random() < 0.5:
            parts.reverse()
        lines = head + module_model + [ln for p in parts for ln in p]
    elif style == "filterpy":
        lines = head + ["def kalman_filter(z):", doc, _q2_filterpy(n, st, rng)]
    else:
        lines = head + module_model + ["def kalman_filter(z):", doc,
                                       _q2_inline(n, st, rng, model_inside)]
    code = "\n".join(lines) + "\n"
    ast.parse(code)  # the generator writes valid Python
    return code


# ------------------------------------------------------------------------------ q3
def _average(st: Style, rng, xt: str, xh: str, P: str, e: str, N: str, ix: str) -> list[str]:
    mean = _cases(rng, "float(np.mean({v}))", "np.mean({v})", "{v}.mean()",
                  "np.sum({v}) / len({v})", "np.average({v})")
    return pick(rng, [
        [f"    {e} = {xt}[:, {ix}] - {xh}[:, {ix}]",
         f"    vals = [{st.mm('a', 'np.linalg.solve(b, a)')} for a, b in zip({e}, {P}[:, {ix}])]",
         "    return " + mean.format(v="np.array(vals)" if ".mean" in mean else "vals")],
        [f"    {N} = {_cases(rng, f'{xt}.shape[0]', f'len({xt})')}", "    total = 0.0",
         f"    for i in range({N}):", f"        {e} = {xt}[i, {ix}] - {xh}[i, {ix}]",
         f"        total += {st.mm(e, f'np.linalg.inv({P}[i, {ix}])', e)}",
         f"    return total / {N}"],
        [f"    {e} = ({xt} - {xh})[:, {ix}, :]",
         f"    q = np.einsum('ri,rij,rj->r', {e}, np.linalg.inv({P}[:, {ix}]), {e})",
         "    return " + mean.format(v="q")],
        [f"    {N} = len({xt})", "    vals = []", f"    for i in range({N}):",
         f"        {e} = {xt}[i][{ix}] - {xh}[i][{ix}]",
         f"        L = np.linalg.cholesky({P}[i][{ix}])", f"        w = np.linalg.solve(L, {e})",
         f"        vals.append({st.mm('w', 'w')})", f"    return sum(vals) / {N}"],
        [f"    {e} = {xt}[:, {ix}, :] - {xh}[:, {ix}, :]",
         f"    s = np.linalg.solve({P}[:, {ix}], {e}[..., None])[..., 0]",
         f"    return float(np.sum({e} * s) / {e}.shape[0])"],
        [f"    {e} = {xt}[:, {ix}] - {xh}[:, {ix}]",
         f"    Pinv = np.array([np.linalg.pinv(p) for p in {P}[:, {ix}]])",
         f"    q = [{st.mm(st.t(f'{e}[i]'), 'Pinv[i]', f'{e}[i]')} for i in range({e}.shape[0])]",
         "    return " + mean.format(v="np.array(q)" if ".mean" in mean else "q")],
        [f"    {N}, total = len({xt}), 0", f"    for a, b, c in zip({xt}, {xh}, {P}):",
         f"        {e} = a[{ix}] - b[{ix}]",
         f"        total = total + {st.mm(e, f'np.linalg.solve(c[{ix}], {e})')}",
         f"    return total / {N}"],
    ])


def _bounds(rng, c2: str, N: str) -> list[str]:
    dof = _cases(rng, f"3 * {N}", "dof")
    head = [f"    dof = 3 * {N}"] if dof == "dof" else []
    scale = _cases(rng, "/ {N}", "* (1 / {N})").format(N=N)
    return head + pick(rng, [
        [f"    return tuple({c2}.ppf([0.025, 0.975], {dof}) {scale})"],
        [f"    lo = {c2}.ppf(0.025, df={dof})", f"    hi = {c2}.ppf(0.975, df={dof})",
         f"    return lo {scale}, hi {scale}"],
        [f"    return np.array({c2}.interval(0.95, {dof})) {scale}"],
        ["    a = 0.05", f"    return {c2}.ppf(a / 2, {dof}) {scale}, {c2}.ppf(1 - a / 2, {dof}) {scale}"],
        [f"    r1 = {c2}.isf(0.975, {dof}) {scale}", f"    r2 = {c2}.isf(0.025, {dof}) {scale}",
         "    return [r1, r2]"],
        [f"    r = {c2}.ppf(np.array([0.025, 0.975]), {dof}) {scale}", "    return r[0], r[1]"],
    ])


def q3(rng: np.random.Generator) -> str:
    n = names(rng)
    st = Style(rng)
    xt, xh, P, e, N = (pick(rng, ["x_true", "xt", "truth"]), pick(rng, ["x_hat", "xh", "est"]),
                       pick(rng, ["P", "covs", "Ps"]), n["e"], n["N"])
    ix = _cases(rng, "-1", "-1", f"{xt}.shape[1] - 1")
    imp = rng.integers(3)
    mod = ["from scipy import stats", "from scipy.stats import chi2", "import scipy.stats"][imp]
    c2 = ["stats.chi2", "chi2", "scipy.stats.chi2"][imp]
    inside = rng.random() < 0.5
    f1 = [f"def average_nees({xt}, {xh}, {P}):"] + _average(st, rng, xt, xh, P, e, N, ix)
    f2 = [f"def nees_bounds({N}):"] + ([f"    {mod}"] if inside else []) + _bounds(rng, c2, N)
    parts = [f1, f2] if rng.random() < 0.7 else [f2, f1]
    code = "\n".join(([] if inside else [mod, ""]) + parts[0] + ["", ""] + parts[1]) + "\n"
    ast.parse(code)
    return code


# ------------------------------------------------------------------------------ a class
GENERATORS = {"q1": q1, "q2": q2, "q3": q3}


@dataclass
class Class:
    """Student -> question -> answer code, and what was planted (question, kind, students)."""

    answers: dict[str, dict[str, str]] = field(default_factory=dict)
    planted: list[tuple[str, str, tuple[str, ...]]] = field(default_factory=list)


def honest(n: int, rng: np.random.Generator) -> Class:
    c = Class()
    for i in range(n):
        c.answers[f"student{i:03d}"] = {q: g(rng) for q, g in GENERATORS.items()}
    return c


def plant(c: Class, question: str, kind: str, size: int, rng: np.random.Generator,
          source: str | None = None) -> tuple[str, ...]:
    """``size`` new students handing in disguised copies of ``source`` (default: a new honest
    answer), each with a disguise ``kind`` (a key of :data:`DISGUISES`, or "mixed")."""
    base = source if source is not None else GENERATORS[question](rng)
    who = []
    for j in range(size):
        name = f"{kind.replace(' ', '_')}{len(c.planted):02d}_{j:02d}"
        k = kind if kind != "mixed" else list(DISGUISES)[j % len(DISGUISES)]
        answers = {q: g(rng) for q, g in GENERATORS.items()}
        answers[question] = DISGUISES[k](base, rng) if (source is not None or j) else base
        c.answers[name] = answers
        who.append(name)
    c.planted.append((question, kind, tuple(who)))
    return tuple(who)


def cells(answers: dict[str, str]) -> list[str]:
    """A notebook's code cells (as a student hands them in) holding ``answers``."""
    return ["import numpy as np\n\nimport gpsaccel", 'VARIANT = {"rate_hz": 200}',
            answers["q1"], "%%writefile kalman_filter.py\n" + answers["q2"], answers["q3"]]
