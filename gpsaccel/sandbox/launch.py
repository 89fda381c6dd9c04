"""A box ready to start, and its first process started (:class:`Prepared`): cold, the runner (basic)
or bwrap around it by exec; warm, the runner forked from a zygote (:mod:`.zygote`), whose keeper
joins what bwrap made around the box's pid 1 (bwrap) or confines the runner itself (basic).
Either way the first process takes the box's limits, uid and cgroup from one plan
(:func:`gpsaccel.sandbox.limits._entry_plan`); :mod:`.box` supervises what it started."""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from gpsaccel.sandbox import _boxuser, fence, warmbox, zygote
from gpsaccel.sandbox._removal import remove_tree
from gpsaccel.sandbox.confinement import (
    _bwrap_command,
    _environment,
    _python,
    bwrap_path,
)
from gpsaccel.sandbox.limits import _cap_last, _Confinement, _entry_plan, _nproc, _preexec
from gpsaccel.sandbox.spec import Limits
from gpsaccel.sandbox.submission import Submission, _copy_submission


def extra_processes(backend: str) -> int:
    """The box's own processes beside the runner, in its cgroup: bwrap's two (its own and the
    box's pid 1, warm or cold); a basic warm box's keeper is outside it, as a supervisor is."""
    return 2 if backend == "bwrap" else 0


@dataclass
class Prepared:
    """A box ready to start: its folder, confinement and the ends of its pipes the first process
    takes (``child_fds``: the result pipe's, the output pipe's, the go pipe's; closed here once
    it runs).  :meth:`cold` and :meth:`warm` start it."""

    backend: str
    tmp: Path
    sub: Submission
    limits: Limits
    allow_gpsaccel: bool
    hide: tuple[str, ...]
    c: _Confinement
    child_fds: list[int]
    owned: list[int]

    def nproc(self, extra: int) -> int:
        """RLIMIT_NPROC: a box uid runs nothing else, so it counts the box exactly (a basic warm
        box's keeper is root's, not counted); with a cgroup it is set a little above pids.max,
        so that the cgroup refuses the fork first and counts it."""
        if self.c.uid is None:
            return _nproc(self.limits)
        extra = extra if self.backend == "bwrap" else 0
        return self.limits.processes + 1 + extra + (8 if self.c.cgroup is not None else 0)

    def plan(self, extra: int) -> dict:
        drop = self.c.uid is not None if self.backend == "bwrap" else os.geteuid() == 0
        own_proc = self.backend == "basic" and self.c.uid is not None and \
            fence.private_proc_allowed()
        return _entry_plan(self.limits, self.nproc(extra), drop, _cap_last(), self.c, own_proc)

    def _folder(self) -> Path:
        box = self.tmp / "box"
        box.mkdir()
        _copy_submission(self.sub, box, self.c.uid)
        return box

    def _bwrap(self, warm: bool) -> tuple[list[str], list[int]]:
        exe = bwrap_path()
        if exe is None:
            raise OSError("bwrap was found usable for this check but its trial box no "
                          "longer starts")
        res_w, _, go_r = self.child_fds
        cmd, fds = _bwrap_command(exe, self.tmp, self.sub, self.limits, self.allow_gpsaccel,
                                  res_w, go_r, self.hide, warm)
        self.owned += fds
        return cmd, fds

    def _close_child_fds(self, fds: Sequence[int]) -> None:
        for fd in fds:  # the parent keeps only the reading ends
            os.close(fd)
            self.owned.remove(fd)

    def cold(self, extra: int) -> subprocess.Popen:
        """The runner (basic) or bwrap around it, started by exec."""
        res_w, out_w, go_r = self.child_fds
        if self.backend == "bwrap":
            # root without a box user: bwrap's user namespace is the box (no capability outside
            # it); with one, bwrap runs as that user and needs none either
            cmd, fds = self._bwrap(False)
            cwd, env = str(self.tmp), _environment("/box")
        else:
            box, fds = self._folder(), []
            control = self.tmp / "control"
            cmd = [_python(), "-I", "-S", "-B", str(control / "_runner.py"), str(control),
                   str(box), str(res_w), str(go_r)]
            cwd, env = str(box), _environment(str(box))
        proc = subprocess.Popen(
            cmd, stdin=subprocess.DEVNULL, stdout=out_w, stderr=out_w, cwd=cwd, env=env,
            pass_fds=(res_w, go_r, *fds), close_fds=True, start_new_session=True,
            preexec_fn=_preexec(self.plan(extra), self.c))
        self._close_child_fds([*self.child_fds, *fds])
        return proc

    def warm(self, z: zygote.Zygote, extra: int, wait: float) -> warmbox.WarmBox:
        """The runner forked from the zygote ``z``: its keeper joins what bwrap made around the
        box's pid 1 (bwrap), or confines the runner itself (basic)."""
        res_w, out_w, go_r = self.child_fds
        fds = {"out": out_w, "res": res_w, "go": go_r}
        plan = self.plan(extra)
        req: dict[str, object] = {"backend": self.backend, "plan": zygote.with_room(plan, z),
               "umask": _umask(),
               "ignored": [int(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
                           if signal.getsignal(s) == signal.SIG_IGN]}
        control = self.tmp / "control"
        if self.backend == "basic":
            box = self._folder()
            if self.c.fence is not None and self.c.fence.ruleset is not None:
                fds["ruleset"] = self.c.fence.ruleset
            req.update(cwd=str(box), env=_environment(str(box)),
                       argv0=str(control / "_runner.py"), argv=[str(control), str(box)])
            return warmbox.request(z, "basic", req, fds, wait)
        cmd, files = self._bwrap(True)
        proc, reaper, ns = warmbox.start_reaper(cmd, str(self.tmp), _environment("/box"), files,
                                               _preexec(plan, self.c), wait)
        self._close_child_fds(files)
        # bwrap's --chdir sets PWD for its command
        req.update(cwd="/box", env=dict(_environment("/box"), PWD="/box"),
                   argv0="/control/_runner.py", argv=["/control", "/box"])
        try:
            return warmbox.request(z, "bwrap", req, {**fds, **ns}, wait, proc, reaper,
                                  self.c.pids)
        except BaseException:
            os.close(reaper)
            proc.kill()
            proc.wait()
            raise
        finally:
            for fd in ns.values():
                os.close(fd)

    def cold_again(self) -> None:
        """After a warm start that did not happen: nothing of it left running, the box folder
        and cgroup as a cold box's."""
        if self.c.cgroup is not None:
            self.c.cgroup.kill()
        if self.c.uid is not None:
            _boxuser.kill_uid(self.c.uid)
        remove_tree(str(self.tmp / "box"))
        if self.c.cgroup is not None:
            self.c.cgroup.set_processes(self.limits.processes + 1 + extra_processes(self.backend))


def _umask() -> int:
    """This process's umask, which a cold box inherits (read, not set: a thread of ours may be
    making a file)."""
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    return 0o022
