"""The wheel the Gradescope zip carries is rebuilt from the installed package
(:func:`gpsaccel.assignments.gradescope.package_wheel`); the end-to-end autograder is in
tests/test_kit.py and tests/test_packaging.py."""

from __future__ import annotations

import zipfile
from importlib import metadata

from gpsaccel.assignments.gradescope import package_wheel


def test_the_rebuilt_wheel_carries_its_license_and_a_record_of_every_file(tmp_path):
    """From the installed package or a checkout (where ``gpsaccel.egg-info`` names the license
    without a copy): the MIT text goes with every copy."""
    wheel = package_wheel(tmp_path)
    dist = metadata.distribution("gpsaccel")
    licenses = dist.metadata.get_all("License-File")
    assert licenses, "the installed metadata names no License-File"
    info = f"gpsaccel-{dist.version}.dist-info"
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        assert {f"{info}/licenses/{name}" for name in licenses} <= names
        assert "MIT" in z.read(f"{info}/licenses/LICENSE").decode()
        recorded = {line.split(",")[0] for line in z.read(f"{info}/RECORD").decode().splitlines()}
    assert recorded == names
    assert "gpsaccel/__init__.py" in names and not any("_lessons/masters" in n for n in names)
