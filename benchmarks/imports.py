"""What the heavy dependencies cost to import: the figures behind the package's lazy imports.

Several modules import filterpy, scipy.stats, scipy.integrate, mpmath or matplotlib in the
function that uses them rather than at module level (``gpsaccel/_lazy.py``, the models'
``kalman_filter``, ``kalman/consistency.py``'s χ² bounds, the coop model's truth, a check's and a
notebook's warm-up).  Their docstrings say why; the price is measured here.  Each case is a fresh
interpreter in an empty folder (``python -c "import numpy; import X"``), repeated; the table gives
medians of CPU (user + system, children included) and wall, and the CPU above the numpy floor,
which every one of these pays anyway.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import _cpu
import _figures

ROOT = Path(__file__).resolve().parents[1]

#: (case, what the interpreter imports after numpy)
CASES = [
    ("numpy (the floor)", ""),
    ("scipy.stats", "import scipy.stats"),
    ("filterpy.kalman (pulls in scipy.stats)", "import filterpy.kalman"),
    ("scipy.integrate", "import scipy.integrate"),
    ("mpmath", "import mpmath"),
    ("matplotlib.figure", "import matplotlib.figure"),
]


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be a positive integer, got {args.repeats}")
    start = _cpu.load()
    rows = []
    for name, code in CASES:
        cmd = ["-c", "import numpy" + (f"; {code}" if code else "")]
        rows.append((name, _cpu.medians(cmd, {"now": ROOT}, args.repeats)["now"]))
    floor = rows[0][1][0]
    print(f"start: {start}")
    print(f"end: {_cpu.load()}; medians of {args.repeats}, CPU = user + system, children "
          f"included\n")
    print("| import (after numpy) | CPU s | CPU s above the floor | wall s |")
    print("|---|---|---|---|")
    for name, (cpu, wall) in rows:
        print(f"| {name} | {cpu:.2f} | {cpu - floor:.2f} | {wall:.2f} |")
    _figures.publish({f"cpu_s/{code.removeprefix('import ') or 'numpy'}": cpu
                      for (_, code), (_, (cpu, _)) in zip(CASES, rows, strict=True)})
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
