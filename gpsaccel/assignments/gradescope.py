"""A Gradescope autograder whose scores a student cannot forge.

``gpsaccel assignment NAME --out DIR`` writes ``DIR/NAME-gradescope.zip`` (:func:`build`), laid out
as Gradescope's autograder specification asks (``setup.sh`` and ``run_autograder`` at the top; the
zip is unpacked into ``/autograder/source``; the student's files are in
``/autograder/submission``, who they are in ``/autograder/submission_metadata.json``; the result
goes to ``/autograder/results/results.json``).  It carries:

* the gpsaccel wheel itself (rebuilt from the installed package, :func:`package_wheel`): the
  container installs it, its dependencies from Gradescope's usual index (PyPI), nothing else;
* ``config.json``: the homework, the roster's email / SID -> student id (so the student's
  variant is the one of their hand-out notebook); ``secret``: the instructor's secret (only
  root can read ``/autograder/source``: ``setup.sh`` makes it so);
* the homework's folder when it is an instructor's own (``gpsaccel assignment course/cv2d``).

``run_autograder`` calls :func:`run`: the notebook is graded by
:func:`gpsaccel.assignments.grading.grade_notebook`, exactly as ``gpsaccel grade`` grades it: it
runs only inside gpsaccel's sandbox (bubblewrap where the container allows it; otherwise, as root,
the box user and its limits), on fresh data drawn from a seed made here and never written where
the box can see, with the student's variant; every score is computed by this process after the
box is empty.  Nothing the student's code writes is read back as a score: ``results.json`` is
written by :func:`run` once the box is gone, replacing whatever is there.  What the student sees
is the feedback text of the student renderer (their observed values, never the expected ones).

Otter's own zip (``DIR/NAME-autograder.zip``) is still written for otter's tools; the students'
``grader.check`` cells need none of this and work as before.
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import zipfile
from pathlib import Path

#: What ``run_autograder`` runs (Gradescope runs it as root in ``/autograder``): ``python -I``,
#: so neither the working folder nor ``PYTHONPATH`` comes before the installed package.
RUN_AUTOGRADER = """#!/usr/bin/env bash
# gpsaccel's autograder: the notebook runs only in gpsaccel's sandbox, scores are computed outside
exec /autograder/venv/bin/python -I -m gpsaccel.assignments.gradescope /autograder
"""

#: ``setup.sh``: bubblewrap if the image has it, a venv, the carried wheel (its dependencies from
#: PyPI), the source folder readable by root only (the secret and the roster are there), and the
#: installed package's folders a box may not read made root's alone (:func:`fence`), so a basic
#: box (the box user) cannot read them even where no Landlock or mount namespace fences them.
SETUP_SH = """#!/usr/bin/env bash
set -euo pipefail
apt-get update -q && (apt-get install -y -q bubblewrap python3-venv || apt-get install -y -q python3-venv)
python3 -m venv /autograder/venv
/autograder/venv/bin/pip install -q "$(ls /autograder/source/gpsaccel-*.whl)[grading]"
chmod -R go-rwx /autograder/source
/autograder/venv/bin/python -I -m gpsaccel.assignments.gradescope --fence
"""


def _record_hash(data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"sha256={digest}"


def _license_text(dist, root: Path, name: str) -> str:
    """A license file the metadata names: in the dist-info's ``licenses/`` (a wheel or editable
    install), or beside the package folder (run from a source checkout, whose ``*.egg-info``
    names it without a copy)."""
    text = dist.read_text(f"licenses/{name}")
    if text is None and (root.parent / name).is_file():
        text = (root.parent / name).read_text(encoding="utf-8")
    if text is None:
        raise FileNotFoundError(f"gpsaccel's metadata names the license file {name!r}, which is "
                                "neither in its dist-info nor beside the package: reinstall gpsaccel")
    return text


def package_wheel(out: Path) -> Path:
    """A wheel of the installed gpsaccel (its package folder and metadata, as installed: from a
    wheel or a source checkout), written into ``out``; the lessons' masters are left out as the
    published wheel leaves them out.  The license files the metadata names go with it (the MIT
    license asks that its text accompany every copy)."""
    from importlib import metadata

    import gpsaccel

    dist = metadata.distribution("gpsaccel")
    version = dist.version
    root = Path(gpsaccel.__file__).resolve().parent
    info = f"gpsaccel-{version}.dist-info"
    path = out / f"gpsaccel-{version}-py3-none-any.whl"
    files: list[tuple[str, bytes]] = []
    for dirpath, dirnames, filenames in os.walk(root, followlinks=True):
        rel = Path(dirpath).relative_to(root)
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__" and not d.startswith(".")
                             and (rel / d).as_posix() != "_lessons/masters")
        for name in sorted(filenames):
            if not name.endswith((".pyc", ".pyo")):
                files.append(((Path("gpsaccel") / rel / name).as_posix(),
                              (Path(dirpath) / name).read_bytes()))
    meta = dist.read_text("METADATA") or ""
    files.append((f"{info}/METADATA", meta.encode()))
    for name in dist.metadata.get_all("License-File") or []:  # PEP 639: the MIT text travels along
        files.append((f"{info}/licenses/{name}", _license_text(dist, root, name).encode()))
    files.append((f"{info}/WHEEL", b"Wheel-Version: 1.0\nGenerator: gpsaccel\n"
                                   b"Root-Is-Purelib: true\nTag: py3-none-any\n"))
    entry = dist.read_text("entry_points.txt")
    if entry:
        files.append((f"{info}/entry_points.txt", entry.encode()))
    record = "".join(f"{n},{_record_hash(d)},{len(d)}\n" for n, d in files) + f"{info}/RECORD,,\n"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files:
            z.writestr(name, data)
        z.writestr(f"{info}/RECORD", record)
    return path


def fence(package: str | os.PathLike | None = None) -> list[Path]:
    """Make the folders of the installed gpsaccel that no box may read
    (:data:`gpsaccel.check.problem.BOX_HIDES`: the checks, the homework's answers, the lessons'
    masters and solutions) readable by their owner alone (``chmod -R go-rwx``); the folders
    changed.  ``setup.sh`` runs it as root, for whom the grader still reads them."""
    import gpsaccel
    from gpsaccel.check.problem import BOX_HIDES

    root = Path(package if package is not None else Path(gpsaccel.__file__).parent)
    done = []
    for rel in BOX_HIDES:
        top = root / rel
        if not top.is_dir() or top.is_symlink():
            continue
        for dirpath, dirnames, filenames in os.walk(top):
            for n in dirnames + filenames:
                path = os.path.join(dirpath, n)
                if not os.path.islink(path):
                    os.chmod(path, os.lstat(path).st_mode & ~0o077)
        os.chmod(top, top.stat().st_mode & ~0o077)
        done.append(top)
    return done


def _keys(s) -> list[str]:  # noqa: ANN001 - a roster's Student
    """What names a roster's student in Gradescope's submission metadata: their email (or an
    id that is one), their SID."""
    return [k for k in (s.email.lower(), s.id.lower() if "@" in s.id else "", s.sis_id) if k]


def unmatched(roster) -> list[str]:  # noqa: ANN001 - Students
    """The roster's ids of the students Gradescope could never find: neither an email (an id
    that is one counts) nor a SID, the two ways its metadata names a submitter."""
    return [s.id for s in roster or () if not _keys(s)]


def build(name: str, out: str | os.PathLike, roster=None, secret: bytes | None = None) -> Path:
    """``out/NAME-gradescope.zip`` (module docstring); ``roster``: the
    :class:`~gpsaccel.assignments.roster.Student` s (their email and SID name the Gradescope
    account), ``secret``: the instructor's (None: everyone gets the public notebook's numbers).
    A roster with students Gradescope cannot name (:func:`unmatched`: a plain roster of names)
    is a ValueError naming them: their every submission would score 0."""
    import tempfile

    from gpsaccel.assignments.generate import _FOLDERS

    out = Path(out)
    lost = unmatched(roster)
    if lost:
        raise ValueError(unmatched_message(lost))
    ids: dict[str, str] = {}
    for s in roster or ():
        for key in _keys(s):
            ids.setdefault(key, s.id)
    config = {"assignment": name, "ids": ids, "own_folder": name if name in _FOLDERS else None}
    target = out / f"{name}-gradescope.zip"
    with tempfile.TemporaryDirectory(prefix="gpsaccel-gs-") as tmp:
        wheel = package_wheel(Path(tmp))
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            for fname, text in (("setup.sh", SETUP_SH), ("run_autograder", RUN_AUTOGRADER)):
                info = zipfile.ZipInfo(fname)
                info.external_attr = 0o755 << 16
                z.writestr(info, text)
            z.write(wheel, wheel.name)
            z.writestr("config.json", json.dumps(config, indent=1))
            if secret:
                z.writestr("secret", secret)
            if name in _FOLDERS:
                folder = _FOLDERS[name]
                for p in sorted(folder.rglob("*")):
                    if p.is_file() and "__pycache__" not in p.parts:
                        z.write(p, (Path("homework") / name / p.relative_to(folder)).as_posix())
    return target


def unmatched_message(lost: list[str]) -> str:
    """Why no zip is written for a roster with students Gradescope cannot name."""
    from gpsaccel._untrusted import shown

    names = ", ".join(repr(shown(x, 60)) for x in lost[:5]) + (
        f" and {len(lost) - 5} more" if len(lost) > 5 else "")
    return (f"Gradescope names a submitter by email and SID, and the roster has neither for "
            f"{len(lost)} student(s) ({names}): their every submission would score 0. Give "
            f"Gradescope's roster (Roster > Download), or a CSV roster with email or sis_id "
            f"columns (docs/grading.md)")


# ------------------------------------------------------------------ in Gradescope's container
def _student_id(meta: dict, ids: dict[str, str]) -> tuple[str, str]:
    """(the roster id of the submitter, "") or ("", why not)."""
    users = meta.get("users") if isinstance(meta, dict) else None
    if not isinstance(users, list) or not users or not isinstance(users[0], dict):
        return "", "the submission names no student"
    user = users[0]
    for key in (str(user.get("email", "")).lower(), str(user.get("sid", "") or "")):
        if key and key in ids:
            return ids[key], ""
    if not ids:  # no roster: the public numbers for everybody, the account's email as the id
        return str(user.get("email") or user.get("id") or "student"), ""
    return "", ("your Gradescope account is not on the class roster this autograder carries: "
                "your instructor will grade this submission by hand")


def results(grade, possible: dict[str, float]) -> dict:
    """Gradescope's results.json for a :class:`~gpsaccel.assignments.grading.Grade`: one test per
    question (its score and points), the student's feedback as the output."""
    scores = {q: float(grade.scores.get(q, 0.0)) for q in possible}
    tests = [{"name": q, "score": scores[q], "max_score": float(p), "visibility": "visible"}
             for q, p in possible.items()]
    return {"score": sum(scores.values()), "output": grade.feedback,
            "visibility": "visible", "stdout_visibility": "hidden", "tests": tests}


