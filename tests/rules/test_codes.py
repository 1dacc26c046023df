"""Population codes: hand-computed values, round trips, patterns and validation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sigmapi import ConfigError, PopulationCode
from sigmapi.codes import grid_coordinates, noisy


def test_hill_values_match_formula():
    code = PopulationCode((5,), width=0.5, height=2.0, normalize=False)
    c = code.encode([[0.5]])[0]  # grid coordinate 2.0
    expected = 2.0 * np.exp(-((np.arange(5) - 2.0) ** 2) / (2 * 0.25))
    np.testing.assert_allclose(c, expected)


def test_normalised_codes_have_unit_length():
    code = PopulationCode((15, 15), width=1.0)
    c = code.encode(np.random.default_rng(0).random((20, 2)))
    np.testing.assert_allclose(np.linalg.norm(c, axis=1), 1.0)


def test_flattening_is_c_order():
    code = PopulationCode((4, 6), normalize=False)
    c = code.encode([[1.0, 0.0]])[0].reshape(4, 6)  # row 3, column 0
    assert np.unravel_index(np.argmax(c), (4, 6)) == (3, 0)
    np.testing.assert_array_equal(grid_coordinates((2, 3))[:, 0], [0, 0, 0, 1, 1, 1])


def test_periodic_wraps_around():
    code = PopulationCode((10,), width=1.0, periodic=True, normalize=False)
    c = code.encode([[0.0]])[0]
    assert c[1] == pytest.approx(c[9])
    bounded = PopulationCode((10,), width=1.0, normalize=False).encode([[0.0]])[0]
    assert bounded[9] < 1e-10


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.floats(0.0, 1.0), min_size=1, max_size=3),
    st.sampled_from([0.5, 1.0, 2.0]),
    st.booleans(),
    st.booleans(),
)
def test_decode_inverts_encode(p, width, periodic, normalize):
    shape = tuple([9, 7, 5][: len(p)])
    code = PopulationCode(shape, width=width, periodic=periodic, normalize=normalize)
    got = code.decode(code.encode([p]))[0]
    diff = np.abs(got - np.asarray(p))
    if periodic:
        diff = np.minimum(diff, 1.0 - diff)
    assert np.all(diff < 1e-6)


def test_pattern_holds_every_point():
    code = PopulationCode((15, 15), width=0.5, normalize=False)
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [0.5, 0.0]])
    pat = code.pattern(pts).reshape(15, 15)
    for r, c in [(0, 0), (14, 14), (7, 0)]:
        assert pat[r, c] == pytest.approx(1.0)
    ell = code.l_shape().reshape(15, 15)
    assert (ell > 0.5).sum() >= 10


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"shape": (15, 0)}, "shape must be"),
        ({"shape": (15,), "width": 0.0}, "width must be"),
        ({"shape": (15,), "width": float("nan")}, "width must be"),
        ({"shape": (15,), "height": -1.0}, "height must be"),
    ],
)
def test_bad_parameters_are_named(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        PopulationCode(**kwargs)


@pytest.mark.parametrize("p", [[[1.5]], [[np.nan]], [[0.1, 0.2]], [[-0.1]]])
def test_bad_positions_are_refused(p):
    with pytest.raises(ValueError, match="p must"):
        PopulationCode((9,)).encode(p)


def test_noisy_codes_have_the_stated_statistics():
    """Thresholds: over 20,000 draws the Poisson mean is within 2 % of the rate at each unit,
    and the Gaussian noise sd within 2 % of level x peak."""
    rng = np.random.default_rng(0)
    c = np.repeat(PopulationCode((9,)).encode([[0.4]]), 20_000, axis=0)
    counts = noisy(c, "poisson", 10.0, rng, normalize=False)
    want = 10.0 * c[0] / c[0].max()
    big = want > 1.0
    np.testing.assert_allclose(counts.mean(0)[big], want[big], rtol=0.02)
    assert np.all(counts == np.round(counts)) and np.all(counts >= 0)
    g = noisy(c, "gaussian", 0.1, rng, normalize=False) - c
    assert abs(g.std() / (0.1 * c[0].max()) - 1.0) < 0.02
    unit = noisy(c[:50], "gaussian", 0.3, rng)
    np.testing.assert_allclose(np.linalg.norm(unit, axis=1), 1.0)
    np.testing.assert_array_equal(noisy(c[:5], "gaussian", 0.0, rng), c[:5])
    with pytest.raises(ValueError, match="kind must be one of"):
        noisy(c, "uniform", 1.0, rng)
    with pytest.raises(ValueError, match="level must be"):
        noisy(c, "poisson", 0.0, rng)
