"""The catalogue's vectorised filters against the package's multirate driver, and its resolution."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from gpsaccel import CalibrationModel, run_multirate
from gpsaccel.calibration import mistakes as cat
from gpsaccel.calibration.compare import reference_filter
from gpsaccel.calibration.simulation import simulate_many
from gpsaccel.check import TOLERANCE

MODEL = CalibrationModel()


@pytest.fixture(scope="module")
def z():
    return np.stack([r.z for r in simulate_many(MODEL, 4, seed=11)])


def _sigma(P):
    return np.sqrt(np.diagonal(P, axis1=-2, axis2=-1))


@pytest.mark.parametrize("method", ["filterpy", "information"])
def test_vectorised_reference_equals_run_multirate(z, method):
    x, P = cat.reference(MODEL).apply(z)
    f = reference_filter(MODEL, method)
    for r in range(z.shape[0]):
        x_r, P_r = f(z[r])
        sd = _sigma(P_r)
        assert np.max(np.abs(x[r] - x_r) / sd) < 1e-9
        assert np.max(np.abs(P - P_r) / (sd[:, :, None] * sd[:, None, :])) < 1e-11


#: The model's own matrices a mistake may change (its fields), and the rest it may replace (a
#: subclass's property, as the driver reads them).
_FIELDS = ("M0", "V", "W")
_PROPERTIES = ("Phi", "Gamma", "Q", "x0")


def _model_for(mistake: cat.Mistake) -> CalibrationModel | None:
    """The same mistake expressed as a CalibrationModel run through the package's driver, where
    a model can express it (a change of its matrices, not of the filter's loop)."""
    kw = {name: np.array(getattr(MODEL, name), dtype=float) for name in _FIELDS}
    replaced: dict[str, np.ndarray] = {}
    for change in mistake.changes:
        name = change[0]
        if name not in _FIELDS + _PROPERTIES:
            return None
        if len(change) == 2:
            (kw if name in _FIELDS else replaced)[name] = np.array(change[1], dtype=float)
        else:
            kw[name][change[1]] = change[2]
    if kw["W"].shape != (1, 1):
        return None  # Q = W·I: W is then the state's 3 x 3, which the model cannot hold
    props = {name: property(lambda self, v=value: v) for name, value in replaced.items()}
    return type("_Mistaken", (CalibrationModel,), props)(**kw)


EXPRESSIBLE = [m for m in cat.catalogue(MODEL) if _model_for(m) is not None]


@pytest.mark.parametrize("mistake", EXPRESSIBLE, ids=[f"{m.code}:{m.variant}" for m in EXPRESSIBLE])
def test_mutant_equals_driver_on_mistaken_model(z, mistake):
    x, P = cat.build(MODEL, (mistake,)).apply(z[:2])
    model = _model_for(mistake)
    for r in range(2):
        res = run_multirate(model, z[r])
        sd = _sigma(res.P)
        assert np.max(np.abs(x[r] - res.x_hat) / sd) < 1e-9
        assert np.max(np.abs(P - res.P) / (sd[:, :, None] * sd[:, None, :])) < 1e-11


def test_gps_rate_mistake_keeps_the_exact_mean_transition():
    """Φ(T) = Φ(Δt)⁴⁰ exactly, so process-noise-interval changes only the noise."""
    pni = cat.mutant("process-noise-interval", MODEL)  # Φ(Δt)⁴⁰ as the 40 steps compose it
    ref = cat.reference(MODEL)
    np.testing.assert_allclose(pni.A, ref.A, rtol=0, atol=1e-15)
    assert not np.allclose(pni.Qe, ref.Qe)
    np.testing.assert_allclose(pni.Qe[1, 1], 0.2**2 * 0.0004, rtol=1e-12)
    np.testing.assert_allclose(ref.Qe[1, 1], 40 * 0.005**2 * 0.0004, rtol=1e-12)


def test_every_entry_is_far_from_every_other_and_from_the_optimum(z):
    """Distinct entries differ by far more than the match tolerance, so a match is unambiguous."""
    outs = [("optimal", *cat.reference(MODEL).apply(z))]
    outs += [(str(m), *cat.build(MODEL, (m,)).apply(z)) for m in cat.catalogue(MODEL)]
    sd = _sigma(outs[0][2])
    for (a, xa, Pa), (b, xb, Pb) in itertools.combinations(outs, 2):
        d = max(np.max(np.abs(xa - xb) / sd),
                np.max(np.abs(Pa - Pb) / (sd[:, :, None] * sd[:, None, :])))
        assert d > 100 * TOLERANCE, (a, b, d)


def test_combinations_skip_mistakes_that_touch_the_same_ingredient():
    cov = cat.covariance_mistakes(MODEL)
    pairs = list(cat.combinations(cov, 2))
    for a, b in pairs:
        assert a.touches.isdisjoint(b.touches)
    steps = [m for m in cov if m.code == "missing-propagation"]
    assert len(steps) >= 2 and (steps[0], steps[1]) not in pairs
    assert len(pairs) < len(cov) * (len(cov) - 1) // 2


def test_codes_cover_the_issue():
    need = {"phi-sign", "process-noise-interval", "m0-order", "std-as-variance",
            "missing-propagation", "mean-not-propagated", "x0-total-state"}
    assert need <= set(cat.codes(MODEL))
    with pytest.raises(ValueError, match="code must be one of"):
        cat.mutant("no-such-code", MODEL)


def _same_entries(a, b):
    assert [(m.code, m.variant, m.message) for m in a] == [(m.code, m.variant, m.message)
                                                            for m in b]
    for m, n in zip(a, b, strict=True):
        assert len(m.changes) == len(n.changes)
        for c, d in zip(m.changes, n.changes, strict=True):
            assert c[:-1] == d[:-1] and np.array_equal(c[-1], d[-1])


def test_the_default_catalogue_is_made_once_and_read_only():
    """catalogue() and codes() of the default model share one set of entries per process (the
    checker's too), each array an entry changes read-only: a write raises, and the entries stay
    those a fresh build makes."""
    first, again = cat.catalogue(), cat.catalogue()
    assert all(m is n for m, n in zip(first, again, strict=True))
    assert cat.default_catalogue().catalogue() == first
    _same_entries(first, cat.covariance_mistakes() + cat.mean_mistakes())
    assert cat.codes() == tuple(dict.fromkeys(m.code for m in first))
    arrays = [c[-1] for m in first for c in m.changes if isinstance(c[-1], np.ndarray)]
    assert arrays and not any(a.flags.writeable for a in arrays)
    w = next(m for m in first if m.code == "w-value").changes[0][-1]
    with pytest.raises(ValueError, match="read-only"):
        w[0, 0] = 1.0
    _same_entries(cat.catalogue(), cat.covariance_mistakes() + cat.mean_mistakes())


def test_a_given_models_catalogue_is_made_from_its_numbers_at_each_call():
    """Not cached by model: a CalibrationModel's arrays are its caller's to change."""
    model = CalibrationModel()
    before = next(m for m in cat.catalogue(model) if m.code == "w-value").changes[0][-1]
    model.V[1, 1] = 0.09  # W = V₂₂ is the w-value mistake
    after = next(m for m in cat.catalogue(model) if m.code == "w-value").changes[0][-1]
    assert before[0, 0] == 0.04**2 and after[0, 0] == 0.09
    assert cat.catalogue()[0] is not cat.catalogue(CalibrationModel())[0]
