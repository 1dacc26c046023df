"""Figures of the robot experiment: the map on the table, learning curves, a film strip. Plot
functions (``ax`` in, Axes out), :func:`robot_figures`, which writes them for a
:class:`~sigmapi.experiments.robot.result.RobotResult` with their captions (``NAME.txt``), and
:func:`film_episode`, one docking episode of the first seed's map learner.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes

from sigmapi._outputs import save_captioned
from sigmapi.agents import reset_from
from sigmapi.envs.robot.frames import Frames
from sigmapi.envs.robot.scene import Scene
from sigmapi.experiments.kit.episodes_result import plot_with_bands, sd_band
from sigmapi.experiments.kit.figures import coincide_sentence, coinciding, film_strip, legend_once
from sigmapi.experiments.kit.results import JSON
from sigmapi.experiments.robot.config import PLAN
from sigmapi.metrics import FOLD_THRESHOLD, ORDERED_R2

_TABLE = (0.15, 1.45, -1.1, 1.1)  # near edge, far edge, right, left (world x, y; robot.xml)


def plot_unit_positions(
    unit_z: NDArray[np.float64], map_shape: tuple[int, ...], ax: Axes | None = None
) -> Axes:
    """Top view of the table with each map unit's preferred ball position (the mean place of
    the calibration balls it wins), joined along the map's rows and columns; the robot at the
    origin facing +x; legend beside the Axes."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(7, 5)).add_subplot()
    frames = Frames(Scene())
    x0, x1, y0, y1 = _TABLE
    ax.add_patch(plt.Rectangle((y0, x0), y1 - y0, x1 - x0, color=(0.85, 0.75, 0.6), label="table"))
    ax.add_patch(plt.Circle((0.0, 0.0), 0.13, color="0.5", label="robot (torso)"))
    ok = np.all(np.isfinite(unit_z), axis=1)
    p = np.full((len(unit_z), 3), np.nan)
    p[ok] = frames.torso_position(unit_z[ok])
    grid = p.reshape(*map_shape, 3)
    for i, line in enumerate((*grid, *grid.transpose(1, 0, 2))):
        label = "the map's rows and columns" if i == 0 else "_rows"
        ax.plot(-line[:, 1], line[:, 0], color="tab:blue", lw=0.8, label=label)
    ax.plot(-p[:, 1], p[:, 0], "o", color="tab:red", ms=3, label="a unit's ball position")
    ax.set(xlim=(-1.0, 1.0), ylim=(-0.2, 1.45), aspect="equal")
    ax.set(xlabel="right of the robot (m)", ylabel="ahead of the robot (m)")
    ax.set_title("each unit's preferred ball position")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return ax


def plot_curves(curves: Mapping[str, Mapping[str, Any]], ax: Axes | None = None) -> Axes:
    """Success per block of episodes, mean over seeds with one standard deviation shaded; one
    marker per state (curves that coincide each show, their legend entries say so)."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(8, 4)).add_subplot()
    plot_with_bands(ax, curves, "success", sd_band, "band: 1 sd over seeds", alpha=0.2, largest=8.0)
    ax.set(xlabel="episode", ylabel="success (docked and touched)", ylim=(-0.02, 1.02))
    legend_once(ax, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return ax


def film_episode(result: Any, max_frames: int = 60) -> list[NDArray[np.uint8]]:
    """Frames (``env.render()``: third-person and head cameras) of one episode of the first
    seed's map learner of ``result``, acting on its policy after training; empty without one."""
    if result.model is None or result.agent is None:
        return []
    env = result.config.state_env("map", result.model, render_mode="rgb_array")
    phi, _ = reset_from(env, PLAN.rng(result.seeds[0], "film"))
    frames = [env.render()]
    for _ in range(max_frames - 1):
        phi, _, terminated, truncated, _ = env.step(result.agent.act(phi))
        frames.append(env.render())
        if terminated or truncated:
            break
    env.close()
    return frames


def _map_words(metrics: JSON) -> str:
    """A map's order and fold verdicts, with their bounds (the fold score's threshold)."""
    r2 = float(metrics["order_r2"])
    order = "ordered" if r2 >= ORDERED_R2 else "twisted"
    fold = "flagged folded" if metrics["folded"] else "not flagged folded"
    score = metrics.get("fold_score")
    said = "" if score is None else f": fold score {float(score):.2f}"
    return (
        f"order R^2 {r2:.3f}, {order} (ordered at >= {ORDERED_R2:g}); {fold} by the fold "
        f"detector{said} (flagged at >= {FOLD_THRESHOLD:g})"
    )


def robot_figures(
    result: Any, out_dir: Path, film: list[NDArray[np.uint8]] | None = None
) -> list[Path]:
    """Write ``map-on-table.png``, ``learning-curves.png`` and (with ``film``) ``film.png``,
    each with its caption ``NAME.txt``."""
    import matplotlib.pyplot as plt

    paths: list[Path] = []
    seeds = ("seed " if len(result.seeds) == 1 else "seeds ") + ", ".join(map(str, result.seeds))

    def save(fig: Any, name: str, caption: str, dpi: int = 120) -> None:
        paths.append(save_captioned(fig, out_dir / name, caption, dpi=dpi, bbox_inches="tight"))
        plt.close(fig)

    if result.unit_z:
        rows, cols = result.config.map.map_shape
        ax = plot_unit_positions(result.unit_z[0], result.config.map.map_shape)
        words = _map_words(result.map_metrics[0]) if result.map_metrics else ""
        save(
            ax.figure,
            "map-on-table.png",
            f"Seed {result.seeds[0]}, top view: the map's {rows}x{cols} units, each drawn (red "
            "dot) at its preferred ball position (the mean place of the calibration balls it "
            "wins) and joined (blue) along the map's rows and columns"
            + (f"; {words}" if words else "")
            + ". Tan: the table; grey disc: the robot, facing up.",
        )
    curves = result.success_curves()
    final = result.final()
    save(
        plot_curves(curves).figure,
        "learning-curves.png",
        f"Success (docked and touched) per block of {result.config.run.block} episodes, mean "
        f"over {seeds} (band: 1 sd over seeds), one line per state the learner reads; final "
        f"success over the last {result.config.run.final_episodes} episodes: "
        + ", ".join(f"{s} {float(np.mean(v)):.2f}" for s, v in final.items())
        + ". "
        + coincide_sentence(
            coinciding({s: c["success"] for s, c in curves.items()}), "at every block"
        ),
    )
    if film:
        fig, pick = film_strip(film, "step {i}", across=False)
        save(
            fig,
            "film.png",
            f"Seed {result.seeds[0]}: {len(pick)} of the {len(film)} frames of one docking "
            "episode of the map learner after training (third-person and head cameras).",
            dpi=90,
        )
    return paths
