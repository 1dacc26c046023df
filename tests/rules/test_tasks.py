"""The two-view sampler: relations hold, views lie in [0, 1], the distribution is right."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import ConfigError, PopulationCode, Relation, TwoViewSampler
from sigmapi.tasks import RELATIONS, kronecker


@pytest.mark.parametrize("name", sorted(RELATIONS))
def test_both_views_satisfy_the_relation(name):
    s = TwoViewSampler(name, PopulationCode((9, 9)), PopulationCode((9, 9)))
    b = s.sample(2000, np.random.default_rng(1))
    rel = RELATIONS[name]
    for px, py in [(b.px0, b.py0), (b.px1, b.py1)]:
        assert px.min() >= 0 and px.max() <= 1 and py.min() >= 0 and py.max() <= 1
        np.testing.assert_allclose(rel.forward(px, py), b.z, atol=1e-12)
    lo, hi = rel.z_range
    assert b.z.min() >= lo and b.z.max() <= hi
    np.testing.assert_allclose(b.x0, s.x_code.encode(b.px0))
    # the two views are independent draws, not copies
    assert np.mean(np.isclose(b.px0, b.px1)) < 0.01


def test_z_is_uniform_and_views_cover_the_axis():
    s = TwoViewSampler("mean", PopulationCode((15,)), PopulationCode((15,)))
    b = s.sample(40_000, np.random.default_rng(2))
    hist, _ = np.histogram(b.z, bins=10, range=(0, 1))
    assert hist.min() > 0.9 * 4000 and hist.max() < 1.1 * 4000
    # given z = 0.5 the feasible x is all of [0, 1]: x is uniform there
    mid = np.abs(b.z[:, 0] - 0.5) < 0.05
    assert 0.4 < b.px0[mid].mean() < 0.6


def test_direct_draw_matches_rejection_distribution():
    """z near the border is finished by the direct draw: same law as rejection."""
    s = TwoViewSampler("mean", PopulationCode((9,)), PopulationCode((9,)))
    z = np.full((20_000, 1), 0.2)  # acceptance 0.4: almost all done by rejection
    zb = np.full((20_000, 1), 0.002)  # acceptance 0.004: almost all done directly
    x_rej, _ = s.sample_view(z, np.random.default_rng(3))
    x_dir, _ = s.sample_view(zb, np.random.default_rng(4))
    # both: x uniform on [0, 2z]; compare the normalised positions
    u_rej = np.sort(x_rej[:, 0] / 0.4)
    u_dir = np.sort(x_dir[:, 0] / 0.004)
    grid = np.linspace(0, 1, 21)
    for u in (u_rej, u_dir):
        cdf = np.searchsorted(u, grid) / u.size
        assert np.max(np.abs(cdf - grid)) < 0.02


def test_custom_relation():
    shift = Relation(
        "shift", lambda x, y: x - y + 0.5, lambda z, x: x + 0.5 - z, lambda z, y: z + y - 0.5
    )
    s = TwoViewSampler(shift, PopulationCode((9,)), PopulationCode((9,)))
    b = s.sample(500, np.random.default_rng(0))
    np.testing.assert_allclose(b.px0 - b.py0 + 0.5, b.z)


def test_unknown_relation_and_mismatched_codes():
    with pytest.raises(ConfigError, match="relation must be one of"):
        TwoViewSampler("product", PopulationCode((9,)), PopulationCode((9,)))
    with pytest.raises(ConfigError, match="same number of dimensions"):
        TwoViewSampler("mean", PopulationCode((9,)), PopulationCode((9, 9)))


@pytest.mark.parametrize("name", sorted(RELATIONS))
def test_views_at_points_are_the_samplers_law(name):
    """``sample_at`` maps uniform points to the pairs ``sample`` draws: the relation holds,
    and each position's quartiles (z and both views) agree with the sampler's within the
    sampling error of 40,000 pairs."""
    periodic = RELATIONS[name].circular
    code = PopulationCode((5, 5), periodic=periodic)
    s = TwoViewSampler(name, code, code)
    at = s.sample_at(np.random.default_rng(3).random((40_000, 6)))
    drawn = s.sample(40_000, np.random.default_rng(4))
    rel = RELATIONS[name]
    for px, py in [(at.px0, at.py0), (at.px1, at.py1)]:
        assert px.min() >= 0 and px.max() <= 1 and py.min() >= 0 and py.max() <= 1
        got = rel.forward(px, py)
        gap = np.abs(got - at.z)
        if rel.circular:
            gap = np.minimum(gap, 1 - gap)
        assert gap.max() < 1e-12
    q = [0.25, 0.5, 0.75]
    for a, b in [(at.z, drawn.z), (at.px0, drawn.px0), (at.py1, drawn.py1)]:
        np.testing.assert_allclose(np.quantile(a, q, axis=0), np.quantile(b, q, axis=0), atol=0.02)
    np.testing.assert_array_equal(at.x0, s.x_code.encode(at.px0))


def test_kronecker_points_are_even_and_any_stretch_is_the_same():
    """The shifted Kronecker sequence: a stretch computed on its own is the same points, every
    point lies in the unit cube, and 4,096 points fill the 64 cells of a 4x4x4 grid far more
    evenly than random points (each cell's count off its mean 64 by at most one random
    cell's standard deviation, 8, and by less than half as much as random points' worst)."""
    rng = np.random.default_rng(5)
    shift = rng.random(3)
    p = kronecker(0, 4096, shift)
    np.testing.assert_array_equal(kronecker(1000, 96, shift), p[1000:1096])
    assert p.min() >= 0 and p.max() < 1

    def worst(points):
        cell = (np.floor(points * 4) @ np.array([16, 4, 1])).astype(int)
        return np.abs(np.bincount(cell, minlength=64) - 64).max()

    assert worst(p) <= 8 and worst(p) < worst(rng.random((4096, 3))) / 2


def test_points_of_the_wrong_shape_or_a_relation_without_bounds_are_refused():
    s = TwoViewSampler("mean", PopulationCode((5, 5)), PopulationCode((5, 5)))
    with pytest.raises(ConfigError, match=r"u must have shape \(n, 6\).*got \(10, 4\)"):
        s.sample_at(np.zeros((10, 4)))
    free = Relation("shift", lambda x, y: x - y, lambda z, x: x - z, lambda z, y: z + y)
    with pytest.raises(ConfigError, match="no x_bounds and y_bounds"):
        TwoViewSampler(free, PopulationCode((5,)), PopulationCode((5,))).sample_at(np.zeros((4, 3)))
