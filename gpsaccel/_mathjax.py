"""MathJax for pages read offline: the MathJax 2.7 that the ``jupyter-server-mathjax`` package
ships, copied next to the pages (the Sphinx site's ``_static/``, the folder of
``gpsaccel lessons --html``), so math is typeset with no network.

Both the docs (``mathjax_path`` in ``docs/conf.py``) and the lessons' HTML template load it as
:data:`URL` relative to the page that :func:`copy_to` returns.
"""

from __future__ import annotations

import shutil
from pathlib import Path

#: MathJax 2's configuration: TeX input with the AMS macros, HTML-CSS output, the Safe extension
#: (no JavaScript from a notebook's markdown); both files are in the package.
CONFIG = "TeX-AMS-MML_HTMLorMML-full,Safe"

#: MathJax's settings for the copy: the package ships only the STIX-Web fonts (not MathJax's
#: default TeX ones), so HTML-CSS is told to use them rather than fall back to the system's fonts.
HUB_CONFIG: dict = {
    "tex2jax": {"inlineMath": [["$", "$"], ["\\(", "\\)"]],
                "displayMath": [["$$", "$$"], ["\\[", "\\]"]], "processEscapes": True},
    "HTML-CSS": {"availableFonts": [], "preferredFont": None, "webFont": "STIX-Web",
                 "imageFont": None},
}

#: The folder name the copy gets, next to the pages.
FOLDER = "mathjax"


def source() -> Path:
    """The folder holding ``MathJax.js`` in the installed ``jupyter-server-mathjax``."""
    try:
        import jupyter_server_mathjax
    except ModuleNotFoundError:
        raise ModuleNotFoundError(
            "offline math needs the package jupyter-server-mathjax: "
            "pip install 'gpsaccel[lessons]' (or [docs])") from None
    folder = Path(jupyter_server_mathjax.__file__).resolve().parent / "static"
    if not (folder / "MathJax.js").is_file():
        raise FileNotFoundError(f"jupyter-server-mathjax holds no MathJax.js in {folder}")
    return folder


def copy_to(folder: Path | str) -> str:
    """Copy MathJax into ``folder/mathjax`` (once: a copy already there of the same ``MathJax.js``
    is kept) and return the URL to load it with, relative to a page in ``folder``."""
    src = source()
    target = Path(folder) / FOLDER
    marker = target / "MathJax.js"
    if not (marker.is_file() and marker.read_bytes() == (src / "MathJax.js").read_bytes()):
        shutil.copytree(src, target, dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    return url()


def config_script() -> str:
    """The ``<script type="text/x-mathjax-config">`` that applies :data:`HUB_CONFIG`."""
    import json

    return (f'<script type="text/x-mathjax-config">MathJax.Hub.Config({json.dumps(HUB_CONFIG)});'
            "</script>")


def url(prefix: str = "") -> str:
    """``mathjax/MathJax.js?config=…`` below ``prefix`` (e.g. ``"../"`` for a page one level
    down)."""
    return f"{prefix}{FOLDER}/MathJax.js?config={CONFIG}"
