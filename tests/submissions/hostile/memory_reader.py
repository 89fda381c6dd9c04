"""Hostile: reads the checker's memory through /proc, looking for the optimal x̂ and P."""
import ctypes
import os

ctypes.CDLL(None).prctl(15, b"gpsacc-hostile", 0, 0, 0)  # PR_SET_NAME: findable by the tests


def _checker_pids():
    """Processes whose command line says they are the checker (pytest, gpsaccel)."""
    for name in os.listdir("/proc"):
        if not name.isdigit() or int(name) == os.getpid():
            continue
        try:
            with open(f"/proc/{name}/cmdline", "rb") as f:
                cmd = f.read()
        except OSError:
            continue
        if os.path.basename(cmd.split(b"\0")[0]) == b"bwrap":
            continue  # the sandbox's own init, not the checker
        if b"pytest" in cmd or b"gpsaccel" in cmd:
            yield int(name), cmd


def _read_memory(pid):
    """Up to 1 MB of the first readable mapping, or raise OSError."""
    with open(f"/proc/{pid}/maps") as maps:
        regions = [line.split()[0] for line in maps if " r" in line[:30]]
    with open(f"/proc/{pid}/mem", "rb") as mem:
        for region in regions:
            start, end = (int(a, 16) for a in region.split("-"))
            try:
                mem.seek(start)
                data = mem.read(min(end - start, 1 << 20))
            except OSError:
                continue
            if data:
                return data
    raise OSError("no readable mapping")


def kalman_filter(z):
    import numpy as np

    found = list(_checker_pids())
    errors = []
    for pid, cmd in found:
        try:
            data = _read_memory(pid)
            with open(f"/proc/{pid}/environ", "rb") as f:
                env = f.read()
        except OSError as exc:
            errors.append(f"{pid}: {exc}")
            continue
        print(f"LEAK: read {len(data)} bytes of memory and {len(env)} bytes of environment "
              f"of the checker {pid} {cmd[:60]!r}")
        return np.zeros((len(z), 3)), np.tile(np.eye(3), (len(z), 1, 1))
    if not found:
        raise LookupError("the checker's process is not visible from here")
    raise PermissionError("could not read the checker's memory: " + "; ".join(errors)[:300])
