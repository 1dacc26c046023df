"""The two-view sampler: relations hold, views lie in [0, 1], the distribution is right."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import ConfigError, PopulationCode, Relation, TwoViewSampler
from sigmapi.tasks import RELATIONS


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
