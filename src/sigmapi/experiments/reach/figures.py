"""Figures of the reach comparison: learning curves and the learned value over z. Each plot
function takes ``ax=None`` (a new figure) and returns the Axes; :func:`reach_figure` lays out
the comparison and returns the Figure (pyplot untouched: plain Figures, drawn when saved).
"""

from __future__ import annotations

import textwrap
from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from sigmapi.experiments.kit.episodes_result import plot_with_bands, sd_band
from sigmapi.experiments.kit.figures import axes, coinciding, legend_once
from sigmapi.experiments.reach.config import ReachConfig


class ReachData(Protocol):
    """What the figures read of a :class:`~sigmapi.experiments.reach.result.ReachResult`."""

    config: ReachConfig
    seeds: tuple[int, ...]
    values: dict[str, NDArray[np.float64]]
    z_axis: NDArray[np.float64]

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]: ...

    def final_rise(self) -> dict[str, float]: ...

    def still_rising(self) -> list[str]: ...

    def levelling_note(self) -> str: ...


LABELS = {
    "map": "Sigma-Pi map (learned)",
    "retina": "retina only",
    "retina_gaze": "retina + gaze (side by side)",
    "true_z": "true z (upper bound)",
}
COLORS = {"map": "C0", "retina": "C3", "retina_gaze": "C1", "true_z": "k"}
CURVES = {
    "success": ("success", sd_band, "band: 1 sd over seeds"),
    "steps": (
        "steps_to_reach",
        lambda c: (c["steps_q25"], c["steps_q75"]),
        "band: quartiles over seeds",
    ),
}
"""Per metric of :func:`plot_reach_curves`: the curve's key, its band and the band's label."""


def coinciding_curves(result: ReachData) -> dict[str, dict[str, str]]:
    """Per metric ("success", "steps"), the states whose curve equals an earlier state's at
    every block (:func:`~sigmapi.experiments.kit.figures.coinciding`): what the caption says
    of them."""
    curves = result.curves()
    return {
        metric: coinciding({s: [*c["episode"], *c[key]] for s, c in curves.items()})
        for metric, (key, _, _) in CURVES.items()
    }


def plot_reach_curves(result: ReachData, metric: str = "success", ax: Axes | None = None) -> Axes:
    """Learning curves per state, with a legend: ``metric`` "success" (rate per block, mean
    over seeds, band = 1 sd over seeds; a learner that had not levelled off at the last
    episode, :meth:`~sigmapi.experiments.reach.result.ReachResult.still_rising`, is marked
    so in the legend) or "steps" (mean steps of the successful episodes per block, band =
    the quartiles over seeds)."""
    if metric not in CURVES:
        raise ValueError(f"metric must be 'success' or 'steps', got {metric!r}")
    ax = axes(ax)
    key, band, what = CURVES[metric]
    curves = result.curves()
    labels = dict(LABELS)
    if metric == "success":
        rise = result.final_rise()
        for s in result.still_rising():
            labels[s] = f"{LABELS.get(s, s)} (still rising: {rise[s]:+.2f})"
    # series that coincide (e.g. two states at success 1) each show; the caption says which
    # (ReachResult.caption, from coinciding_curves)
    plot_with_bands(
        ax, curves, key, band, what, labels=labels, colours=COLORS, largest=8.0, say=False
    )
    n, run = len(result.seeds), result.config.run
    ax.set_xlabel(f"episode (blocks of {run.block})")
    if metric == "success":
        ax.set_ylabel("success rate")
        ax.set_ylim(0.0, 1.02)
        ax.set_title(f"reaching success, mean of {n} seed{'s' * (n > 1)} (band: 1 sd)", fontsize=9)
    else:
        ax.set_ylabel("steps to reach (successes)")
        ax.set_title(f"steps to reach, mean of {n} seed{'s' * (n > 1)} (band: IQR)", fontsize=9)
    ax.grid(alpha=0.3)
    # the bands share one entry
    legend_once(ax, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)
    return ax


def plot_value_function(
    result: ReachData, state: str, ax: Axes | None = None, **kwargs: Any
) -> Axes:
    """The critic's value over body-centred z (the first seed) for ``state``, with the goal
    region; its colour bar (2-D) or y axis (1-D) is labelled.

    2-D: an image over (z0, z1); 1-D: a curve. Extra ``kwargs`` go to ``imshow`` / ``plot``.
    """
    if state not in result.values:
        raise ValueError(f"no value function for state {state!r}; have {sorted(result.values)}")
    ax = axes(ax)
    v, z = result.values[state], result.z_axis
    radius = result.config.env.goal_radius
    lo, hi = 0.5 - radius, 0.5 + radius
    if v.ndim == 2:
        im = ax.imshow(
            v.T, origin="lower", extent=(0, 1, 0, 1), cmap=kwargs.pop("cmap", "viridis"), **kwargs
        )
        ax.plot([lo, hi, hi, lo, lo], [lo, lo, hi, hi, lo], color="w", lw=1.2, label="goal region")
        ax.set_xlabel("z0")
        ax.set_ylabel("z1")
        bar = ax.figure.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
        bar.set_label("V(z): expected discounted reward", fontsize=8)
    else:
        ax.plot(z, v, color=COLORS.get(state), label="the critic's value over z", **kwargs)
        ax.axvspan(lo, hi, color="0.85", zorder=0, label="goal region")
        ax.set_xlabel("z")
        ax.set_ylabel("V(z): expected discounted reward")
    ax.set_title(f"V over z: {LABELS.get(state, state)}", fontsize=9)
    return ax


def reach_figure(result: ReachData) -> Figure:
    """The comparison on one page: success and steps curves, then the value over z per state."""
    states = list(result.values)
    n = max(len(states), 2)
    width = max(3.2 * n, 9.6)
    fig = Figure(figsize=(width, 8.0), layout="constrained")
    grid = fig.add_gridspec(2, n)
    half = n // 2
    plot_reach_curves(result, "success", fig.add_subplot(grid[0, :half]))
    plot_reach_curves(result, "steps", fig.add_subplot(grid[0, half:]))
    values = [np.asarray(result.values[s]) for s in states]
    # one colour scale for every state's value map, so that they compare
    shared: dict[str, float] = {}
    if values and values[0].ndim == 2:
        shared = {
            "vmin": min(float(v.min()) for v in values),
            "vmax": max(float(v.max()) for v in values),
        }
    for i, s in enumerate(states):
        plot_value_function(result, s, fig.add_subplot(grid[1, i]), **shared)
    env, agent = result.config.env, result.config.agent
    title = (
        f"Gaze-and-reach, {env.dim}-D, saccade rate {env.saccade_rate:g}: actor-critic "
        f"(gamma {agent.gamma:g}, rates {agent.critic_lr:g}/{agent.actor_lr:g}, "
        f"beta {agent.beta:g}); "
        f"bottom: critic's value over z after training (seed {result.seeds[0]}; "
        f"{'white square' if env.dim == 2 else 'grey band'}: goal region)",
        result.levelling_note(),
    )
    chars = int(width * 13)  # about as many characters of 10-point text fit an inch
    fig.suptitle("\n".join(textwrap.fill(t, chars) for t in title), fontsize=10)
    return fig
