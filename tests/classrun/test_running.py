"""One run of a task over a class (gpsaccel.classrun.running): the seed drawn once, the imports
warmed once before the pool forks, entries without a submission never run, an item that dies or
raises lost for its own entry only and worded by the sandbox's table, Ctrl-C."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from gpsaccel.classrun import Entry, Interrupted, Task, run
from gpsaccel.classrun.running import WARM_FROM, backend_of, jobs_of, lost_text, seed_of, warm_of
from gpsaccel.sandbox import Lost, Warm, zygote
from gpsaccel.sandbox.outcomes import OUTCOMES

WARMED: list[int] = []


class _Toy(Task):
    """Items by name: ``ok`` returns what it inherited, ``dies`` ends its process, ``raises``
    raises, ``stops`` sends Ctrl-C to the run and waits."""

    timeout, deadline = 5.0, 30.0

    def warm(self) -> None:
        WARMED.append(os.getpid())

    def item(self, entry: Entry) -> dict:
        if entry.student == "dies":
            os._exit(3)
        if entry.student == "raises":
            raise ValueError("boom")
        if entry.student == "stops":
            os.kill(os.getppid(), signal.SIGINT)
            time.sleep(60)  # killed by the run on its way out
        return {"student": entry.student, "pid": os.getpid(), "warmed": list(WARMED)}

    def refused(self, entry: Entry) -> dict:
        return {"student": entry.student, "refused": entry.problem[0]}

    def lost(self, entry: Entry, why: str) -> dict:
        return {"student": entry.student, "lost": why}


def _entries(*names: str) -> list[Entry]:
    return [Entry(n, None, ("no-notebook", "none")) if n == "nothing" else
            Entry(n, Path(f"{n}.py"), id=n) for n in names]


def test_a_lost_item_is_its_own_entrys_only_and_worded_by_the_sandbox():
    WARMED.clear()
    seen: list[int] = []
    results = run(_Toy(), _entries("ok", "dies", "raises", "nothing", "ok2"), 2,
                  on_result=lambda i, r: seen.append(i))
    assert sorted(seen) == [0, 1, 2, 3, 4] and seen[0] == 3  # the refused one at once, here
    ok, dies, raises, nothing, ok2 = results
    assert ok["warmed"] == ok2["warmed"] == [os.getpid()]  # warmed once, here, then forked
    assert ok["pid"] != os.getpid() != ok2["pid"] != ok["pid"]  # a process per item
    assert dies == {"student": "dies", "lost": OUTCOMES["lost.died"].finding.format(
        detail="exit status 3", doing="running this item")}
    assert raises == {"student": "raises", "lost": "the run failed: ValueError: boom"}
    assert nothing == {"student": "nothing", "refused": "no-notebook"}


def test_in_this_process_one_after_the_other():
    WARMED.clear()
    results = run(_Toy(), _entries("ok", "raises", "nothing"), 1, executor=None)
    assert results[0] == {"student": "ok", "pid": os.getpid(), "warmed": [os.getpid()]}
    assert results[1]["lost"] == "the run failed: ValueError: boom"
    assert results[2]["refused"] == "no-notebook"


class _Boxes(_Toy):
    """Items that say which zygotes their boxes would start from (and whether they run)."""

    def boxes(self) -> tuple[Warm, ...]:
        return (Warm(("numpy",)), Warm(("numpy",), allow_gpsaccel=True))

    def item(self, entry: Entry) -> dict:
        return {"zygotes": sorted((z.pid, z.folder, z.allow_gpsaccel, z.alive())
                                  for z in zygote._ACTIVE)}


@pytest.mark.skipif(not zygote.usable(), reason="boxes start warm only as root on Linux")
def test_a_warm_run_serves_its_items_from_a_zygote_per_kind_gone_when_it_ends():
    warm = run(_Boxes(), _entries("a", "b", "nothing"), 2, warm_boxes=True)
    assert warm[0] == warm[1] and warm[2] == {"student": "nothing", "refused": "no-notebook"}
    served = warm[0]["zygotes"]
    assert sorted((allow, alive) for _, _, allow, alive in served) == [(False, True),
                                                                        (True, True)]
    for pid, folder, _, _ in served:  # killed by pid and reaped, their folders removed
        try:
            assert folder.encode() not in Path(f"/proc/{pid}/cmdline").read_bytes()
        except FileNotFoundError:
            pass
        assert not os.path.exists(folder)
    assert not zygote._ACTIVE
    assert run(_Boxes(), _entries("a"), 1, warm_boxes=False)[0] == {"zygotes": []}


def test_warm_boxes_only_where_they_can_start_warm():
    with pytest.raises(ValueError, match=r"warm_boxes \(--boxes warm\): .*not from 'dask-local'"):
        run(_Boxes(), _entries("a"), 1, executor="dask-local", warm_boxes=True)
    with pytest.raises(ValueError, match="warm_boxes must be True, False or None"):
        run(_Boxes(), _entries("a"), 1, warm_boxes=1)
    if not zygote.usable():
        with pytest.raises(ValueError, match="only as root on Linux"):
            run(_Boxes(), _entries("a"), 1, warm_boxes=True)


def test_boxes_start_warm_by_default_where_they_can_and_cold_elsewhere():
    """The default (None): warm as root on Linux with this machine's items and a class of at
    least WARM_FROM items (its zygotes' imports are paid once), cold with Dask's, for fewer
    items or where boxes cannot start warm, never an error."""
    assert warm_of(None, "processes") is warm_of(None, None) is zygote.usable()
    assert warm_of(None, "processes", WARM_FROM) is zygote.usable()
    assert warm_of(None, "processes", WARM_FROM - 1) is False
    assert warm_of(None, "dask-local") is False and warm_of(None, "tcp://h:1") is False
    assert warm_of(False, "processes") is False
    assert run(_Boxes(), _entries(*"abcdefg"), 2)[0]["zygotes"] == []
    ran = run(_Boxes(), _entries(*"abcdefgh"), 2)[0]["zygotes"]
    assert len(ran) == (2 if zygote.usable() else 0)


def test_the_lost_wording_states_the_deadline_and_its_slack():
    task = _Toy()
    task.timeout, task.deadline = 60.0, 180.0
    text = lost_text(Lost("too-long", "30 s"), task)
    assert text == ("running this item took more than 180 s (time limit plus 120 s) and was "
                    "stopped")
    assert lost_text(Lost("unheard-of", "why"), task) == "why"


def test_ctrl_c_stops_the_run_and_keeps_what_finished():
    with pytest.raises(Interrupted) as exc:
        run(_Toy(), _entries("ok", "stops", "ok2"), 1)
    assert isinstance(exc.value, KeyboardInterrupt)  # the command exits 130
    assert exc.value.results[0]["student"] == "ok" and exc.value.results[1:] == [None, None]


def test_the_settings_are_checked_once_before_anything_runs():
    seeds = {seed_of(None) for _ in range(3)}
    assert all(drawn and 0 <= s < 2**63 for s, drawn in seeds) and len(seeds) == 3
    assert seed_of(7) == (7, False)
    for bad in (-1, 1.5, "7"):
        with pytest.raises(ValueError, match="seed"):
            seed_of(bad)
    assert jobs_of(None, 3) == 3 and jobs_of(2, 3) == 2
    with pytest.raises(ValueError, match="max_workers"):
        jobs_of(0, 3, "max_workers")
    with pytest.raises(ValueError, match="sandbox must be one of"):
        backend_of("docker")
