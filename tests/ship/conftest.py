"""The ship tests' shared model: report 004's defaults, built once per session."""

from __future__ import annotations

import pytest

from gpsaccel.ship.model import ShipModel


@pytest.fixture(scope="session")
def model():
    return ShipModel()
