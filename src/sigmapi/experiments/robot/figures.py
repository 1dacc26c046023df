"""Figures of the robot experiment: the map on the table, learning curves, a film strip.

Thin plot functions (``ax`` in, Axes out) and :func:`robot_figures`, which writes them for a
:class:`~sigmapi.experiments.robot.result.RobotResult`; :func:`film_episode` renders one
docking episode of the first seed's map learner and :func:`write_gif` saves frames as an
animated GIF (Pillow, which matplotlib installs).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi._outputs import save_figure, save_gif
from sigmapi.envs.robot.frames import Frames
from sigmapi.envs.robot.scene import Scene
from sigmapi.experiments.robot.config import PLAN

__all__ = ["film_episode", "plot_curves", "plot_unit_positions", "robot_figures", "write_gif"]

_TABLE = (0.15, 1.45, -1.1, 1.1)  # near edge, far edge, right, left (world x, y; robot.xml)


def plot_unit_positions(
    unit_z: NDArray[np.float64], map_shape: tuple[int, ...], ax: Any = None
) -> Any:
    """Top view of the table with each map unit's preferred ball position (the mean place of
    the calibration balls it wins), joined along the map's rows and columns; the robot at the
    origin facing +x."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(5, 5)).add_subplot()
    frames = Frames(Scene())
    x0, x1, y0, y1 = _TABLE
    ax.add_patch(plt.Rectangle((y0, x0), y1 - y0, x1 - x0, color=(0.85, 0.75, 0.6)))
    ax.add_patch(plt.Circle((0.0, 0.0), 0.13, color="0.5"))
    ok = np.all(np.isfinite(unit_z), axis=1)
    p = np.full((len(unit_z), 3), np.nan)
    p[ok] = frames.torso_position(unit_z[ok])
    grid = p.reshape(*map_shape, 3)
    for line in (*grid, *grid.transpose(1, 0, 2)):
        ax.plot(-line[:, 1], line[:, 0], color="tab:blue", lw=0.8)
    ax.plot(-p[:, 1], p[:, 0], "o", color="tab:red", ms=3)
    ax.set(
        xlim=(-1.0, 1.0),
        ylim=(-0.2, 1.45),
        aspect="equal",
        xlabel="right of the robot (m)",
        ylabel="ahead of the robot (m)",
        title="each unit's preferred ball position",
    )
    return ax


def plot_curves(curves: dict[str, dict[str, list[float]]], ax: Any = None) -> Any:
    """Success per block of episodes, mean over seeds with one standard deviation shaded."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(6, 4)).add_subplot()
    for state, c in curves.items():
        e, m, sd = (np.asarray(c[k]) for k in ("episode", "success", "success_sd"))
        ax.plot(e, m, label=state)
        ax.fill_between(e, m - sd, m + sd, alpha=0.2)
    ax.set(xlabel="episode", ylabel="success (docked and touched)", ylim=(0, 1))
    ax.legend(loc="lower right")
    return ax


def film_episode(result: Any, max_frames: int = 60) -> list[NDArray[np.uint8]]:
    """Frames (``env.render()``: third-person and head cameras) of one episode of the first
    seed's map learner of ``result``, acting on its policy after training; empty without one."""
    if result.model is None or result.agent is None:
        return []
    env = result.config.state_env("map", result.model, render_mode="rgb_array")
    start = PLAN.rng(result.seeds[0], "film")
    phi, _ = env.reset(seed=int(start.integers(0, 2**31 - 1)))
    frames = [env.render()]
    for _ in range(max_frames - 1):
        phi, _, terminated, truncated, _ = env.step(result.agent.act(phi))
        frames.append(env.render())
        if terminated or truncated:
            break
    env.close()
    return frames


def write_gif(frames: list[NDArray[np.uint8]], path: Path, fps: int = 6) -> Path:
    """Save ``frames`` as an animated GIF at ``path`` (:func:`~sigmapi._outputs.save_gif`)."""
    return save_gif(frames, path, fps=fps)


def robot_figures(
    result: Any, out_dir: Path, film: list[NDArray[np.uint8]] | None = None
) -> list[Path]:
    """Write ``map-on-table.png``, ``learning-curves.png`` and (with ``film``) ``film.png``."""
    import matplotlib.pyplot as plt

    paths = []
    if result.unit_z:
        ax = plot_unit_positions(result.unit_z[0], result.config.map.map_shape)
        paths.append(out_dir / "map-on-table.png")
        save_figure(ax.figure, paths[-1], dpi=120, bbox_inches="tight")
        plt.close(ax.figure)
    ax = plot_curves(result.curves())
    paths.append(out_dir / "learning-curves.png")
    save_figure(ax.figure, paths[-1], dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    if film:
        pick = np.linspace(0, len(film) - 1, min(6, len(film))).round().astype(int)
        fig, axes = plt.subplots(len(pick), 1, figsize=(7, 3 * len(pick)))
        for a, i in zip(np.atleast_1d(axes), pick, strict=True):
            a.imshow(film[i])
            a.set_axis_off()
            a.set_title(f"step {i}", fontsize=9)
        paths.append(out_dir / "film.png")
        save_figure(fig, paths[-1], dpi=90, bbox_inches="tight")
        plt.close(fig)
    return paths
