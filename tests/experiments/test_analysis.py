"""What a trained map learned, as arrays (analysis.py), and learning curves (curves.py)."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.analysis import map_data as analysis
from sigmapi.analysis.curves import checkpoints, costs


def test_fig8_data_views_share_z(model_2d):
    d8 = analysis.fig8_data(model_2d, seed=3, n_pairs=4)
    assert d8.x.shape == (6, 16) and d8.h.shape == (6, 12)
    pos_x = model_2d.x_code.decode(d8.x[:4])
    pos_y = model_2d.y_code.decode(d8.y[:4])
    np.testing.assert_allclose((pos_x + pos_y) / 2, np.repeat(d8.z[None], 4, axis=0), atol=1e-6)
    assert len(d8.labels) == 6 and 0.0 <= d8.invariance_spread <= 2.0


@pytest.mark.parametrize(
    ("transform", "name"),
    [
        (lambda g: g, "same orientation"),
        (lambda g: 3 - g, "rotated by 180"),
        (lambda g: np.stack([3 - g[:, 1], g[:, 0]], axis=1), "90 degrees clockwise"),
        (lambda g: np.stack([g[:, 1], 3 - g[:, 0]], axis=1), "90 degrees counter-clockwise"),
        (lambda g: np.stack([3 - g[:, 0], g[:, 1]], axis=1), "mirrored top-bottom"),
        (lambda g: g[:, ::-1], "main diagonal"),
    ],
)
def test_map_polarity_names(transform, name):
    som = SigmaPiSOM(map_shape=(4, 4), x_shape=(3, 3), y_shape=(3, 3))
    g = som.map_coords
    pol = analysis.map_polarity(som, centres=transform(g) / 3.0)
    assert name in pol.name
    assert pol.r2 == pytest.approx(1.0)


def test_map_polarity_1d():
    som = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,))
    g = som.map_coords
    assert analysis.map_polarity(som, centres=g / 4).name.startswith("same direction")
    assert analysis.map_polarity(som, centres=1 - g / 4).name.startswith("reversed")


def test_invariance_matrix_of_a_perfect_map_is_constant_on_antidiagonals(model_1d):
    inv = analysis.invariance_matrix(model_1d)
    n = inv.positions.size
    assert inv.winners.shape == (n, n)
    assert 0.0 < inv.constancy <= 1.0
    s = np.add.outer(np.arange(n), np.arange(n))
    perfect = analysis.InvarianceMatrix(0, inv.positions, s, s.astype(float), "", 1.0)
    assert perfect.constancy == 1.0


def test_weight_tiles_marginals_sum_the_other_axis(model_2d):
    t0 = analysis.weight_tiles(model_2d, axis=0)
    t1 = analysis.weight_tiles(model_2d, axis=1)
    assert t0.shape == t1.shape == (12, 4, 4)
    w = model_2d.weights_.reshape(12, 4, 4, 4, 4)
    np.testing.assert_allclose(t0, w.sum(axis=(2, 4)))
    np.testing.assert_allclose(t1, w.sum(axis=(1, 3)))


def test_checkpoints_are_block_multiples_and_end_at_the_run():
    pts = checkpoints(300_000, 20)
    assert pts[0] == 1000 and pts[-1] == 300_000
    assert all(p % 1000 == 0 for p in pts) and pts == sorted(set(pts))
    assert checkpoints(500, 5) == [500]
    lin = checkpoints(10_000, 10, spacing="linear")
    assert lin == list(range(1000, 10_001, 1000))


def test_learning_curve_records_each_checkpoint_once(curves):
    c = curves[0]
    assert c["t"] == sorted(set(c["t"])) and c["t"][-1] == 2000
    for key in ("sigma", "view_consistency", "z_error", "cost", "cost_winner", "usage"):
        assert len(c[key]) == len(c["t"])
    assert all(np.isfinite(c["cost"]))


def test_costs_match_the_models_cost(model_2d):
    batch = model_2d.sampler.sample(50, np.random.default_rng(0))
    c, cw = costs(model_2d, batch)
    assert c == pytest.approx(model_2d.cost(batch))
    assert cw == pytest.approx(model_2d.cost(batch, sigma=1e-5))
