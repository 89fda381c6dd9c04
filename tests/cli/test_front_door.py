"""The command's front door: bad requests refused before any work, one line, the right exit code.

The CLI cases run the real command (``python -m gpsaccel.cli``) in a subprocess in an empty
working folder and check the exit code, that stderr is one line naming the flag, that nothing was
printed on stdout (no work was done) and that nothing was written.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

from gpsaccel import _atomic  # noqa: E402
from gpsaccel import _validation as _v  # noqa: E402
from gpsaccel.cli import build_parser, main  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SUBMISSION = ROOT / "tests" / "submissions" / "correct_joseph.py"


def gpsaccel(*args: str, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "gpsaccel.cli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


#: One child process that runs the command (``gpsaccel.cli`` as ``__main__``, as ``python -m``
#: does) once per case, each in its own working folder: a fresh interpreter and import of the
#: package cost 0.35 CPU s a case, and the refusals need none of their own.
_CASES = r"""
import contextlib, io, json, os, runpy, sys, traceback
results = []
for argv, cwd in json.loads(sys.stdin.read()):
    os.chdir(cwd)
    sys.argv = ["gpsaccel.cli", *argv]
    out, err, code = io.StringIO(), io.StringIO(), 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            runpy.run_module("gpsaccel.cli", run_name="__main__", alter_sys=True)
        except SystemExit as exc:  # as the interpreter ends: a number, or a message and 1
            if exc.code is None or isinstance(exc.code, int):
                code = exc.code or 0
            else:
                print(exc.code, file=sys.stderr)
                code = 1
        except BaseException:
            traceback.print_exc()
            code = 1
    results.append([int(code), out.getvalue(), err.getvalue()])
print(json.dumps(results))
"""


def gpsaccel_cases(cases: list[tuple[list[str], Path]], timeout: float = 600
                   ) -> list[subprocess.CompletedProcess]:
    """Each ``(argv, cwd)`` run as the command in one child process (:data:`_CASES`)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", _CASES], env=env, capture_output=True,
                          text=True, timeout=timeout,
                          input=json.dumps([[list(a), str(c)] for a, c in cases]))
    assert proc.returncode == 0 and proc.stdout.strip(), proc
    return [subprocess.CompletedProcess([sys.executable, "-m", "gpsaccel.cli", *argv], code,
                                        out, err)
            for (argv, _), (code, out, err) in zip(cases, json.loads(proc.stdout), strict=True)]


def assert_refused(res: subprocess.CompletedProcess, *words: str) -> None:
    assert res.returncode == 2, res
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert res.stdout == ""  # nothing was computed (every command prints before it writes)


