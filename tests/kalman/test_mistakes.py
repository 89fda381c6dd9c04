"""One mechanism for a known mistake: every system's catalogue is made of the core's one entry type,
each entry a change of its system's ingredients, and the names that left kalman.epochs still read."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from gpsaccel.kalman import epochs
from gpsaccel.kalman.linear_catalogue import LinearCatalogue
from gpsaccel.kalman.linear_model import LinearModel
from gpsaccel.kalman.mistakes import Mistake, apply, combinations, with_changes


def _model() -> LinearModel:
    return LinearModel(Phi=[[1.0, 0.1], [0.0, 1.0]], Gamma=[[0.005], [0.1]], W=[[0.3]],
                       H=[[1.0, 0.0]], V=[[0.2]], M0=np.diag([1.0, 2.0]), x0=[0.0, 0.0],
                       every=3, n_epochs=5)


def _catalogues() -> dict[str, tuple]:
    from gpsaccel.calibration import mistakes as cal
    from gpsaccel.coop import mistakes as coop
    from gpsaccel.ship import mistakes as ship

    return {"calibration": cal.catalogue(), "linear": LinearCatalogue(_model()).catalogue(),
            "ship filter": ship.catalogue("filter"), "ship update": ship.catalogue("update"),
            "coop ekf": coop.catalogue(kind="ekf"), "coop lkf": coop.catalogue(kind="lkf")}


@pytest.mark.parametrize("name", list(_catalogues()))
def test_every_catalogue_is_made_of_the_one_entry_type(name):
    entries = _catalogues()[name]
    assert entries
    for m in entries:
        assert type(m) is Mistake, (name, m)
        assert m.code and m.title == m.variant and m.message and m.changes


def test_the_homework_entries_are_marked_in_the_catalogues_they_come_from():
    from gpsaccel.assignments import coop as hw_coop
    from gpsaccel.assignments import ship as hw_ship

    cats = _catalogues()
    assert hw_coop.ekf_mistakes() == tuple(m for m in cats["coop ekf"] if m.homework)
    assert hw_ship.update_mistakes() == cats["ship update"]
    assert all(m.hint for m in cats["ship update"])  # the homework says where to look


def test_the_ship_variants_are_combinations_of_its_entries():
    from gpsaccel.ship import mistakes as ship

    entries = set(ship.catalogue("filter"))
    vs = ship.variants()
    assert vs[0].mistakes == ()
    report = [v for v in vs[1:] if set(v.codes) <= set(ship.REPORT_CODES)]
    assert len(report) == 11  # the valid combinations of the report's four entries
    for v in vs[1:]:
        assert set(v.mistakes) <= entries and v.codes
        g = v.ingredients
        assert (g.zeroed, g.report_covariance, g.monorate_gain, g.no_input) == tuple(
            c in v.codes for c in ship.REPORT_CODES)
    # every other entry is matched on its own, and each entry is in some variant
    assert all(len(v.mistakes) == 1 for v in vs[1:] if v not in report)
    assert {m for v in vs for m in v.mistakes} == entries
    assert not any("report-covariance" in v.codes and "zeroed-gain" not in v.codes for v in vs)


def test_changes_apply_to_a_field_or_an_element_in_turn():
    @dataclass(frozen=True)
    class G:
        a: float = 1.0
        M: np.ndarray = field(default_factory=lambda: np.eye(2))

    one = Mistake("x", "a = 2", "", (("a", 2.0),))
    two = Mistake("y", "M₂₂ = 5", "", (("M", (1, 1), 5.0),))
    g = apply(G(), (one, two))
    assert g.a == 2.0 and g.M[1, 1] == 5.0 and G().M[1, 1] == 1.0  # the original is untouched
    assert with_changes(G(), (("M", (0, 1), 3.0), ("M", (1, 0), 4.0))).M.tolist() == [[1, 3],
                                                                                      [4, 1]]
    # entries that change the same ingredient never combine; an entry "alone" never combines
    same = Mistake("z", "a = 3", "", (("a", 3.0),))
    alone = Mistake("w", "own loop", "", (("b", True),), alone=True)
    assert list(combinations([one, same, two, alone], 2)) == [(one, two), (same, two)]


def test_the_names_that_left_epochs_still_read_from_it():
    from gpsaccel.kalman import linear_catalogue, linear_model, mistakes

    assert epochs.LinearModel is linear_model.LinearModel
    assert epochs.LinearIngredients is linear_model.LinearIngredients
    assert epochs.LinearCatalogue is linear_catalogue.LinearCatalogue
    assert epochs.Mistake is mistakes.Mistake and epochs.Catalogue is mistakes.Catalogue
    assert epochs.LINEAR_MESSAGES is linear_catalogue.LINEAR_MESSAGES
    with pytest.raises(AttributeError):
        epochs.NoSuchName  # noqa: B018
