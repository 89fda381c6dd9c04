"""Run every benchmark script in this folder (``make bench``), one subprocess each, in name order.

Each script prints its own table; this runner adds a header per script and its wall time, and
exits non-zero if any script failed.  Arguments after ``--only`` restrict to scripts whose file
name contains one of them (``python benchmarks/run.py --only montecarlo``).  ``--markdown DIR``
(``make bench`` gives ``docs/benchmarks``) also writes each script's output to ``DIR/NAME.txt``
under a line saying when, where and at what load it was measured; the documentation's benchmark
page is made of these files, so no table there is typed by hand.  With it, each script also
publishes its figures (benchmarks/_figures.py): ``DIR/NAME.json`` holds them, the header line and
the sha256 of ``DIR/NAME.txt``, written together once the script has succeeded (a failed script
leaves the last pair as it was); tests/test_published_figures.py compares the docs' quoted
figures with them.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _figures import ENV

#: Scripts run on their own, not by ``make bench``: suite_cost.py runs the whole test suite;
#: lessons.py runs notebooks for many minutes and writes docs/benchmarks/lessons.txt itself (--write);
#: suite_per_test.py is a pytest plugin and the table of two of its runs.
SEPARATE = ("suite_cost.py", "lessons.py", "suite_per_test.py")


def _header(script: Path, seconds: float) -> str:
    import datetime
    import os
    import platform

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"`python benchmarks/{script.name}`, {datetime.date.today().isoformat()}, Python "
            f"{platform.python_version()}, {os.cpu_count()} CPUs, load average {load:.1f} at the "
            f"end, {seconds:.0f} s wall")


def _write(markdown: Path, script: Path, header: str, stdout: str, figures: Path) -> None:
    """``NAME.txt`` (the header and the table) and ``NAME.json`` (the figures the script
    published, if any, the header and the table's sha256)."""
    text = header + "\n" + stdout
    published = json.loads(figures.read_text(encoding="utf-8")) if figures.exists() else {}
    record = {"script": script.name, "measured": header,
              "txt_sha256": hashlib.sha256(text.encode("utf-8")).hexdigest(),
              "figures": published.get("figures", {})}
    (markdown / f"{script.stem}.txt").write_text(text, encoding="utf-8")
    (markdown / f"{script.stem}.json").write_text(json.dumps(record, indent=1, sort_keys=True)
                                                  + "\n", encoding="utf-8")


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parent
    markdown = None
    if "--markdown" in argv:
        i = argv.index("--markdown")
        markdown = Path(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
        markdown.mkdir(parents=True, exist_ok=True)
    only = argv[argv.index("--only") + 1:] if "--only" in argv else []
    scripts = sorted(p for p in here.glob("*.py") if p.name != Path(__file__).name
                     and not p.name.startswith("_") and p.name not in SEPARATE)
    if only:
        scripts = [p for p in scripts if any(o in p.name for o in only)]
    failed = []
    for script in scripts:
        print(f"=== {script.name} " + "=" * max(0, 70 - len(script.name)), flush=True)
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="bench-figures-") as tmp:
            figures = Path(tmp) / "figures.json"
            env = dict(os.environ, **({ENV: str(figures)} if markdown else {}))
            proc = subprocess.run([sys.executable, str(script)], cwd=here.parent, text=True,
                                  stdout=subprocess.PIPE if markdown else None, env=env)
            rc = proc.returncode
            seconds = time.perf_counter() - t0
            if markdown is not None:
                print(proc.stdout, end="", flush=True)
                if rc == 0:
                    _write(markdown, script, _header(script, seconds), proc.stdout, figures)
        print(f"--- {script.name}: exit {rc}, {seconds:.1f} s wall\n", flush=True)
        if rc != 0:
            failed.append(script.name)
    if failed:
        print(f"failed: {', '.join(failed)}")
        return 1
    print(f"{len(scripts)} benchmark script(s) done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
