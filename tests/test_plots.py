"""Figures: every figure renders headless on tiny 1-D and 2-D models (data: test_analysis.py)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest

from sigmapi import analysis, plots
from sigmapi.figures import FIGURES, draw_figure

PNG = b"\x89PNG\r\n\x1a\n"


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
