"""Figures: every figure renders headless on tiny 1-D and 2-D models (data: test_analysis.py)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from sigmapi.analysis import map_data as analysis
from sigmapi.viz import plots
from sigmapi.viz.figures import FIGURES, draw_figure

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


# ---------------------------------------------------------------------------- issue 15


def test_weight_tiles_use_a_sequential_map_for_non_negative_weights(model_1d):
    tiles = analysis.weight_tiles(model_1d)
    ax = plots.plot_weight_tiles(np.abs(tiles), model_1d.map_shape)
    img = ax.images[0]
    assert img.get_cmap().name.startswith(plots.WEIGHT_CMAP_POSITIVE) and img.get_clim()[0] == 0
    signed = tiles - tiles.mean()
    img = plots.plot_weight_tiles(signed, model_1d.map_shape).images[0]
    lo, hi = img.get_clim()
    assert img.get_cmap().name.startswith(plots.WEIGHT_CMAP) and lo == -hi


def test_iteration_ticks_are_short_and_never_run_together(curves):
    assert [plots._count_label(v) for v in (500, 2000, 100_000, 200_000, 1e6)] == [
        "500", "2k", "100k", "200k", "1M",
    ]  # fmt: skip
    ax = plots.plot_learning_curves(curves)
    ax.figure.canvas.draw()
    for pa in ax.figure.axes:
        if pa.get_xscale() == "log":
            labels = [t.get_text() for t in pa.get_xticklabels() if t.get_text()]
            assert labels and all("," not in t and len(t) <= 5 for t in labels), labels


def test_captions_say_twisted_when_the_data_do():
    from sigmapi import SOMConfig
    from sigmapi.viz.figures import RunInfo, caption

    run = RunInfo("quick-2d", SOMConfig(map_shape=(5, 5), x_shape=(5, 5), y_shape=(5, 5)), (0,), 0)
    fig8 = {"z": [0.5, 0.5], "polarity": "mirrored left-right", "polarity_r2": 0.41,
            "invariance_spread": 1.3}  # fmt: skip
    text = caption("fig8", run, fig8)
    assert "twisted" in text and "reappears" not in text and "responses differ" in text
    text = caption("fig8", run, {**fig8, "polarity_r2": 0.99, "invariance_spread": 0.1})
    assert "reappears on the map, mirrored left-right" in text and "responses agree" in text
    net = caption("net", run, {"polarity": "same orientation", "order_r2_centres": 0.5})
    assert "twisted" in net and "same orientation" not in net
    curves = {"checkpoints": 5, "final": {}, "reference_lines": []}
    assert "Dashed" not in caption("curves", run, curves)
    assert "Dashed lines" in caption("curves", run, {**curves, "reference_lines": ["z_error"]})


def test_one_seed_shows_no_spread():
    from sigmapi.experiments.reproduce.report_html import _mean_sd

    assert _mean_sd(0.5, 0.0, 1) == "0.500 (one seed)"
    assert _mean_sd(0.5, 0.01, 3) == "0.500 ± 0.010"


def test_reach_value_maps_share_one_colour_scale():
    from sigmapi.experiments.reach.config import ReachConfig
    from sigmapi.experiments.reach.figures import reach_figure
    from sigmapi.experiments.reach.run import REACH

    cfg = ReachConfig().replace(dim=2, grid=5, map_shape=(3, 3), iterations=300, episodes=4,
                                block=2, final_episodes=2, max_episode_steps=10,
                                backend="reference")  # fmt: skip
    res = REACH.run(cfg, seeds=[0])
    clims = {ax.images[0].get_clim() for ax in reach_figure(res).axes if ax.images}
    assert len(clims) == 1


def test_figure_dpi_on_request(model_1d, tmp_path: Path):
    import matplotlib.image as mpimg

    draw_figure("net", model_1d, tmp_path / "a.png")
    draw_figure("net", model_1d, tmp_path / "b.png", dpi=300)
    small = mpimg.imread(tmp_path / "a.png")
    big = mpimg.imread(tmp_path / "b.png")
    assert big.shape[1] > 2.5 * small.shape[1]


def test_compare_figure_log_axes_read_plain_numbers():
    import re

    from sigmapi.experiments.compare.figures import compare_figure

    labels = [10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000]
    methods = [
        {"name": name, "view_consistency": 0.5, "unit_consistency": 0.4,
         "z_error_by_labels": {str(n): 0.55 + k / np.sqrt(n) for n in labels}}
        for name, k in (("sigma-pi", 4.0), ("kohonen", 2.0))
    ]  # fmt: skip
    result = {"methods": methods, "quantisation_floor": 0.45,
              "config": {"labels": labels, "seeds": [0, 1]}}  # fmt: skip
    ax = compare_figure(result).axes[0]
    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        shown = [axis.get_major_formatter()(v) for v in axis.get_majorticklocs() if lo <= v <= hi]
        assert len(shown) >= 3, shown  # the z error spans less than a decade: still 3 ticks
        assert all(re.fullmatch(r"\d+(\.\d+)?", t) for t in shown), shown  # not 6x10^-1
        assert axis.get_minor_formatter()(3.0) == ""
    assert "1000" in [ax.xaxis.get_major_formatter()(v) for v in ax.xaxis.get_majorticklocs()]