def run(root: str | os.PathLike, sandbox: str = "auto") -> dict:
    """Grade the submission under ``root`` (``/autograder`` in the container) and write
    ``root/results/results.json``; returns what it wrote."""
    from gpsaccel._atomic import write_text
    from gpsaccel._untrusted import secret_seed
    from gpsaccel.assignments.generate import use_folder
    from gpsaccel.assignments.grading import grade_notebook, notebook_in, possible_of

    root = Path(root)
    source = root / "source"
    config = json.loads((source / "config.json").read_text(encoding="utf-8"))
    name = config["assignment"]
    if config.get("own_folder"):
        name = use_folder(source / "homework" / name)
    secret = (source / "secret").read_bytes() if (source / "secret").is_file() else None
    possible = possible_of(name)
    try:
        meta = json.loads((root / "submission_metadata.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        meta = {}
    student, why = _student_id(meta, config.get("ids") or {})
    path, problem = notebook_in(root / "submission", name) if student else (None, None)
    if problem is not None:  # the class's rule: none, several, too deep (never an unbounded walk)
        why = problem[1]
    if path is None:
        out = {"score": 0.0, "output": why, "visibility": "visible",
               "stdout_visibility": "hidden",
               "tests": [{"name": q, "score": 0.0, "max_score": p} for q, p in possible.items()]}
    else:
        g = grade_notebook(path, name, student, secret_seed(), secret=secret,
                           sandbox=sandbox, file=path.name)
        out = results(g, possible)
    (root / "results").mkdir(parents=True, exist_ok=True)
    write_text(root / "results" / "results.json", json.dumps(out, indent=1))
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m gpsaccel.assignments.gradescope /autograder``: what ``run_autograder`` runs."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    if args == ["--fence"]:  # setup.sh, as root
        for path in fence():
            print(f"readable by root only: {path}")
        return 0
    usage = ("usage: python -m gpsaccel.assignments.gradescope [ROOT | --fence]: grades "
             "ROOT/submission/ (default ROOT /autograder) with the autograder zip unpacked "
             "in ROOT/source/, writes ROOT/results/results.json")
    if len(args) > 1 or (args and args[0].startswith("-")):
        print(f"{usage}\nerror: unexpected argument(s): {' '.join(args)}", file=sys.stderr)
        return 2
    root = Path(args[0] if args else "/autograder")
    if not (root / "source" / "config.json").is_file():
        print(f"{usage}\nerror: ROOT: {root} has no source/config.json (unpack "
              "NAME-gradescope.zip into ROOT/source/)", file=sys.stderr)
        return 2
    run(root)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
