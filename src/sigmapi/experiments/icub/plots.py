"""Figures of the iCub experiment: both eyes' views, map 2's units over the table, reach
success over the table and over gaze, the babbling curves, a film strip of one reach.

Thin plot functions (``ax`` in, Axes out) and :func:`icub_figures`, which writes them for an
:class:`~sigmapi.experiments.icub.result.ICubResult`; captions are computed from the data.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi._outputs import save_figure, save_gif
from sigmapi.envs.icub import REACH_REGION
from sigmapi.experiments.icub.reaching import METHODS

__all__ = [
    "icub_figures",
    "plot_eyes",
    "plot_servo",
    "plot_success_gaze",
    "plot_success_table",
    "plot_units_on_table",
    "write_gif",
]

_TABLE = (0.09, 0.59, -0.5, 0.3)  # near and far edge, right and left side (world x, y)


def _table(ax: Any) -> None:
    import matplotlib.pyplot as plt

    x0, x1, y0, y1 = _TABLE
    ax.add_patch(plt.Rectangle((-y1, x0), y1 - y0, x1 - x0, color=(0.85, 0.75, 0.6)))
    (rx0, rx1), (ry0, ry1) = REACH_REGION
    ax.add_patch(
        plt.Rectangle((-ry1, rx0), ry1 - ry0, rx1 - rx0, fill=False, ls="--", color="0.3", lw=0.8)
    )
    ax.add_patch(plt.Circle((0.0, 0.0), 0.07, color="0.5"))
    ax.set(
        xlim=(-0.35, 0.55),
        ylim=(-0.1, 0.62),
        aspect="equal",
        xlabel="right of the robot (m)",
        ylabel="ahead of the robot (m)",
    )


def plot_units_on_table(
    points: NDArray[np.float64],
    map_shape: tuple[int, ...],
    ax: Any = None,
    record: dict[str, Any] | None = None,
) -> Any:
    """Top view of the table with map 2's units at the table point of their preferred
    torso-centred direction, joined along the map's rows and columns (dashed: the region of
    the reaches; grey disc: the robot). ``record`` (the map's metrics: ``order_r2``,
    ``folded``) puts its verdict in the title, so a folded map is called folded."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(5.5, 4.5)).add_subplot()
    _table(ax)
    grid = points.reshape(*map_shape, 2)
    for line in (*grid, *grid.transpose(1, 0, 2)):
        ax.plot(-line[:, 1], line[:, 0], color="tab:blue", lw=0.8)
    ax.plot(-points[:, 1], points[:, 0], "o", color="tab:red", ms=3)
    title = "map 2: each unit's preferred direction, on the table"
    if record is not None:
        verdict = "flagged folded" if record["folded"] else "not flagged folded"
        title += f"\norder R$^2$ {record['order_r2']:.3f}, {verdict} by the fold detector"
    ax.set_title(title)
    return ax


