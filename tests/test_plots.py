"""Figures: every figure renders headless on tiny 1-D and 2-D models; the analysis behind them."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from sigmapi import SigmaPiSOM, analysis, plots
from sigmapi.curves import LearningCurve, checkpoints, costs
from sigmapi.figures import FIGURES, draw_figure

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def model_1d() -> SigmaPiSOM:
    return SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0).fit()


@pytest.fixture(scope="module")
def model_2d() -> SigmaPiSOM:
    return SigmaPiSOM(
        map_shape=(3, 4), x_shape=(4, 4), y_shape=(4, 4), code_width=1.0, iterations=1000, seed=0
    ).fit()


@pytest.fixture(scope="module")
def curves(model_1d: SigmaPiSOM) -> list[dict[str, list[float]]]:
    som = SigmaPiSOM(model_1d.config)
    curve = LearningCurve(at=checkpoints(2000, 5), n_test=100)
    som.fit(callback=curve)
    return [curve.to_dict()]


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _labelled(ax) -> None:
    """The Axes (or, for a multi-panel figure, its panels) carry a title and axis labels."""
    assert ax.get_title().strip(), "figure has no title"
    panels = ax.child_axes or [ax]
    assert any(p.get_xlabel().strip() for p in panels), "no x axis label"
    assert any(p.get_ylabel().strip() for p in panels), "no y axis label"


@pytest.mark.parametrize("name", FIGURES)
@pytest.mark.parametrize("dims", ["1d", "2d"])
def test_every_figure_renders_to_png(name, dims, model_1d, model_2d, curves, tmp_path: Path):
    model = model_1d if dims == "1d" else model_2d
    path = tmp_path / f"{name}-{dims}.png"
    facts = draw_figure(name, model, path, curves=curves, label="tiny", reference={"z_error": 0.3})
    data = path.read_bytes()
    assert data.startswith(PNG) and len(data) > 5000
    assert isinstance(facts, dict)


def test_plot_functions_take_ax_none_and_return_labelled_axes(model_1d, model_2d, curves):
    for model in (model_1d, model_2d):
        centres = analysis.receptive_field_centres(model)
        d8 = analysis.fig8_data(model, seed=1, centres=centres)
        axes = [
            plots.plot_fig8(d8),
            plots.plot_weight_tiles(analysis.weight_tiles(model), model.map_shape),
            plots.plot_net(centres, model.map_shape),
            plots.plot_invariance(analysis.invariance_matrix(model, centres=centres)),
            plots.plot_learning_curves(curves),
        ]
        for ax in axes:
            assert isinstance(ax, matplotlib.axes.Axes)
            _labelled(ax)


def test_plot_draws_into_a_given_axes(model_1d):
    fig, ax = plt.subplots()
    inv = analysis.invariance_matrix(model_1d)
    assert plots.plot_invariance(inv, ax=ax) is ax
    assert len(fig.axes) == 2  # the Axes and its colour bar


def test_colour_bars_where_colour_carries_a_value(model_2d):
    fig, ax = plt.subplots()
    plots.plot_weight_tiles(analysis.weight_tiles(model_2d), model_2d.map_shape, ax=ax)
    assert any(_is_colorbar(a) for a in fig.axes)
    ax8 = plots.plot_fig8(analysis.fig8_data(model_2d))
    assert sum(_is_colorbar(a) for a in ax8.child_axes) == 1


def _is_colorbar(ax) -> bool:
    return getattr(ax, "_colorbar", None) is not None


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
