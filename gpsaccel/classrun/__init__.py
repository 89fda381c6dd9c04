"""A class's run, for ``gpsaccel check DIR`` and ``gpsaccel grade`` alike: one walk, one run, one
writer.

Below the command line and above the items it runs (:mod:`gpsaccel.check` checks one file,
:mod:`gpsaccel.assignments` grades one notebook)::

    from gpsaccel import classrun
    entries, notes = classrun.walk("class/", classrun.PYTHON)      # who, their ids, or why not
    results = classrun.check_many(["class/"], n_runs=4)            # every file, a box each
    print(classrun.table(results))
    grades = classrun.grade("Homework 1/", "calibration", roster="roster.csv")   # every file

* :mod:`~gpsaccel.classrun.entries`: the walk of a class into :class:`Entry` s (student, id,
  path, or the status and reason why there is none), for a kind of submission (:data:`PYTHON`,
  :func:`notebooks`) and a :data:`Naming` (who an export's name is: where LMS exports meet the
  roster);
* :mod:`~gpsaccel.classrun.exports`: the namings of Canvas's, Moodle's and Gradescope's
  submission downloads, each name mapped to the roster through the ids it carries;
* :mod:`~gpsaccel.classrun.running`: one run of a :class:`Task` over the entries (the secret
  seed, the jobs, the backend, the imports before forking, the sandbox's pool or Dask, deadlines,
  lost items in the sandbox's words, Ctrl-C);
* :mod:`~gpsaccel.classrun.writing`: every file and table the runs write, through
  :mod:`gpsaccel._untrusted`, and a terminal a closed pipe cannot stop;
* :mod:`~gpsaccel.classrun.statuses`: every status a grade can have, who caused it and its
  gradebook cell (a status the student did not cause is never a score);
* :mod:`~gpsaccel.classrun.checking` (:func:`check_many`), :mod:`~gpsaccel.classrun.grading`
  (:func:`grade`; its record, what a run writes after every notebook and what a rerun keeps:
  :mod:`~gpsaccel.classrun.record`) and :mod:`~gpsaccel.classrun.classwide` (the gradebooks
  and the similarity report, written by :func:`grade` itself, or again from the recorded grades
  by :func:`rewrite_class` when a full disk kept a run from writing them).
"""

from typing import TYPE_CHECKING

from gpsaccel import _lazy

if TYPE_CHECKING:  # for mypy and editors; at run time each name loads on first use (_lazy)
    from gpsaccel.classrun.checking import CheckPlan, check_many, plan_check
    from gpsaccel.classrun.entries import PYTHON, Entry, Kind, Name, Naming, notebooks, plain, walk
    from gpsaccel.classrun.grading import Graded, default_out, grade, grade_class, rewrite_class
    from gpsaccel.classrun.running import Interrupted, Task, run
    from gpsaccel.classrun.writing import appender, log_path, table, write_json

__all__ = [
    "PYTHON", "CheckPlan", "Entry", "Graded", "Interrupted", "Kind", "Name", "Naming", "Task",
    "appender", "check_many", "default_out", "grade", "grade_class", "log_path", "notebooks",
    "plain", "plan_check", "rewrite_class", "run", "table", "walk", "write_json",
]

# the command imports this package to reach its parts: nothing of the check or the grader loads
# before a name of them is read
__getattr__, __dir__ = _lazy.attach(
    __name__,
    attributes={
        "checking": ("CheckPlan", "check_many", "plan_check"),
        "entries": ("PYTHON", "Entry", "Kind", "Name", "Naming", "notebooks", "plain", "walk"),
        "grading": ("Graded", "default_out", "grade", "grade_class", "rewrite_class"),
        "running": ("Interrupted", "Task", "run"),
        "writing": ("appender", "log_path", "table", "write_json"),
    })
