"""docs/_ext/stale_pages.py: an incremental docs build removes the generated API page of a module
that no longer exists (a stale ``gpsaccel.check.titles.rst`` failed ``sphinx -W``) and nothing
else.  The cleaning function on a planted folder, no Sphinx build: stdlib modules and a package
made here stand for the documented ones."""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _stale_pages():
    spec = importlib.util.spec_from_file_location(
        "_gpsaccel_docs_stale_pages", ROOT / "docs" / "_ext" / "stale_pages.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_only_pages_of_names_that_cannot_be_found_are_removed(tmp_path, monkeypatch):
    pkg = tmp_path / "src" / "docpkg"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "kept.py").write_text("class Thing:\n    def method(self):\n        pass\n")
    # exists, but its import fails: its page stays and Sphinx names the error
    (pkg / "broken.py").write_text("import docpkg_no_such_dependency\n")
    # a removed package leaves its folder behind with only its __pycache__
    (pkg / "gone_pkg" / "__pycache__").mkdir(parents=True)
    monkeypatch.syspath_prepend(str(tmp_path / "src"))
    for name in [n for n in sys.modules if n == "docpkg" or n.startswith("docpkg.")]:
        monkeypatch.delitem(sys.modules, name)

    folder = tmp_path / "generated"
    folder.mkdir()
    kept = ["json", "json.decoder", "json.JSONDecoder.decode", "docpkg", "docpkg.kept",
            "docpkg.kept.Thing", "docpkg.kept.Thing.method", "docpkg.broken"]
    stale = ["json.no_such_module", "json.decoder.NoSuchClass", "no_such_package_xyz.module",
             "docpkg.titles", "docpkg.kept.Thing.no_such_method", "docpkg.gone_pkg"]
    for name in kept + stale:
        (folder / f"{name}.rst").write_text(f"{name}\n")
    (folder / "notes.txt").write_text("not a page")
    (folder / "sub").mkdir()
    (folder / "sub" / "docpkg.titles.rst").write_text("below the folder: not autosummary's")
    old = 1_000_000_000
    for page in folder.glob("*.rst"):
        os.utime(page, (old, old))

    removed = _stale_pages().remove_stale_pages(folder)

    assert sorted(p.stem for p in removed) == sorted(stale)
    assert sorted(p.stem for p in folder.glob("*.rst")) == sorted(kept)
    assert all(p.stat().st_mtime == old for p in folder.glob("*.rst"))  # untouched: incremental
    assert (folder / "notes.txt").is_file() and (folder / "sub" / "docpkg.titles.rst").is_file()


def test_every_page_of_a_fresh_build_is_findable():
    """The names autosummary gives gpsaccel's pages (module pages) are found as they are; a
    renamed module's old name is not (the case that failed the lead's build)."""
    findable = _stale_pages().findable
    assert findable("gpsaccel.check.linear") and findable("gpsaccel.check.linear_consistency")
    assert findable("gpsaccel.check.linear.LinearProblem")
    assert not findable("gpsaccel.check.titles")
