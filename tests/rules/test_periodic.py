"""Angles: the relation sum_mod, a periodic (toroidal) map, and the circular metrics.

Stated thresholds: the trained ring (a 10-unit ring on 10-unit codes, 40,000 iterations of
the angles-1d schedule, seeds 0 and 1) must be seamless with circular order >= 0.95; the
synthetic tables of the seam tests are exact.
"""

from __future__ import annotations

import numpy as np
import pytest

import sigmapi
from sigmapi import ConfigError, SigmaPiSOM, evaluate, load_preset
from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.metrics.circular import CIRCULAR_KEYS, circular_means, ring_fit, seam, wrap
from sigmapi.rules.ordering import torus_angles
from sigmapi.tasks import TwoViewSampler


def test_sum_mod_views_cover_every_x_for_every_z():
    code = PopulationCode((15,), periodic=True)
    s = TwoViewSampler("sum_mod", code, code)
    z = np.full((4000, 1), 0.95)
    b = s.sample(4000, np.random.default_rng(0), z=z)
    for px, py in ((b.px0, b.py0), (b.px1, b.py1)):
        np.testing.assert_allclose(wrap(px + py - b.z), 0.0, atol=1e-12)
        assert px.min() >= 0 and px.max() < 1 and py.min() >= 0 and py.max() < 1
        # x uniform over the whole turn, whatever z: every tenth of it holds 10 % +- 2 %
        share = np.bincount((px[:, 0] * 10).astype(int), minlength=10) / px.shape[0]
        assert np.all(np.abs(share - 0.1) < 0.02)


def test_config_validates_map_periodic_and_angles():
    with pytest.raises(ConfigError, match="map_periodic"):
        SigmaPiSOM(map_periodic="yes")
    with pytest.raises(ConfigError, match="periodic = true"):
        SigmaPiSOM(relation="sum_mod")
    with pytest.raises(ConfigError, match=r"a ring, a torus.*set ordering='none'"):
        SigmaPiSOM(map_shape=(3, 3, 3), x_shape=(3, 3), y_shape=(3, 3), map_periodic=True)
    assert load_preset("paper-1d").map_periodic is False


def test_ring_model_saves_loads_and_continues_bit_for_bit(tmp_path):
    cfg = load_preset("angles-1d").replace(iterations=2000, seed=3)
    model = SigmaPiSOM(cfg).fit(iterations=1000)
    model.save(tmp_path / "ring.npz")
    back = sigmapi.load(tmp_path / "ring.npz")
    assert back.config.map_periodic and back.config.relation == "sum_mod"
    model.fit(iterations=2000)
    back.fit(iterations=2000)
    np.testing.assert_array_equal(model.weights_, back.weights_)


def test_circular_means_wrap_around():
    z = np.array([[0.95], [0.05], [0.2], [0.3]])
    mean, counts = circular_means(np.array([0, 0, 1, 1]), z, 3)
    np.testing.assert_allclose(wrap(mean[:2, 0] - [0.0, 0.25]), 0.0, atol=1e-12)
    np.testing.assert_array_equal(counts, [2, 2, 0])


def _ring_table(k: int, sign: float, offset: float) -> np.ndarray:
    return ((sign * np.arange(k) / k + offset) % 1.0)[:, None]


def test_ring_fit_recovers_sign_and_offset():
    coords = grid_coordinates((12,))
    z = _ring_table(12, -1.0, 0.3)
    fit = ring_fit(coords, z, (12,))
    assert fit.signs == [-1.0] and fit.axes == [0]
    np.testing.assert_allclose(wrap(fit.predict(coords) - z), 0.0, atol=1e-12)


def test_seam_of_an_ordered_ring_a_bounded_map_and_a_dead_unit():
    k = 12
    coords = grid_coordinates((k,))
    won, starved = np.ones(k, bool), np.zeros(k, bool)
    spacing = np.array([12.0])
    table = _ring_table(k, 1.0, 0.5 / k)
    fit = ring_fit(coords, table, (k,))
    ring = seam(table, won, starved, fit, coords, (k,), True, spacing)
    assert ring == {"seam_jump": pytest.approx(1.0), "seam_gap": 1.0, "seam_units_win": True,
                    "seamless": True}  # fmt: skip
    # the same table on a bounded map: the ends meet at the wrap, 11 units apart
    bounded = seam(table, won, starved, fit, coords, (k,), False, spacing)
    assert bounded["seam_gap"] == 11.0 and not bounded["seamless"]
    # the unit at the wrap never wins: units on one side of it are missing
    dead = starved.copy()
    dead[0] = True
    gone = seam(table, won, dead, fit, coords, (k,), True, spacing)
    assert not gone["seam_units_win"] and not gone["seamless"]


