"""Figures of the reach comparison: learning curves and the learned value over z.

Every function takes ``ax=None`` (a new figure when None) and returns the Axes, except
:func:`reach_figure`, which lays out the whole comparison and returns the Figure. Nothing is
shown and pyplot is never touched: figures are plain :class:`matplotlib.figure.Figure`
objects that draw on the Agg canvas when saved with ``fig.savefig(path)``.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from sigmapi.experiments.reach_config import ReachConfig

__all__ = ["LABELS", "ReachData", "plot_reach_curves", "plot_value_function", "reach_figure"]


class ReachData(Protocol):
    """What the figures read of a :class:`~sigmapi.experiments.reach_result.ReachResult`."""

    config: ReachConfig
    seeds: tuple[int, ...]
    values: dict[str, NDArray[np.float64]]
    z_axis: NDArray[np.float64]

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]: ...


LABELS = {
    "map": "Sigma-Pi map (learned)",
    "retina": "retina only",
    "retina_gaze": "retina + gaze (side by side)",
    "true_z": "true z (upper bound)",
}
COLORS = {"map": "C0", "retina": "C3", "retina_gaze": "C1", "true_z": "k"}


def _ax(ax: Axes | None) -> Axes:
    if ax is None:
        ax = Figure(figsize=(5, 3.5), layout="constrained").subplots()
    return ax


def plot_reach_curves(result: ReachData, metric: str = "success", ax: Axes | None = None) -> Axes:
    """Learning curves per state: ``metric`` "success" (rate per block, band = 1 sd over
    seeds) or "steps" (mean steps of the successful episodes per block)."""
    if metric not in ("success", "steps"):
        raise ValueError(f"metric must be 'success' or 'steps', got {metric!r}")
    ax = _ax(ax)
    for state, c in result.curves().items():
        ep = c["episode"]
        if metric == "success":
            ax.plot(ep, c["success"], color=COLORS.get(state), label=LABELS.get(state, state))
            ax.fill_between(ep, c["success"] - c["success_sd"], c["success"] + c["success_sd"],
                            color=COLORS.get(state), alpha=0.15, linewidth=0)  # fmt: skip
        else:
            ax.plot(
                ep, c["steps_to_reach"], color=COLORS.get(state), label=LABELS.get(state, state)
            )
    ax.set_xlabel(f"episode (blocks of {result.config.run.block})")
    if metric == "success":
        ax.set_ylabel("success rate")
        ax.set_ylim(0.0, 1.02)
        ax.set_title(f"reaching success, mean of {len(result.seeds)} seeds")
    else:
        ax.set_ylabel("steps to reach (successes)")
        ax.set_title("steps to reach the goal")
    ax.grid(alpha=0.3)
    return ax


def plot_value_function(
    result: ReachData, state: str, ax: Axes | None = None, **kwargs: Any
) -> Axes:
    """The critic's value over body-centred z (seed 0) for ``state``, with the goal region.

    2-D: an image over (z0, z1); 1-D: a curve. Extra ``kwargs`` go to ``imshow`` / ``plot``.
    """
    if state not in result.values:
        raise ValueError(f"no value function for state {state!r}; have {sorted(result.values)}")
    ax = _ax(ax)
    v, z = result.values[state], result.z_axis
    radius = result.config.env.goal_radius
    lo, hi = 0.5 - radius, 0.5 + radius
    if v.ndim == 2:
        im = ax.imshow(
            v.T, origin="lower", extent=(0, 1, 0, 1), cmap=kwargs.pop("cmap", "viridis"), **kwargs
        )
        ax.plot([lo, hi, hi, lo, lo], [lo, lo, hi, hi, lo], color="w", lw=1.2)
        ax.set_xlabel("z0")
        ax.set_ylabel("z1")
        ax.figure.colorbar(im, ax=ax, fraction=0.046, pad=0.04)
    else:
        ax.plot(z, v, color=COLORS.get(state), **kwargs)
        ax.axvspan(lo, hi, color="0.85", zorder=0)
        ax.set_xlabel("z")
        ax.set_ylabel("V(z)")
    ax.set_title(f"V over z: {LABELS.get(state, state)}", fontsize=9)
    return ax


def reach_figure(result: ReachData) -> Figure:
    """The comparison on one page: success and steps curves, then the value over z per state."""
    states = list(result.values)
    n = max(len(states), 2)
    fig = Figure(figsize=(3.2 * n, 7.0), layout="constrained")
    grid = fig.add_gridspec(2, n)
    half = n // 2
    ax0 = fig.add_subplot(grid[0, :half])
    ax1 = fig.add_subplot(grid[0, half:])
    plot_reach_curves(result, "success", ax0)
    plot_reach_curves(result, "steps", ax1)
    ax0.legend(fontsize=8, loc="lower right")
    values = [np.asarray(result.values[s]) for s in states]
    shared: dict[
        str, float
    ] = {}  # one colour scale for every state's value map, so that they compare
    if values and values[0].ndim == 2:
        shared = {"vmin": min(float(v.min()) for v in values),
                  "vmax": max(float(v.max()) for v in values)}  # fmt: skip
    for i, s in enumerate(states):
        plot_value_function(result, s, fig.add_subplot(grid[1, i]), **shared)
    env, agent = result.config.env, result.config.agent
    fig.suptitle(
        f"Gaze-and-reach, {env.dim}-D, saccade rate {env.saccade_rate:g}: actor-critic "
        f"(gamma {agent.gamma:g}, rates {agent.critic_lr:g}/{agent.actor_lr:g}, "
        f"beta {agent.beta:g}); "
        "bottom: critic's value over z after training (seed 0; white: goal region)",
        fontsize=10,
    )
    return fig
