"""Every figure of the course reports, by report: ``gpsaccel figures --report 000|...|all``.

Each report has a module ``gpsaccel.figures.rNNN`` (declared to the registry below) with

* ``TITLE``: the report's one-line title,
* ``DEFAULT_RUNS``: the Monte Carlo size the report used (the CLI's default for ``--runs``),
* ``figures(runs: int, seed: int) -> Iterator[ReportFigure]``: draws the report's figures in order,
  computing what they share once,
* ``FIGURES``: the figure numbers the report lists, registered with
  :func:`gpsaccel.registry.add_report` when the module is imported.

The drawing itself lives in :mod:`gpsaccel.plots` (kinds of figure reused everywhere); a report
module only says which figure is which.  :func:`write_figures` saves PNGs named
``r{report}-fig{number}-{slug}.png`` and an ``index.html`` with the captions.
"""

from __future__ import annotations

import html
import importlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from matplotlib.figure import Figure

from gpsaccel import registry
from gpsaccel._atomic import savefig, write_text

#: The reports' figure modules, each registering its report when imported, in reading order (a new
#: report: its module, and one line here).
registry.provide("report", tuple(f"{__name__}.r{number}" for number in
                                 ("000", "001", "003", "002", "004")))


@dataclass
class ReportFigure:
    """One drawn figure of a report.  ``number`` is e.g. ``"07"``, ``"03b"``, ``"10a"``."""

    report: str
    number: str
    slug: str
    caption: str
    figure: Figure

    @property
    def filename(self) -> str:
        return f"r{self.report}-fig{self.number}-{self.slug}.png"


def available_reports() -> list[str]:
    """The reports the package covers, in reading order: every report a figure module registered
    (:func:`gpsaccel.registry.reports`; a new report is one module and one line above)."""
    return list(registry.reports())


def report_module(report: str):
    """The figure module of ``report``; ValueError naming the reports available."""
    if report not in available_reports():
        raise ValueError(f"report must be one of {', '.join(available_reports())} or 'all'; "
                         f"got {report!r}")
    return importlib.import_module(registry.report(report).module)


def write_figures(reports: list[str], out: Path | str, runs: int | None = None, seed: int = 0,
                  dpi: int = 110, results: dict[str, dict] | None = None,
                  progress: bool = False) -> list[Path]:
    """Draw ``reports`` into ``out`` as PNG plus ``index.html``; returns the PNG paths.

    ``runs`` overrides each report's Monte Carlo size (``DEFAULT_RUNS``) when given.
    ``results[report]``: what the caller has computed already, passed to that report's
    ``figures`` as keywords (``gpsaccel run`` passes report 000's single run and ensemble).
    ``progress``: a bar of the figures written, on stderr when it is a terminal.
    """
    import matplotlib.pyplot as plt
    from tqdm.auto import tqdm

    bar = tqdm(desc="figures", unit="figure", leave=False, disable=None if progress else True)

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[tuple[str, ReportFigure, Path]] = []
    for report in reports:
        module = report_module(report)
        n = module.DEFAULT_RUNS if runs is None else runs
        for fig in module.figures(n, seed, **(results or {}).get(report, {})):
            path = out / fig.filename
            savefig(fig.figure, path, dpi=dpi)  # whole or not at all
            plt.close(fig.figure)
            fig.figure = None  # drawn and saved; keep only the caption
            written.append((module.TITLE, fig, path))
            bar.set_postfix_str(f"report {report}", refresh=False)
            bar.update()
    bar.close()
    _write_index(out / "index.html", written, runs, seed)
    return [p for _, _, p in written]


def _write_index(path: Path, written: list, runs: int | None, seed: int) -> None:
    parts = ["<!doctype html><meta charset='utf-8'><title>gpsaccel figures</title>",
             "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}"
             "figure{margin:2em 0}img{max-width:100%}</style>",
             f"<h1>gpsaccel: the reports' figures</h1><p>seed {seed}"
             f"{'' if runs is None else f', {runs} Monte Carlo runs'}</p>"]
    title = None
    for report_title, fig, png in written:
        if report_title != title:
            title = report_title
            parts.append(f"<h2>Report {fig.report}: {html.escape(title)}</h2>")
        parts.append(f"<figure><img src='{png.name}' alt='{html.escape(fig.slug)}'>"
                     f"<figcaption><b>Figure {fig.number}.</b> {html.escape(fig.caption)}"
                     f"</figcaption></figure>")
    write_text(path, "\n".join(parts) + "\n")


def iter_report(report: str, runs: int | None = None, seed: int = 0,
                **options: object) -> Iterator[ReportFigure]:
    """Draw one report's figures without saving them (for notebooks).  ``options`` go to the
    report's ``figures`` (report 002's ``executor``: its filters on a pool while it draws)."""
    module = report_module(report)
    return module.figures(module.DEFAULT_RUNS if runs is None else runs, seed, **options)