def test_bounded_maps_keep_their_metric_keys():
    model = SigmaPiSOM(map_shape=(6,), x_shape=(6,), y_shape=(6,), iterations=500, seed=0).fit()
    keys = set(evaluate(model, n_test=200).to_dict())
    assert not keys & set(CIRCULAR_KEYS) and "circular" not in keys
    assert keys >= {"view_consistency", "z_error", "order_r2", "folded"}


@pytest.mark.parametrize("ordering", ["crossview", "none"])
def test_a_small_ring_learns_angles_without_a_seam(ordering):
    for seed in (0, 1):
        cfg = load_preset("angles-1d").replace(
            map_shape=(10,), x_shape=(10,), y_shape=(10,), iterations=40_000, seed=seed,
            ordering=ordering,
        )  # fmt: skip
        m = evaluate(SigmaPiSOM(cfg).fit(), n_test=2000).to_dict()
        assert m["seamless"] and m["order_circular"] >= 0.95, (seed, m)


def test_transform_places_ring_units_round_the_turn():
    cfg = load_preset("angles-1d").replace(map_shape=(8,), x_shape=(8,), y_shape=(8,), seed=0)
    som = SigmaPiSOM(cfg, iterations=500).fit()
    b = som.sampler.sample(50, np.random.default_rng(0))
    np.testing.assert_allclose(som.transform(b.x0, b.y0)[:, 0], som.winner(b.x0, b.y0) / 8)
    som.set_params(map_periodic=False)  # a bounded map of 8 units: k / 7
    np.testing.assert_allclose(som.transform(b.x0, b.y0)[:, 0], som.winner(b.x0, b.y0) / 7)


def _turn_agreement(a: np.ndarray, b: np.ndarray) -> float:
    """|mean exp(2 pi i (a - b))| or the same for a + b, the larger: 1 when the angles ``a``
    and ``b`` (in turns) differ by a constant, either way round."""
    return max(abs(np.mean(np.exp(2j * np.pi * (a - s * b)))) for s in (1.0, -1.0))


def test_torus_angles_separate_two_mixed_angles():
    """Scores that are a random orthogonal mix of (cos, sin) of two angles, with noise: each
    angle found comes back as one of the two (agreement >= 0.98), the other not (<= 0.1)."""
    rng = np.random.default_rng(5)
    z = rng.uniform(size=(2000, 2))
    turns = 2 * np.pi * z
    base = np.column_stack([np.cos(turns[:, 0]), np.sin(turns[:, 0]),
                            np.cos(turns[:, 1]), np.sin(turns[:, 1])])  # fmt: skip
    mix, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    found = torus_angles(3.0 * base @ mix.T + rng.normal(scale=0.3, size=(2000, 4)))
    agree = np.array([[_turn_agreement(found[:, a], z[:, b]) for b in (0, 1)] for a in (0, 1)])
    assert sorted(agree.max(axis=1)) >= [0.98, 0.98] and agree.min(axis=1).max() <= 0.1, agree
    assert set(agree.argmax(axis=1)) == {0, 1}  # one found angle per true angle
    with pytest.raises(ValueError, match="2 or 4 scores"):
        torus_angles(base[:, :3])


def test_the_crossview_start_places_a_torus_once_round_both_ways():
    """The cross-view start on a 10x10 torus of two angles, before any learning to speak of
    (100 iterations): circular order >= 0.9 on seeds 0 and 1 (the random start scores below
    0.01 there); the same seed gives the same weights."""
    cfg = SigmaPiSOM(
        map_shape=(10, 10), x_shape=(10, 10), y_shape=(10, 10), periodic=True,
        map_periodic=True, relation="sum_mod", code_width=0.5, iterations=100,
        refine_rounds=0, kernel_tol=1e-4,
    ).config  # fmt: skip
    for seed in (0, 1):
        a = SigmaPiSOM(cfg.replace(seed=seed)).fit()
        m = evaluate(a, n_test=2000).to_dict()
        assert m["order_circular"] >= 0.9, (seed, m)
    b = SigmaPiSOM(cfg.replace(seed=1)).fit()
    np.testing.assert_array_equal(a.weights_, b.weights_)


@pytest.mark.slow
def test_the_angles_2d_preset_orders_a_seamless_torus():
    """The preset as shipped (about 12 s of CPU per seed), tuning seeds 0 and 1: seamless,
    circular order >= 0.98 and view consistency >= 0.70 (fresh seeds 720-739 measured
    0.987-0.988 and 0.709-0.730, docs/guide/ceiling.md)."""
    for seed in (0, 1):
        m = evaluate(SigmaPiSOM(load_preset("angles-2d").replace(seed=seed)).fit()).to_dict()
        assert m["seamless"] and m["order_circular"] >= 0.98, (seed, m)
        assert m["view_consistency"] >= 0.70, (seed, m)
