"""Figures of the reward comparison: success over episodes per method, and where each map's
units lie in z (the magnification near the goal). Each plot function takes ``ax=None`` (a new
figure) and returns the Axes; :func:`reward_figure` lays out the comparison and returns the
Figure (pyplot untouched).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle
from numpy.typing import NDArray

from sigmapi.experiments.kit.episodes_result import plot_with_bands
from sigmapi.experiments.kit.figures import axes, legend_once
from sigmapi.experiments.kit.worlds import GAZE_REACH
from sigmapi.experiments.reward.config import RewardConfig


class RewardData(Protocol):
    """What the figures read of a :class:`~sigmapi.experiments.reward.result.RewardResult`."""

    config: RewardConfig
    seeds: tuple[int, ...]
    units: dict[str, NDArray[np.float64]]
    scores: dict[str, dict[str, NDArray[np.float64]]]

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]: ...


LABELS = {
    "frozen": "frozen map",
    "gated": "reward-gated map",
    "shuffled": "shuffled reward",
    "initial": "learned map (before)",
}
COLORS = {"frozen": "C0", "gated": "C2", "shuffled": "C3", "initial": "C0"}


def plot_reward_curves(result: RewardData, ax: Axes | None = None) -> Axes:
    """Success rate per block, mean over seeds (line), band from the worst to the best seed."""
    ax = axes(ax)
    plot_with_bands(  # curves that coincide each show, and their labels say so
        ax,
        result.curves(),
        "success",
        lambda c: (c["success_min"], c["success_max"]),
        "band: min-max over seeds",
        labels=LABELS,
        colours=COLORS,
        largest=7.0,
    )
    target = result.config.run.target
    ax.axhline(target, color="0.5", linestyle=":", linewidth=1, label=f"target {target:.0%}")
    ax.set_xlabel(f"episode (blocks of {result.config.run.block})")
    ax.set_ylabel("success rate")
    ax.set_ylim(0.0, 1.02)
    ax.set_title(f"reaching success, mean of {len(result.seeds)} seeds (band: min-max)")
    # the bands share one entry
    legend_once(ax, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def plot_units(result: RewardData, method: str, ax: Axes | None = None) -> Axes:
    """The first seed's units at their preferred z, neighbours on the map joined, with the goal
    box (grey) and the region "near the goal" (dashed) whose units the magnification counts."""
    ax = axes(ax)
    cfg = result.config
    pz = result.units[method]
    grid = pz.reshape(*cfg.map.map_shape, -1)  # 2-D: the units are drawn for the 2-D task
    for line in (*grid.transpose(1, 0, 2), *grid):
        ax.plot(line[:, 0], line[:, 1], color="0.6", linewidth=0.6, label="map neighbours, joined")
    ax.plot(*pz.T, "o", color=COLORS.get(method), markersize=3, label="a unit at its preferred z")
    goal = np.asarray(GAZE_REACH.source(cfg.env).goal)
    r, rn = cfg.env.goal_radius, cfg.run.near_radius
    ax.add_patch(Rectangle(tuple(goal - r), 2 * r, 2 * r, color="0.85", zorder=0, label="the goal"))
    near_box = Rectangle(tuple(goal - rn), 2 * rn, 2 * rn, fill=False, linestyle="--")
    near_box.set(edgecolor="k", linewidth=0.8, label="the region near the goal")
    ax.add_patch(near_box)
    mag = result.scores[method]["magnification"]
    near = result.scores[method]["units_near"]
    ax.set_title(
        f"{LABELS.get(method, method)}: {int(near[0])} units near, x{mag[0]:.2f}", fontsize=9
    )
    ax.set(xlim=(0, 1), ylim=(0, 1), aspect="equal", xlabel="z[0]", ylabel="z[1]")
    return ax


def drawn_units(result: RewardData) -> list[str]:
    """The methods whose units in z the figure draws (the 2-D task only)."""
    if result.config.env.dim != 2:
        return []
    return [m for m in ("frozen", "gated", "shuffled") if m in result.units]


def reward_figure(result: RewardData) -> Figure:
    """Curves on the left, each method's units in z on the right (first seed)."""
    methods = drawn_units(result)
    fig = Figure(figsize=(4.2 + 3.0 * len(methods), 3.6), layout="constrained")
    axes = fig.subplots(1, 1 + len(methods), width_ratios=[1.5] + [1.0] * len(methods))
    axes = np.atleast_1d(axes)
    plot_reward_curves(result, axes[0])
    for ax, m in zip(axes[1:], methods, strict=True):
        plot_units(result, m, ax)
    fig.suptitle(
        f"seed {result.seeds[0]} maps: magnification = units per area near the goal "
        "over units per area overall",
        fontsize=9,
    )
    return fig