def plot_success_table(
    ball: NDArray[np.float64],
    success: dict[str, NDArray[np.bool_]],
    methods: tuple[str, ...] = METHODS,
) -> Any:
    """One top view per method: each reach's ball, filled green when touched, red otherwise."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(methods), figsize=(3.2 * len(methods), 3.2), sharey=True)
    for ax, m in zip(np.atleast_1d(axes), methods, strict=True):
        _table(ax)
        ok = success[m]
        ax.plot(-ball[ok, 1], ball[ok, 0], "o", color="tab:green", ms=3)
        ax.plot(-ball[~ok, 1], ball[~ok, 0], "x", color="tab:red", ms=4)
        ax.set_title(f"{m}: {ok.mean():.2f}", fontsize=10)
        ax.set(xlim=(-0.15, 0.42), ylim=(0.08, 0.36))
    return fig


def plot_success_gaze(
    gaze: NDArray[np.float64], success: dict[str, NDArray[np.bool_]], bins: int = 4, ax: Any = None
) -> Any:
    """Success per method over the gaze's horizontal direction (neck yaw + eye version,
    degrees; positive: to the robot's left), in ``bins`` equal-count bins."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(6, 4)).add_subplot()
    look = np.degrees(gaze[:, 5] - gaze[:, 1])
    bins = max(1, min(bins, look.size // 2))
    which = np.argsort(np.argsort(look)) * bins // look.size  # equal-count bins
    centres = [float(np.mean(look[which == b])) for b in range(bins)]
    for m, ok in success.items():
        ax.plot(centres, [ok[which == b].mean() for b in range(bins)], "o-", label=m)
    ax.set(
        xlabel="gaze direction: neck yaw - eye version (deg, + left)",
        ylabel="success",
        ylim=(-0.02, 1.02),
        title="reach success over the gaze",
    )
    ax.legend(fontsize=8)
    return ax


def plot_servo(
    first_view: dict[str, float], servo: dict[str, float], upper: float, ax: Any = None
) -> Any:
    """Success per associated method: the posture of the first view alone and after the
    learned servo, side by side; ``upper`` (scripted IK) as a dashed line."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(6, 4)).add_subplot()
    names = list(servo)
    at = np.arange(len(names))
    for shift, values, label in ((-0.2, first_view, "first view"), (0.2, servo, "after servo")):
        bars = ax.bar(at + shift, [values[m] for m in names], 0.4, label=label)
        ax.bar_label(bars, fmt="%.2f", fontsize=8)
    ax.axhline(upper, ls="--", color="0.3", lw=0.8, label=f"scripted IK {upper:.2f}")
    ax.set_xticks(at, names)
    ax.set(ylabel="success", ylim=(0, 1.1), title="reaches: first view alone, then the servo")
    ax.legend(fontsize=8, loc="lower right")
    return ax


def plot_eyes(eyes: dict[str, Any]) -> Any:
    """Both eyes' frames, the ball's (red circle) and the palm's (cyan cross) projections."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(7, 3.6))
    for ax, eye, title in zip(axes, ("l_eye", "r_eye"), ("left eye", "right eye"), strict=True):
        img = eyes[eye]
        ax.imshow(img, extent=(0, img.shape[1], img.shape[0], 0))
        (bu, bv), (pu, pv) = eyes[f"{eye}_ball"], eyes[f"{eye}_palm"]
        ax.plot([bu], [bv], "o", mfc="none", mec="yellow", ms=12, mew=1.5)
        ax.plot([pu], [pv], "+", color="cyan", ms=12, mew=2)
        ax.set(xlim=(0, img.shape[1]), ylim=(img.shape[0], 0), title=title)
        ax.set_xlabel(f"ball ({bu:.1f}, {bv:.1f}) px, palm ({pu:.1f}, {pv:.1f}) px", fontsize=8)
    return fig


def write_gif(frames: list[NDArray[np.uint8]], path: Path, fps: int = 8) -> Path:
    """Save ``frames`` as an animated GIF at ``path`` (:func:`~sigmapi._outputs.save_gif`)."""
    return save_gif(frames, path, fps=fps)


def icub_figures(result: Any, out_dir: Path) -> list[Path]:
    """Write ``eyes.png``, ``map-on-table.png``, ``success-table.png``, ``success-gaze.png``,
    ``babbling.png``, ``film.png`` and, with the servo, ``servo.png`` (from the first seed; the
    success figures pool every seed's reaches)."""
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    first = result.per_seed[0]
    paths: list[Path] = []

    def save(fig: Any, name: str) -> None:
        paths.append(out_dir / name)
        save_figure(fig, paths[-1], dpi=110, bbox_inches="tight")
        plt.close(fig)

    if "eyes" in first:
        save(plot_eyes(first["eyes"]), "eyes.png")
    if "unit_table" in first:
        save(
            plot_units_on_table(
                first["unit_table"], result.config.map_shape, record=first["maps"]["map2"]
            ).figure,
            "map-on-table.png",
        )
    ball = np.concatenate([s["ball"] for s in result.per_seed])
    gaze = np.concatenate([s["gaze"] for s in result.per_seed])
    succ = {m: np.concatenate([s["success"][m] for s in result.per_seed]) for m in METHODS}
    save(plot_success_table(ball, succ), "success-table.png")
    save(plot_success_gaze(gaze, succ).figure, "success-gaze.png")
    served = result.servo()
    if served:
        total = result.success()
        save(plot_servo(total, served, total["scripted_ik"]).figure, "servo.png")
    ax = plt.figure(figsize=(6, 4)).add_subplot()
    for m, pts in result.curves().items():
        n, e = np.array(pts).T
        ax.plot(n, e, "o-", label=m)
    ax.set(
        xscale="log",
        xlabel="babbles learned from",
        ylabel="palm error, median (cm)",
        title="babbling: reach error on held-out babbles",
    )
    ax.legend(fontsize=8)
    save(ax.figure, "babbling.png")
    film = first.get("film") or []
    if film:
        pick = np.linspace(0, len(film) - 1, min(6, len(film))).round().astype(int)
        fig, axes = plt.subplots(1, len(pick), figsize=(3.0 * len(pick), 2.4))
        for a, i in zip(np.atleast_1d(axes), pick, strict=True):
            a.imshow(film[i])
            a.set_axis_off()
            a.set_title(f"frame {i + 1} of {len(film)}", fontsize=8)
        save(fig, "film.png")
    return paths
