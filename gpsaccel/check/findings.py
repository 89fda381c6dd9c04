"""What came back from a student's box, as findings: one function for every problem, wording as data.

:func:`box_findings` turns a :class:`gpsaccel.sandbox.BoxResult` into findings of a
:class:`~gpsaccel.check.report.Report`.  Every message is a template of :data:`MESSAGES` (code ->
text with ``{fields}``); a problem changes its wording by giving its own templates for some codes
(``Problem.messages``), never by a branch here.  The fields every template may use:

``function`` the function of the failing call (or the contract's), ``signature`` its signature,
``label`` the case of the failing call ("run 3", "the course log"), ``done`` / ``n_calls`` the
calls completed and made, ``time`` the time limit (s), ``mib`` the memory limit (MiB),
``output_limit`` / ``file_size`` (bytes), ``processes``, ``tb`` "; the traceback ends with: ..."
(or "." when there is none, a limit that killed the box), ``traceback`` (never empty:
:data:`NO_TRACEBACK`), ``last`` the tail of what was printed, ``detail`` the sandbox's account,
and the runner's own (``type``, ``shape``, ``length``, ``name``, ``error``, ``callables``,
``found``).  A problem adds fields of its own (``Problem.message_fields``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from gpsaccel import sandbox as sb
from gpsaccel.check.report import Report, used
from gpsaccel.sandbox.outcomes import OUTCOMES

#: Characters of the student's printed output kept in a finding.
OUTPUT_KEEP = 1500

#: Printed output (bytes) beyond which a check warns about prints.
OUTPUT_WARN = 20_000

#: code -> message template (module docstring for the fields): how the box ended, from the
#: sandbox's one table of outcomes (:data:`gpsaccel.sandbox.outcomes.OUTCOMES`), and the notes on
#: a box that returned.  "timeout.never" and "timeout.slow" complete "timeout";
#: "no-function.found" completes "no-function".
MESSAGES: dict[str, str] = {
    **{code: o.finding for code, o in OUTCOMES.items() if not code.startswith("lost.")},
    "prints-a-lot": "Your code printed {output_bytes:,} bytes during the check ({n_calls} "
                    "calls). Remove debug prints from {function}: they slow it down and bury "
                    "the messages that matter. The last lines were:\n{last6}",
    "left-processes": "Your code left {killed} process(es) running after it returned; the "
                      "checker killed them. {function} should not start processes (os.fork, "
                      "subprocess, multiprocessing).",
    "forked": "Your code forked its process {forked_where} (os.fork, or multiprocessing, which "
              "calls it). Only the process the checker started hands back results: the copy was "
              "stopped where it would have returned one, so nothing it computed counts, for or "
              "against you. {function} should compute its result in its own process: remove "
              "os.fork.",
    "timeout.never": "It never returned once: look for a loop whose condition never changes "
                     "(e.g. while k < n without k += 1) or input() waiting for a keyboard.",
    "timeout.slow": "It is too slow: {work}.",
    "no-function.found": " ({function} is a {found_type}, not a function)",
    "runner": "The check could not run your file: {failure} {detail}",
    "returns-list": "{name} is a Python {type}; it was converted with np.array({name}, "
                    "dtype=float). Returning numpy arrays is expected (np.array(...) at the end "
                    "of your function).",
    "returns-matrix": "{name} is a numpy.matrix; it was converted to an array. numpy.matrix is "
                      "deprecated: use numpy arrays and @.",
    "filterpy-column": "{name} came back with a trailing axis of length 1, {shape} (filterpy "
                       "keeps x as a column, kf.x); it was accepted as {wanted}. Store "
                       "kf.x[:, 0] (or x.ravel()) to return the declared shape.",
}

#: (got, wanted) -> hint of :func:`shape_hints`, as templates.
SHAPE_HINTS: dict[str, str] = {
    "transposed": "{name} looks transposed: one row per time, one column per component.",
    "column": "{name} has a trailing axis of length 1 (filterpy's kf.x is a column): store "
              "kf.x[:, 0] or x.ravel().",
    "every-step": "{name} has one row per propagation step; return the measurement times only "
                  "(every {every}th row: {name}[::{every}]).",
    "rows": "{name} has {got_rows} rows: one row per time from the first to the last "
            "({want_rows} rows).",
    "diagonal": "{name} looks like the diagonal only (or the standard deviations): return the "
                "full covariance at each time.",
    "time-last": "{name} has time last (MATLAB's P(:,:,k)); numpy puts it first: P[k] is one "
                 "covariance.",
}


def _indent(text: str, n: int = 6) -> str:
    return "\n".join(" " * n + line for line in text.splitlines())


#: What a finding's "the traceback ends with:" is followed by when the box sent none: the
#: runner always sends one, but the student's code runs in its process and may empty it (patch
#: the traceback module, forge the frame), and "ends with:" above nothing reads as the
#: checker's bug.
NO_TRACEBACK = "(none came back: your code's process sent an empty traceback)"


def _tail(text: str, lines: int, n: int) -> str:
    return _indent("\n".join(text[-OUTPUT_KEEP:].rstrip().splitlines()[-lines:]) or "(nothing)",
                   n)


def shape_hints(got: tuple[int, ...], want: tuple[int, ...], name: str, every: int = 1) -> list[str]:
    """What a returned shape ``got`` says about the mistake, for an output declared ``want``
    (time first); ``every`` is the propagation steps per measurement."""
    key = None
    if len(want) == 2 and got == want[::-1]:
        key = "transposed"
    elif got == want + (1,):
        key = "column"
    elif len(got) == len(want) >= 2 and len(want) == 3 and got == want[1:] + want[:1]:
        key = "time-last"
    elif len(want) == 3 and got == want[:2]:
        key = "diagonal"
    elif got and len(got) == len(want) and got[1:] == want[1:]:
        if every > 1 and got[0] == (want[0] - 1) * every + 1:
            key = "every-step"
        elif got[0] in (want[0] - 1, want[0] + 1):
            key = "rows"
    if key is None:
        return []
    return [SHAPE_HINTS[key].format(name=name, every=every, got_rows=got[0] if got else 0,
                                    want_rows=want[0])]


def _box_fields(box: sb.BoxResult, calls: Sequence[sb.Call], limits: sb.Limits,
                labels: Sequence[str] | None, fields: Mapping[str, object]
                ) -> tuple[Sequence[sb.Output], dict[str, object]]:
    """The outputs of the call the box stopped at, and the fields of the box's templates: the
    student's own output, traceback and counts, and the check's limits, never an answer."""
    problem = box.problem or {}
    tb = str(problem.get("traceback") or "")
    i = problem.get("call")
    call = calls[i] if isinstance(i, int) and 0 <= i < len(calls) else (calls[0] if calls else None)
    outputs = call.outputs if call else ()
    f: dict[str, object] = {
        "function": call.function if call else "your function", "signature": (
            f"{call.function}(...)" if call else "the contract's function"),
        "n_calls": len(calls),
        "done": len(box.results), "time": limits.time, "mib": limits.memory / 2**20,
        "output_limit": limits.output, "file_size": limits.file_size,
        "processes": limits.processes, "detail": box.detail, "failure": box.failure,
        "output_bytes": box.output_bytes, "killed": box.killed,
        "last6": _tail(box.output, 6, 6), "last8": _tail(box.output, 8, 8),
        "label": (labels[i] if labels and isinstance(i, int) and i < len(labels)
                  else f"call {i + 1} of {len(calls)}" if isinstance(i, int) else "a call"),
        "traceback": _indent(tb if tb.strip() else NO_TRACEBACK),
        "tb": "; the traceback ends with:\n" + _indent(tb) if tb.strip() else ".",
        "outputs": ", ".join(o.name for o in outputs), "work": "it should take well under a "
                                                               "second per call",
        **fields,
    }
    return outputs, f


def box_findings(report: Report, box: sb.BoxResult, calls: Sequence[sb.Call],
                 limits: sb.Limits, messages: Mapping[str, str] | None = None,
                 labels: Sequence[str] | None = None, renames: Mapping[str, str] | None = None,
                 **fields: object) -> bool:
    """Add the findings about the box itself; True when every call returned (there are results
    to compare).  ``messages`` overrides :data:`MESSAGES` per code, ``labels[i]`` names call i's
    case, ``renames`` maps a failure to the code reported, ``fields`` fill the templates."""
    text = {**MESSAGES, **(messages or {})}
    problem = box.problem or {}
    outputs, f = _box_fields(box, calls, limits, labels, fields)
    report.details["sandbox"] = box.backend
    report.details["sandbox_limits"] = box.limit_backend  # cgroup2, cgroup1 or rlimit
    if box.output_bytes > OUTPUT_WARN and box.failure != "output-limit":
        _add(report, "prints-a-lot", text["prints-a-lot"], f, "warning")
    if box.killed:
        report.details["processes_killed"] = box.killed
        _add(report, "left-processes", text["left-processes"], f, "warning")
    if box.forked is not None:
        _add(report, "forked", text["forked"],
             {**f, "forked_where": _call_label(box.forked, calls, labels)}, "warning")
    if box.failure is None:
        returned_notes(report, box.returned or {}, text)
        return True
    failure = box.failure
    f.update(_runner_fields(failure, problem, outputs, f, text))
    key = failure if failure in text else "runner"
    _add(report, (renames or {}).get(failure, failure if key != "runner" else "runner"),
         text[key], f)
    return False


def _call_label(i: int, calls: Sequence[sb.Call], labels: Sequence[str] | None) -> str:
    """Where call ``i`` (-1: the import of the file) was, in the student's words."""
    if i < 0:
        return "while your file was imported"
    return f"on {labels[i]}" if labels and i < len(labels) else f"in call {i + 1} of {len(calls)}"


