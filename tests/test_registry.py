"""The registry: homework and reports are registered where they are defined, and what lists them
(the CLI, the generator, the packaged student side, the lessons' index) reads it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from gpsaccel import figures, registry
from gpsaccel.assignments.generate import assignments_dir, student_package_dir
from gpsaccel.cli import main
from gpsaccel.problems import PROBLEM_TITLES

ROOT = Path(__file__).resolve().parents[1]


def _packaged_assignments() -> list[str]:
    """The package's own homework: an instructor's folder (the cv2d example of tests/homework/) registers
    one more in the same process, which is not in the package."""
    return sorted(n for n in registry.assignments()
                  if registry.assignment(n).module.startswith("gpsaccel.assignments."))


def test_every_homework_with_a_master_is_registered_and_packaged():
    masters = sorted(p.parent.name for p in assignments_dir().glob("*/*.ipynb")
                     if p.stem == p.parent.name)
    packaged = _packaged_assignments()
    assert packaged == masters
    assert sorted(p.name for p in student_package_dir().iterdir() if p.is_dir()) == masters
    for name in packaged:
        entry = registry.assignment(name)
        assert entry.problem in registry.problems() and entry.title, name
        assert entry.module == f"gpsaccel.assignments.{name}"


def test_what_the_command_lists_without_importing_is_what_the_modules_register():
    """The help and choices read the problems' titles and the homework's names without importing
    a module (registry.problem_titles, registry.assignment_names): they must be what the modules
    register when imported, in the same order."""
    packaged = tuple(m.rpartition(".")[2] for m in registry.providers("problem"))
    assert tuple(PROBLEM_TITLES) == packaged
    assert registry.problems()[:len(packaged)] == packaged
    for name, title in PROBLEM_TITLES.items():
        assert registry.entry(name).title == title == registry.problem(name).title, name
    assert tuple(registry.problem_titles())[:len(packaged)] == packaged
    assert set(registry.problem_titles()) == set(registry.problems())
    assert registry.assignment_names() == registry.assignments()
    assert tuple(_packaged_assignments()) == tuple(sorted(
        m.rpartition(".")[2] for m in registry.providers("assignment")))


def test_a_kind_no_package_declared_is_an_error_not_an_empty_list():
    """The registry names no module above it: a list asked for before the owning package declared
    its modules would be silently empty, so it is refused.  Run in a fresh interpreter, where only
    the registry is imported."""
    code = ("from gpsaccel import registry\n"
            "for ask in (registry.problems, registry.assignments, registry.reports):\n"
            "    try:\n        ask()\n    except LookupError as e:\n        print(e)\n"
            "import gpsaccel.check\nprint(registry.problem_titles()['coop'][:10])")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         check=True, timeout=120).stdout.splitlines()
    assert [line.split(" modules")[0] for line in out[:3]] == [
        f"no package has declared its {kind}" for kind in ("problem", "assignment", "report")]
    assert out[3] == "Report 002"


def test_declared_titles_must_name_the_modules_in_order():
    with pytest.raises(ValueError, match="titles must name the problem modules"):
        registry.provide("problem", ("a.b.one", "a.b.two"), titles={"two": "T", "one": "O"})
    with pytest.raises(ValueError, match="kind must be one of problem, assignment, report"):
        registry.provide("problems", ())


def test_a_problem_in_a_file_is_told_from_a_registered_name():
    assert registry.is_file_spec("course/problems.py:cv2d")
    assert registry.is_file_spec("p.py:")  # a file with no name: load_problem names what is missing
    for name in ("calibration", "problems.txt:cv2d", "cv2d", "a:b", "p.py"):
        assert not registry.is_file_spec(name), name


def test_every_report_is_registered_by_its_figure_module_in_reading_order():
    assert figures.available_reports() == list(registry.reports())
    assert registry.reports() == tuple(m.rsplit(".r", 1)[1] for m in registry.providers("report"))
    for number in registry.reports():
        entry = registry.report(number)
        module = sys.modules[entry.module]
        assert entry.figures == module.FIGURES and entry.title == module.TITLE
    assert registry.report_figures()["000"][:4] == ("1", "2", "3", "3b")


def test_unknown_names_and_bad_entries_are_refused_naming_the_choices():
    with pytest.raises(ValueError, match="assignment must be one of calibration, coop, ship"):
        registry.assignment("nope")
    with pytest.raises(ValueError, match="report must be one of 000, 001"):
        registry.report("999")
    with pytest.raises(ValueError, match="report must be three digits"):
        registry.add_report("4", "m", ("1",))
    with pytest.raises(ValueError, match="figures must be"):
        registry.add_report("998", "m", ("01",))
    with pytest.raises(ValueError, match="already registered"):
        registry.add_assignment("tracker", "gpsaccel.assignments.tracker", system="other")
    with pytest.raises(ValueError, match="name must be lower-case"):
        registry.add_assignment("Tracker 2", "m")


def test_the_cli_choices_are_the_registry_s_and_building_the_parser_imports_no_homework(capsys):
    assert main(["assignment", "nope", "--out", "x"]) == 2
    err = capsys.readouterr().err
    assert all(name in err for name in registry.assignments())
    # the choices are read when a parse needs them: importing and building the parser loads no
    # homework module and no figure module
    code = ("import sys; from gpsaccel.cli import build_parser; build_parser(); "
            "print(any(m.startswith(('gpsaccel.assignments.', 'gpsaccel.figures.r')) "
            "for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         check=True, timeout=120).stdout
    assert out.strip() == "False"
