"""How a student's box can end, as data: one table of the sandbox's outcomes and their wording.

Every failure code a box reports (:attr:`gpsaccel.sandbox.BoxResult.failure`: a limit, a crash, a
refused result, a use of the checker, or the runner's account of the student's function) has
one :class:`Outcome` here: the checker's template of its finding (:func:`gpsaccel.check.findings
.box_findings`, fields in that module's docstring) and, where the homework's grader stops a
notebook on it, the clause it says (:mod:`gpsaccel.assignments.scoring`, fields ``limit`` (s)
and ``memory`` (GB)).  ``lost.<reason>`` are the pool's items without a result
(:class:`gpsaccel.sandbox.Lost`), worded by the run they were lost from (fields ``detail``,
``limit``, ``slack``, and ``doer`` and ``doing``: "checker" and "checking this file" for a
check, "grader" and "grading this notebook" for a grade).  These are student-facing texts
built from the student's own run and the run's limits only, never from an answer.

An outcome is ``ours`` when it says nothing about the student's code: the checker or the machine
failed (``lost.*``, and ``machine-busy``: the box reached its backstop on a machine too busy to
give it its time limit, :mod:`gpsaccel.sandbox.clock`).  The checker's finding asks for the check to
be run again; the grader records the notebook as ``grader-error`` (not a grade: graded again,
:func:`ours`), never as the student's zero.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Outcome:
    """One way a box ends: ``finding`` the checker's template, ``stop`` the grader's clause
    ("" where the grader does not stop on it), ``ours`` the checker's or the machine's fault,
    not the student's (module docstring)."""

    finding: str
    stop: str = ""
    ours: bool = False


#: failure code (or ``lost.<reason>``) -> its wording (module docstring).
OUTCOMES: dict[str, Outcome] = {
    "timeout": Outcome(
        "Your {function} did not finish within the time limit of {time:g} s ({detail}): it completed "
        "{done} of {n_calls} calls{rate}. {timeout_hint}",
        stop="it was still running at the time limit of {limit:g} s"),
    "machine-busy": Outcome(
        "The computer running this check was too busy to give your code its {time:g} s ({detail}), "
        "so the check stopped after {done} of {n_calls} calls without a verdict. This says nothing "
        "about your code: run the check again, later or on a less busy computer.",
        stop="the grading computer was too busy to give it its {limit:g} s (not the student's "
             "fault: it is graded again)", ours=True),
    "memory-limit": Outcome(
        "Your code ran out of memory: a check may use {mib:g} MiB of address space, and your file "
        "asked for more (after {done} of {n_calls} calls){tb} A filter needs a few kilobytes: look for "
        "an array sized by the number of steps squared, or a list that grows in a loop that never ends.",
        stop="it ran out of memory (the limit is {memory} GB)"),
    "output-limit": Outcome(
        "Your code printed more than {output_limit:,} bytes, the most a check keeps, so it was stopped "
        "after {done} of {n_calls} calls. Remove the prints from {function} (or print only when "
        "debugging).\nIts last output:\n{last8}",
        stop="it printed too much"),
    "file-limit": Outcome(
        "Your code wrote a file larger than the {file_size:,} bytes a check allows (or filled its "
        "working folder){tb} A filter needs no files: return its results instead of saving them.",
        stop="it wrote too large a file"),
    "process-limit": Outcome(
        "Your code started more processes than the {processes} a check allows (after {done} of "
        "{n_calls} calls){tb} {function} must compute its result in its own process: remove os.fork, "
        "subprocess and multiprocessing.",
        stop="it started too many processes"),
    "uses-checker": Outcome(
        "Your file imports gpsaccel, the package that checks it. During a check the submission must "
        "compute its results with its own code (numpy, scipy and filterpy are available); remove the "
        "import of gpsaccel.",
        stop="it tried to use the grader's own checks"),
    "result-refused": Outcome(
        "What your code handed back to the checker was refused ({detail}). Only {function}'s return "
        "value counts: do not write to the checker's file descriptors or replace the checker's "
        "functions.",
        stop="the grader's channel received something that is not an answer"),
    "crashed": Outcome(
        "The Python process running your file ended without a result ({detail}) after {done} of "
        "{n_calls} calls. Does your file call os._exit() or kill a process?\nIts last output:\n{last8}",
        stop="its process ended (a crash, os._exit or a signal)"),
    "import-error": Outcome(
        "Your file raises an error when it is imported (before {function} is called); the traceback "
        "ends with:\n{traceback}"),
    "no-function": Outcome(
        "Your file does not define a function {signature}{found}. Functions it defines: {callables}. "
        "Name your function {function}."),
    "exception": Outcome(
        "{function}(...) raised an exception on {label}; the traceback ends with:\n{traceback}"),
    "return-value": Outcome(
        "{function}(...) must return a tuple ({outputs}); on {label} it returned "
        "{a_type}{shape_text}{length_text}. End it with: return {outputs}."),
    "not-numeric": Outcome(
        "{name} returned by {function} is not an array of numbers ({type}): np.array({name}, "
        "dtype=float) fails with: {error}."),
    "wrong-shape": Outcome(
        "{function} must return {wanted} ({rows}); on {label} it returned "
        "{returned}{between_calls}.{hints}"),
    "lost.error": Outcome(
        "the {doer} failed: {detail}", ours=True),
    "lost.not-a-report": Outcome(
        "the {doer}'s process returned no report", ours=True),
    "lost.too-long": Outcome(
        "{doing} took more than {limit:g} s (time limit plus {slack:g} s) and was stopped",
        ours=True),
    "lost.died": Outcome(
        "the process {doing} died ({detail}) before it reported; a submission that kills "
        "its parent process ends like this", ours=True),
}


def ours(code: str | None) -> bool:
    """Whether failure (or finding) ``code`` is the checker's or the machine's, not the
    student's: the grader then records no grade (module docstring)."""
    outcome = OUTCOMES.get(code or "")
    return outcome is not None and outcome.ours