def _add(report: Report, code: str, template: str, fields: Mapping[str, object],
         severity: str = "error") -> None:
    """A finding whose student text is ``template``: every field here is the student's own
    (their output, traceback, what they returned) or the check's limits, never an answer."""
    report.add(code, severity=severity, text=template, observed=used(template, fields),
               where=str(fields.get("label", "")))


def _runner_fields(failure: str, problem: dict, outputs: Sequence[sb.Output],
                   f: Mapping[str, object], text: Mapping[str, str]) -> dict[str, object]:
    """The fields of the runner's account of ``failure`` (shapes, types, hints)."""
    ret = problem.get("returned") or {}
    done, n = int(f["done"]), int(f["n_calls"])  # type: ignore[call-overload]
    out: dict[str, object] = {
        "type": ret.get("type", ""), "name": problem.get("name", ""),
        "a_type": "None" if ret.get("type") == "None" else f"a {ret.get('type', '')}",
        "error": str(problem.get("error", "")).rstrip("."),
        "shape_text": f" of shape {tuple(ret['shape'])}" if ret.get("shape") else "",
        "length_text": (f" with {problem['length']} items"
                        if problem.get("length") is not None else ""),
        "callables": ", ".join(problem.get("callables", [])) or "none",
        "found": "", "rate": (f" (≈ {float(f['time']) / done:.2g} s per call, {n} calls "  # type: ignore[arg-type]
                              f"needed)" if done else ""),
    }
    found = problem.get("found")
    if found:
        out["found"] = text["no-function.found"].format(function=f["function"],
                                                        found_type=found.get("type"))
    out["timeout_hint"] = text["timeout.never" if not done else "timeout.slow"].format(**f)
    if failure == "wrong-shape":
        shapes = problem.get("shapes") or {}
        every = int(f.get("every", 1))  # type: ignore[call-overload]
        hints: list[str] = []
        for o in outputs:
            got = tuple(shapes.get(o.name) or ())
            if got != tuple(o.shape):
                hints += shape_hints(got, tuple(o.shape), o.name, every)
        out["wanted"] = " and ".join(f"{o.name} of shape {tuple(o.shape)}" for o in outputs)
        out["returned"] = " and ".join(f"{o.name} {tuple(shapes.get(o.name) or ())}"
                                       for o in outputs)
        out["hints"] = "".join(" " + h for h in hints)
        out["between_calls"] = (" (the earlier calls had the right shapes: does your file keep "
                                "results between calls, e.g. a module-level list that grows?)"
                                if problem.get("call") else "")
        if "rows" not in f:
            out["rows"] = "one row per time"
    return out


