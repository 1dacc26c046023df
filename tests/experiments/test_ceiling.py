"""The rule's ceiling (sigmapi.analysis.fixed_point): the quadrature grid and the fixed point of
Eq. 7."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.analysis import fixed_point as ceiling
from sigmapi.errors import ConfigError
from sigmapi.tasks import Relation


@pytest.fixture(scope="module")
def model() -> SigmaPiSOM:
    return SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0).fit()


@pytest.mark.parametrize("relation", ["mean", "difference"])
def test_grid_views_follow_the_samplers_law_given_z(relation):
    som = SigmaPiSOM(map_shape=(4,), x_shape=(6,), y_shape=(6,), relation=relation, seed=0)
    grid = ceiling.view_grid(som, z_points=9, view_points=400)
    rel = som.sampler.relation
    assert np.allclose(grid.weight.sum(axis=1), 1.0) and np.isclose(grid.z_weight.sum(), 1.0)
    assert np.allclose(rel.forward(grid.px, grid.py), grid.z[:, None, :])  # views of their z
    # the moments of x given z match the sampler's rejection draws
    rng = np.random.default_rng(1)
    for i in (0, 4, 8):
        z = np.repeat(grid.z[i][None, :], 40_000, axis=0)
        px, _ = som.sampler.sample_view(z, rng)
        for power in (1, 2):
            quad = float(np.sum(grid.weight[i] * grid.px[i, :, 0] ** power))
            assert quad == pytest.approx(float(np.mean(px**power)), abs=0.01), (i, power)


def test_a_2d_grid_combines_the_axes():
    som = SigmaPiSOM(map_shape=(2, 2), x_shape=(3, 3), y_shape=(3, 3), seed=0)
    grid = ceiling.view_grid(som, z_points=4, view_points=3)
    assert grid.z.shape == (16, 2) and grid.px.shape == (16, 9, 2)
    assert np.allclose(grid.weight, 1.0 / 9)


def test_the_fixed_point_satisfies_eq7_on_its_grid(model):
    found = ceiling.fixed_point(model, z_points=60, view_points=12, tol=0.0, max_rounds=30,
                                n_test=500)  # fmt: skip
    assert found.rounds == len(found.changed) >= 1 and found.converged
    assert found.changed[-1] == 0.0 and 0.0 < found.metrics.view_consistency <= 1.0
    assert found.to_dict()["z_points"] == 60 and "model" not in found.to_dict()
    fp = found.model
    assert fp is not None
    grid = ceiling.view_grid(model, 60, 12)
    w = np.array(fp.weights_)
    again = ceiling._means(fp, grid, ceiling._winners(fp, grid), w)  # Eq. 7 of its own winners
    assert np.allclose(again, w, rtol=0, atol=1e-6)  # a backend may store float32


def test_keeping_the_moments_between_rounds_changes_nothing(model, monkeypatch):
    kept = ceiling.fixed_point(model, z_points=40, view_points=8, tol=0.0, max_rounds=4,
                               n_test=300)  # fmt: skip
    monkeypatch.setattr(ceiling, "MOMENTS_BYTES", 0)  # computed again every round
    again = ceiling.fixed_point(model, z_points=40, view_points=8, tol=0.0, max_rounds=4,
                                n_test=300)  # fmt: skip
    assert kept.rounds == again.rounds >= 2 and kept.changed == again.changed
    assert kept.model is not None and again.model is not None
    assert np.array_equal(kept.model.weights_, again.model.weights_)  # bit for bit


def test_the_fixed_point_removes_weight_noise(model):
    noisy = SigmaPiSOM.from_arrays(
        {**model.to_arrays()[0], "backend": "reference"},
        {"weights": np.clip(np.array(model.weights_) + 0.02 *
                            np.random.default_rng(0).standard_normal(model.weights_.shape),
                            0, None)},
    )  # fmt: skip
    from sigmapi import evaluate

    before = evaluate(noisy, n_test=2000).view_consistency
    after = ceiling.fixed_point(noisy, n_test=2000).metrics.view_consistency
    assert after > before  # the means remove the noise the weights carry


def test_bad_grids_and_relations_without_bounds_are_refused(model):
    with pytest.raises(ConfigError, match="z_points must be >= 2"):
        ceiling.fixed_point(model, z_points=1)
    rel = Relation("shift", lambda x, y: x - y + 0.5, lambda z, x: x + 0.5 - z,
                   lambda z, y: z + y - 0.5, (0.0, 1.0))  # fmt: skip
    custom = SimpleNamespace(sampler=SimpleNamespace(relation=rel, ndim=1))  # a custom sampler
    with pytest.raises(ConfigError, match="has no x_bounds / y_bounds"):
        ceiling.view_grid(custom, 4, 2)  # type: ignore[arg-type]