def files_in(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


# ------------------------------------------------------------------------------ the front door's cost
def _subcommands() -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return list(sub.choices)


#: What the answers below must come back without: the work's first imports.  (Their CPU is
#: benchmarks/startup.py's; a test asserts what ran, never a time.)
NOT_BEFORE_WORK = ("numpy", "gpsaccel.sandbox", "gpsaccel.check")

#: Modules of those the answers may load: none (the help and an argument error read the problems'
#: names and titles from gpsaccel.problems, outside the checker).
LIGHT: tuple[str, ...] = ()

#: ``python -m gpsaccel ARGS`` as the command runs it (runpy, __main__), then the loaded modules of
#: NOT_BEFORE_WORK (a sub-module counts as its package, but those of LIGHT) on the last line of stdout.
_IMPORTED_BY_THE_COMMAND = r"""
import json, runpy, sys
watched, light = json.loads(sys.argv[1])
sys.argv = ["gpsaccel", *json.loads(sys.argv[2])]
try:
    runpy.run_module("gpsaccel", run_name="__main__", alter_sys=True)
except SystemExit as exc:
    code = exc.code
sys.stdout.flush()
print("\n" + json.dumps([code, sorted(w for w in watched if any(
    (m == w or m.startswith(w + ".")) and m not in light for m in sys.modules))]))
"""


def _front_door_cases() -> list[list[str]]:
    commands = _subcommands()
    return [["--help"], ["--version"], ["--no-such-flag"], ["nope"],
            *([c, "--help"] for c in commands),
            *([c, "--no-such-flag"] for c in commands),
            ["check", "x.py", "--runs", "0"], ["check", "x.py", "--problem", "nope"],
            ["grade", "x", "--assignment", "nope"], ["assignment", "nope", "--out", "x"],
            ["montecarlo", "--truth", "nope"]]


@pytest.fixture(scope="module")
def front_door(tmp_path_factory):
    """Each case of _front_door_cases run as the command in a fresh interpreter (a module loaded
    by an earlier case would hide one loaded by a later): (exit code, loaded, stdout, stderr)."""
    folder = tmp_path_factory.mktemp("front-door")
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    results = {}
    for argv in _front_door_cases():
        proc = subprocess.run([sys.executable, "-c", _IMPORTED_BY_THE_COMMAND,
                               json.dumps([NOT_BEFORE_WORK, LIGHT]), json.dumps(argv)], cwd=folder,
                              env=env, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc
        out, _, last = proc.stdout.rstrip("\n").rpartition("\n")
        code, loaded = json.loads(last)
        results[tuple(argv)] = (code, loaded, out, proc.stderr)
    assert files_in(folder) == []  # nothing was written
    return results


def test_help_version_and_argument_errors_come_back_before_numpy_the_sandbox_and_checker(
        front_door):
    assert len(front_door) >= 2 * 11 + 9
    for argv, (code, loaded, out, err) in front_door.items():
        assert loaded == [], (argv, loaded)
        if "--help" in argv:
            usage = f"usage: gpsaccel {argv[0] if len(argv) > 1 else ''}".rstrip()
            assert code == 0 and out.startswith(usage), argv
        elif argv == ("--version",):
            from gpsaccel import __version__

            assert code == 0 and out.strip() == f"gpsaccel {__version__}"
        else:
            assert code == 2 and len(err.strip().splitlines()) == 1 and out.strip() == "", argv
            assert err.startswith("gpsaccel"), argv


def test_the_help_still_lists_the_registered_choices(front_door):
    """The problems (with their titles) and the homework come from the registry, read without
    importing a problem or homework module.  The registry is read as a fresh process has it (the
    command's own view), not as this pytest process has it: other tests register their own
    problems and homework (an instructor's), which the command never sees."""
    fresh = ("import json, gpsaccel.check, gpsaccel.assignments; from gpsaccel import registry; "
             "print(json.dumps("
             "[[(n, registry.entry(n).title) for n in registry.problems()], "
             "list(registry.assignments())]))")
    problems, assignments = json.loads(subprocess.run(
        [sys.executable, "-c", fresh], capture_output=True, text=True, check=True).stdout)
    assert [n for n, _ in problems][:4] == ["calibration", "coop", "ship", "tracker"]

    out = front_door[("check", "--help")][2]
    flat = " ".join(out.split())
    for name, title in problems:
        assert f"{name}: {' '.join(title.split())}" in flat, name
    assert "calibration, coop, ship, tracker" in " ".join(front_door[("--help",)][2].split())
    for name in assignments:
        assert name in front_door[("grade", "--help")][2]
        assert name in front_door[("grade", "x", "--assignment", "nope")][3]
    assert "error-model" in front_door[("montecarlo", "--help")][2]
    assert "invalid choice: 'nope'" in front_door[("montecarlo", "--truth", "nope")][3]


# ------------------------------------------------------------------------------ unknown flags
def test_an_unknown_flag_is_named_whatever_else_is_missing(front_door):
    """``gpsaccel check --no-such-flag`` said "the following arguments are required: paths"."""
    for command in ["", *_subcommands()]:
        argv = (command, "--no-such-flag") if command else ("--no-such-flag",)
        code, _, out, err = front_door[argv]
        prog = f"gpsaccel {command}".rstrip()
        assert code == 2 and err.startswith(f"{prog}: error: unrecognized arguments: "
                                            f"--no-such-flag "), (argv, err)


@pytest.mark.parametrize("argv, named", [
    (["check", "--no-such-flag", "--runs", "0"], "--no-such-flag"),      # and a bad value
    (["check", "x.py", "--runz", "3"], "--runz"),                         # a typo
    (["check", "x.py", "--run", "3", "--jsn=out.json"], "--jsn"),         # a prefix is a flag
    (["grade", "--studnet", "bob"], "--studnet"),                         # no SUBMISSIONS either
    (["assignment", "calibration", "--out", "x", "-q"], "-q"),
    (["--bogus", "run"], "--bogus"),                                      # before the command
    (["run", "extra"], "extra"),                                          # not a flag: named too
], ids=lambda v: " ".join(v) if isinstance(v, list) else None)
def test_unknown_flags_are_named_under_the_command_that_met_them(capsys, argv, named):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"error: unrecognized arguments: {named} " in err[0], err
    command = argv[0] if not argv[0].startswith("-") else ""
    assert err[0].startswith(f"gpsaccel {command}".rstrip() + ": error"), err


@pytest.mark.parametrize("argv", [
    ["compare", "--seed", "-1"],                # a negative number is a value, not a flag
    ["check", "x.py", "--run", "0"],            # a long flag by its prefix (--runs)
    ["check", "x.py", "--timeout=-1"],
    ["check", "x.py", "-vv", "--seed", "x"],    # short flags joined
])
def test_a_bad_value_is_still_named_by_its_flag(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unrecognized" not in err and "error: argument " in err, err


# ------------------------------------------------------------------------------ numeric flags
BAD_NUMBERS = [
    (["check", str(SUBMISSION), "--runs", "0"], "--runs", "integer >= 2"),
    (["check", str(SUBMISSION), "--runs", "-1"], "--runs", "integer >= 2"),
    (["check", str(SUBMISSION), "--timeout", "0"], "--timeout", "> 0"),
    (["check", str(SUBMISSION), "--seed", "-1"], "--seed", "integer >= 0"),
    (["check", str(SUBMISSION), "--workers", "0"], "--workers", "integer >= 1"),
    (["montecarlo", "--runs", "1"], "--runs", "integer >= 2"),
    (["montecarlo", "--chunk-size", "0"], "--chunk-size", "integer >= 1"),
    (["montecarlo", "--alpha", "1.5"], "--alpha", "(0, 1)"),
    (["run", "--seed", "-1"], "--seed", "integer >= 0"),
    (["figures", "--runs", "1.5"], "--runs", "must be an integer"),
    (["compare", "--seed", "-1"], "--seed", "integer >= 0"),
    (["coop", "--sets", "0"], "--sets", "integer >= 1"),
    (["coop", "--alpha", "nan"], "--alpha", "finite"),
    (["ship", "--runs", "0"], "--runs", "integer >= 2"),
    (["lessons", "--runs", "1"], "--runs", "integer >= 2"),
]


@pytest.fixture(scope="module")
def bad_numbers(tmp_path_factory):
    """Every case of BAD_NUMBERS run in an empty folder of its own: (result, folder) by case."""
    folders = [tmp_path_factory.mktemp("bad-number") for _ in BAD_NUMBERS]
    results = gpsaccel_cases([(argv, f) for (argv, _, _), f in zip(BAD_NUMBERS, folders,
                                                                    strict=True)])
    return list(zip(results, folders, strict=True))


@pytest.mark.parametrize("k", range(len(BAD_NUMBERS)), ids=lambda v: None)
def test_bad_number_is_refused_before_any_work(bad_numbers, k):
    argv, flag, expected = BAD_NUMBERS[k]
    res, folder = bad_numbers[k]
    assert_refused(res, f"argument {flag}:", expected, f"gpsaccel {argv[0]}: error")
    assert files_in(folder) == []


def _numeric_actions():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        for action in p._actions:
            if isinstance(action.default, int | float) and not isinstance(action.default, bool) \
                    or action.type in (int, float) \
                    or getattr(action.type, "__module__", None) == _v.__name__:  # default None
                yield name, action


def test_every_numeric_flag_of_every_subcommand_uses_a_shared_validator():
    """A sub-command added later with ``type=int`` would let ``--runs 0`` through to the work."""
    seen = list(_numeric_actions())
    assert len(seen) >= 15
    for name, action in seen:
        assert action.type not in (int, float, None), (name, action.option_strings)
        assert action.type.__module__ == _v.__name__, (name, action.option_strings)
        if "--seed" in action.option_strings:
            assert action.type is _v.flag_seed, name


@pytest.mark.parametrize("text", ["-1", "x", "1e3", "2.0"])
def test_seed_flag_names_itself(text):
    with pytest.raises(argparse.ArgumentTypeError, match="must be an integer"):
        _v.flag_seed(text)


def test_flag_float_bounds():
    parse = _v.flag_float(0.0, 1.0, open_min=True, open_max=True)
    assert parse("0.5") == 0.5
    for bad in ("0", "1", "inf", "-inf", "nan", "abc"):
        with pytest.raises(argparse.ArgumentTypeError):
            parse(bad)
    assert _v.flag_float(0.0)("0") == 0.0
    with pytest.raises(argparse.ArgumentTypeError, match=">= 0"):
        _v.flag_float(0.0)("-1e-300")


# ------------------------------------------------------------------------------ output paths
def test_output_paths_are_checked_before_any_work(tmp_path):
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    cases = [
        (["montecarlo", "--runs", "200000", "--out", str(a_file)], "--out", "not a folder"),
        (["run", "--out", str(a_file / "sub")], "--out", "not a folder"),
        (["figures", "--out", "/proc/gpsaccel-figures"], "--out", "not writable"),
        (["check", str(SUBMISSION), "--json", str(tmp_path)], "--json", "is a folder"),
        (["check", str(SUBMISSION), "--json", "/proc/x/results.json"], "--json", "not writable"),
        (["lessons", "--html", "/proc/gpsaccel-html"], "--html", "not writable"),
    ]
    results = gpsaccel_cases([(argv, tmp_path) for argv, _, _ in cases])
    for (_, flag, expected), res in zip(cases, results, strict=True):
        # refused by the parser: nothing computed, nothing printed
        assert_refused(res, f"argument {flag}:", expected)
    assert files_in(tmp_path) == ["a-file"]


def test_output_dir_probe_leaves_nothing(tmp_path):
    target = tmp_path / "new" / "deeper"
    assert _v.output_dir(str(target)) == target
    assert not (tmp_path / "new").exists() and list(tmp_path.iterdir()) == []


def test_oserror_during_the_work_is_one_line_exit_2(tmp_path):
    """A figure's name taken by a folder: the rename fails after the work; one line, exit 2."""
    out = tmp_path / "out"
    (out / "montecarlo-error-model-pave-minus-p.png").mkdir(parents=True)
    res = gpsaccel("montecarlo", "--runs", "20", "--no-progress", "--out", str(out), cwd=tmp_path)
    assert res.returncode == 2, res
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in res.stderr
    assert err[0].startswith("gpsaccel montecarlo: error: ") and "pave-minus-p.png" in err[0]
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary file left


def test_oserror_in_main_is_one_line(monkeypatch, capsys):
    import gpsaccel.calibration.compare as cmp

    def full_disk(**kwargs):
        raise OSError(28, "No space left on device", "/somewhere/file.png")

    monkeypatch.setattr(cmp, "compare", full_disk)
    assert main(["compare"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["gpsaccel compare: error: No space left on device: /somewhere/file.png"]


# ------------------------------------------------------------------------------ Ctrl-C
#: A hang guard, not an expected duration: how long a liveness test waits for an event that comes
#: within seconds when the code works (a loaded shared machine has taken minutes); the tests fail
#: by the event never coming, never by a clock.
HANG = 600.0


def _wait_for_line(fd: int, proc: subprocess.Popen, line: bytes) -> None:
    """Block until the child writes ``line`` to the pipe ``fd`` (its event), or fail when it ends
    first (EOF) or the hang guard runs out."""
    import select

    seen = b""
    while line not in seen:
        ready, _, _ = select.select([fd], [], [], HANG)
        assert ready, f"no {line!r} from the child within {HANG:g} s"
        chunk = os.read(fd, 4096)
        assert chunk, f"the child ended before {line!r}: {proc.communicate(timeout=HANG)}"
        seen += chunk


def test_ctrl_c_is_one_line_exit_130_and_writes_nothing(tmp_path):
    """Ctrl-C while the ensemble is computed: one line, exit 130, no file.  The child says when its
    first chunk of the ensemble starts (a line on a pipe); the signal comes after that, so it lands
    in the work whatever the load: the 200,000 runs are about 5 CPU s, chunks of 1,000 runs
    (about 30 ms each) between which Python takes it.  Not more: an interrupt that is lost lets
    the whole ensemble run before the test fails (2,000,000 runs cost one such failure 67 CPU s
    at load 5)."""
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    read, write = os.pipe()
    code = ("import os, sys\n"
            "import gpsaccel.calibration.montecarlo.engine as mc\n"
            "real = mc._chunk_sums\n"
            "def chunk_sums(*args, **kwargs):\n"
            f"    os.write({write}, b'running\\n')\n"
            "    return real(*args, **kwargs)\n"
            "mc._chunk_sums = chunk_sums\n"
            "from gpsaccel.cli import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    proc = subprocess.Popen([sys.executable, "-c", code, "montecarlo", "--runs", "200000",
                             "--no-progress", "--out", str(out)], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, pass_fds=(write,))
    os.close(write)
    try:
        _wait_for_line(read, proc, b"running\n")
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
        stdout, stderr = proc.communicate(timeout=HANG)  # the guard only stops a hang
    finally:
        os.close(read)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, stderr
    assert stderr.strip().splitlines() == ["gpsaccel montecarlo: interrupted"]
    assert stdout == ""
    assert not out.exists() or files_in(out) == []


class _Interrupting:
    """An artist whose drawing is interrupted halfway, as by Ctrl-C during savefig."""

    def __init__(self, fig):
        from matplotlib.artist import Artist

        class Boom(Artist):
            def draw(self, renderer):
                raise KeyboardInterrupt

        fig.add_artist(Boom())


def test_interrupted_figure_leaves_neither_file_nor_temporary(tmp_path):
    from matplotlib.figure import Figure

    target = tmp_path / "figure.png"
    good = Figure()
    good.add_subplot().plot([0, 1])
    _atomic.savefig(good, target, dpi=50)
    before = target.read_bytes()
    assert before.startswith(b"\x89PNG") and oct(target.stat().st_mode & 0o777) != "0o600"
    bad = Figure()
    bad.add_subplot().plot([1, 0])
    _Interrupting(bad)
    with pytest.raises(KeyboardInterrupt):
        _atomic.savefig(bad, target, dpi=50)
    assert target.read_bytes() == before  # the previous, complete file is still there
    assert files_in(tmp_path) == ["figure.png"]
    with pytest.raises(KeyboardInterrupt):
        _atomic.savefig(bad, tmp_path / "new.png", dpi=50)
    assert files_in(tmp_path) == ["figure.png"]


# ------------------------------------------------------------------------------ seeds
def test_compare_refuses_an_unreproducible_seed():
    from gpsaccel.calibration.compare import compare

    for bad in (None, -1, 1.5):
        with pytest.raises(ValueError, match="seed must be an integer"):
            compare(seed=bad)


def test_check_many_refuses_bad_numbers_before_running_anyone(tmp_path):
    from gpsaccel.classrun import check_many

    for kwargs, name in (({"n_runs": 0}, "n_runs"), ({"seed": -1}, "seed"),
                         ({"timeout": 0}, "timeout")):
        with pytest.raises(ValueError, match=name):
            check_many([SUBMISSION], executor=None, **kwargs)


def _student_pids(folder: Path) -> dict[int, str]:
    """PID -> file name of every sandboxed runner of a file in ``folder`` (its working folder, the
    box, holds the copy of the file; a warm box's runner is a fork of the zygote and keeps its
    command line).  The scan is machine-wide, so the callers name their files uniquely: another
    test (or another checkout's run) checking an ``alice.py`` at the same time would otherwise be
    counted as ours."""
    names = {p.name for p in folder.iterdir()}
    found = {}
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            cmd = (proc / "cmdline").read_bytes().split(b"\0")
            if not any(part.endswith((b"_runner.py", b"_zygote.py")) for part in cmd):
                continue
            for name in names & set(os.listdir(proc / "cwd")):
                found[int(proc.name)] = name
        except OSError:
            continue
    return found


def _students_running(folder: Path) -> set[str]:
    return set(_student_pids(folder).values())


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_ctrl_c_during_a_parallel_check_stops_workers_and_students(tmp_path):
    """Ctrl-C reaches the whole group: the busy workers stop their task (the student's process,
    in a session of its own, is killed on the way out) and the idle one (carol's check is done)
    ignores it, instead of each printing a traceback or waiting for the students' time limit."""
    subs = tmp_path / "subs"
    subs.mkdir()
    loop = (ROOT / "tests" / "submissions" / "broken_infinite_loop.py").read_text()
    tag = uuid.uuid4().hex[:12]  # names no other run on the machine uses (see _student_pids)
    alice, bob, carol = (f"{who}_{tag}.py" for who in ("alice", "bob", "carol"))
    for name in (alice, bob):
        (subs / name).write_text(loop)
    (subs / carol).write_text(SUBMISSION.read_text())
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")
    # the students' time limit is beyond every wait below: only the interrupt can end the check
    # (exit 130; a time limit would give exit 1 with findings)
    proc = subprocess.Popen([sys.executable, "-m", "gpsaccel.cli", "check", str(subs), "--runs",
                             "2", "--workers", "3", "--timeout", str(10 * HANG)], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + HANG  # a hang guard: the event is the two loops running
        while (_students_running(subs) != {alice, bob} and proc.poll() is None
               and time.monotonic() < deadline):
            time.sleep(0.2)  # until carol's two runs are done (her worker idle), the others loop
        assert _students_running(subs) == {alice, bob}
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=HANG)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        # the checker kills its students on the way out: wait for them to be gone (they loop
        # forever otherwise, so the guard only bounds a failure)
        give_up = time.monotonic() + HANG
        while _student_pids(subs) and time.monotonic() < give_up:
            time.sleep(0.1)
        leftovers = _student_pids(subs)
        for pid in leftovers:  # a failed run must not leave endless loops on the machine
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
    assert not leftovers, leftovers
    assert proc.returncode == 130, stderr
    lines = [line for line in stderr.strip().splitlines() if not line.startswith("sandbox: ")]
    assert lines == ["gpsaccel check: interrupted"], stderr
