"""The slider helper the lessons use."""

from __future__ import annotations

import pytest

from gpsaccel.lessons import HEADLESS_VARIABLE, sliders


@pytest.fixture(autouse=True)
def _closed_widgets():
    """Every widget a test made is closed after it: one left to the interpreter's shutdown
    closes its comm then, and printed an ImportError per widget at the end of the suite's run."""
    yield
    try:
        import ipywidgets
    except ImportError:  # the tests that need it skipped
        return
    ipywidgets.Widget.close_all()


def test_sliders_draw_the_default_once_without_a_front_end(monkeypatch, capsys):
    widgets = pytest.importorskip("ipywidgets")
    monkeypatch.setenv(HEADLESS_VARIABLE, "1")
    calls = []
    assert sliders(lambda a, b: calls.append((a, b)),
                   a=widgets.FloatSlider(value=0.5, min=0, max=1), b=widgets.IntSlider(value=3)) is None
    assert calls == [(0.5, 3)]
    assert "drawn once with a = 0.5, b = 3" in capsys.readouterr().out


def test_sliders_make_widgets_with_a_front_end_and_leave_no_repr(monkeypatch):
    widgets = pytest.importorskip("ipywidgets")
    monkeypatch.delenv(HEADLESS_VARIABLE, raising=False)
    calls = []
    s = widgets.FloatSlider(value=0.25, min=0, max=1, description="GPS every (steps)")
    assert sliders(lambda a: calls.append(a), a=s) is None   # nothing for Jupyter to print
    assert calls == [0.25]          # interact runs the callback once with the default as well
    assert s.style.description_width == "initial"           # the label in full


def test_a_slider_that_cannot_open_at_the_lessons_number_is_refused(monkeypatch):
    widgets = pytest.importorskip("ipywidgets")
    monkeypatch.setenv(HEADLESS_VARIABLE, "1")

    def tune(W=4e-4):
        return None

    log = widgets.FloatLogSlider(value=4e-4, base=10, min=-6, max=-1)   # Lab shows 10^-3.4
    with pytest.raises(ValueError, match="control 'W' opens at 0.000398.*default .* is 0.0004"):
        sliders(tune, W=log)
    sliders(tune, W=widgets.SelectionSlider(options=[1e-4, 4e-4, 1e-3], value=4e-4))
    with pytest.raises(ValueError, match="opens at 0.35"):
        sliders(lambda x=0.37: None, x=widgets.FloatSlider(value=0.37, min=0, max=1, step=0.05))


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # traitlets on a dict given whole, as here
def test_uncropped_figures_reach_the_kernel_as_a_setting_it_reads(monkeypatch, tmp_path):
    """``execute(crop_figures=False)`` starts the kernel with a command-line setting that the
    kernel's (traitlets) parser turns into the inline backend's ``print_figure_kwargs`` (a
    setting nothing read would be ignored silently, and the tests' runs would crop again)."""
    import contextlib

    import nbformat
    from matplotlib_inline.config import InlineBackend
    from traitlets.config import Application

    from gpsaccel.lessons import kernel

    app = Application()
    app.parse_command_line([kernel.UNCROPPED])
    assert InlineBackend(config=app.config).print_figure_kwargs == {"bbox_inches": None}
    assert InlineBackend().print_figure_kwargs == {"bbox_inches": "tight"}  # what it replaces

    seen = []

    class Client:
        def __init__(self, nb, **options):
            seen.append(options["extra_arguments"])

        def execute(self, **kwargs):  # env= (the private TMPDIR)
            return None

    monkeypatch.setattr("nbclient.NotebookClient", Client)
    monkeypatch.setattr(kernel, "_local_kernel", lambda: contextlib.nullcontext(None))
    path = tmp_path / "empty.ipynb"
    nbformat.write(nbformat.v4.new_notebook(), path)
    kernel.execute(path)
    kernel.execute(path, crop_figures=False)
    assert seen == [[], [kernel.UNCROPPED, kernel.UNLAID]]


def test_figures_drawn_without_layout_are_drawn_whole_and_left_as_they_were(monkeypatch):
    """The start-up line ``execute(crop_figures=False)`` gives the kernel (a setting its parser
    reads) wraps IPython's ``print_figure``: the figure is drawn (a label that cannot be drawn
    raises) without running its layout engine, and keeps that engine."""
    from ipykernel.kernelapp import IPKernelApp
    from IPython.core import pylabtools
    from matplotlib.figure import Figure

    from gpsaccel.lessons import kernel

    original = pylabtools.print_figure
    monkeypatch.setattr(pylabtools, "print_figure", original)     # put back after the test
    app = IPKernelApp()
    app.parse_command_line([kernel.UNLAID])
    (line,) = app.exec_lines
    namespace: dict = {}
    exec(line, namespace)                                          # as the kernel runs it
    assert set(namespace) == {"__builtins__"}                      # no name for the lesson

    fig = Figure(layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1])
    engine = fig.get_layout_engine()
    laid, drawn = [], []
    monkeypatch.setattr(engine, "execute", laid.append)
    axes_draw = type(ax).draw
    monkeypatch.setattr(type(ax), "draw", lambda *a: drawn.append(a) or axes_draw(*a))
    assert pylabtools.print_figure(fig, bbox_inches=None).startswith(b"\x89PNG")
    assert laid == [] and len(drawn) == 1 and fig.get_layout_engine() is engine
    ax.set_title(r"$\foo$")
    with pytest.raises(ValueError, match="Unknown symbol"):
        pylabtools.print_figure(fig, bbox_inches=None)
    assert fig.get_layout_engine() is engine
    ax.set_title("laid out")
    drawn.clear()
    original(fig, bbox_inches=None)
    assert laid == [fig] and len(drawn) == 2                       # what the wrapper skips