def returned_notes(report: Report, returned: Mapping[str, Mapping], text: Mapping[str, str]
                   = MESSAGES) -> None:
    """Notes on outputs that came back as lists, tuples or numpy.matrix (converted)."""
    for name, desc in returned.items():
        typ = str(desc.get("type", ""))
        if typ in ("builtins.list", "builtins.tuple"):
            report.add("returns-list", severity="note", text=text["returns-list"], where=name,
                       observed={"name": name, "type": typ.split(".")[-1]})
        elif typ == "numpy.matrix":
            report.add("returns-list", severity="note", text=text["returns-matrix"], where=name,
                       observed={"name": name})


def mistake_finding(report: Report, mistake: object, prefix: str = "", where: str = "",
                    severity: str = "error", part: str = "",
                    student: Mapping[str, str] | None = None, **observed: object) -> None:
    """A catalogue entry the student's output matches, as a finding: the student reads the
    code's wording (``student``'s, a problem's own, over :data:`gpsaccel.check.wording.STUDENT`)
    and the entry's variant (what their filter does); the entry's message, which may quote the
    problem's right numbers, is the instructor's.  ``prefix`` (e.g. the function's name) leads
    both; ``where`` fills the wording's place (the entry's own, :attr:`Mistake.where`, when the
    caller has none)."""
    from gpsaccel.check.wording import STUDENT, UNWORDED

    code, variant = mistake.code, mistake.variant  # type: ignore[attr-defined]
    where = where or getattr(mistake, "where", "")
    template = {**STUDENT, **(student or {})}.get(code, UNWORDED.replace("{code}", code))
    report.add(code, f"{prefix}{mistake.message}", severity,  # type: ignore[attr-defined]
               text="{prefix}" + template + " Your output matches a filter that makes this "
               "mistake ({variant}).", where=where,
               observed={"prefix": prefix, "variant": variant, **observed}, part=part)
