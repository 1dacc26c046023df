"""Figures of the iCub's 3-D task: the end-point error per method, and what it measures.

- :func:`end_point_histogram`: the end-point errors of every method, one panel each;
- :func:`end_point_definition`: a side view of the palm, its contact point, the marker behind
  it and the ball, with the distance the end-point error is.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi._outputs import save_captioned
from sigmapi.envs.icub.detect import TARGETS
from sigmapi.envs.icub.model import BALL_RADIUS, HAND_MARKER, HAND_SPAN, MARKER_RADIUS


def end_point_histogram(errors: Mapping[str, NDArray[np.float64]], path: Path) -> Path:
    """One histogram per method of its end-point errors ``errors[method]`` (cm), on shared
    bins, the median and the 90th percentile marked; the figure at ``path`` with its caption
    beside it."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    path.parent.mkdir(parents=True, exist_ok=True)
    top = float(max(np.percentile(e, 98) for e in errors.values()))
    bins = np.linspace(0.0, max(top, 1.0), 31)
    fig, axes = plt.subplots(len(errors), 1, figsize=(6.0, 1.3 * len(errors)), sharex=True)
    for ax, (name, e) in zip(np.atleast_1d(axes), errors.items(), strict=True):
        ax.hist(np.clip(e, 0.0, bins[-1]), bins=bins, color="0.55", label="reaches")
        med, p90 = float(np.median(e)), float(np.percentile(e, 90))
        ax.axvline(med, color="C3", label="median")
        ax.axvline(p90, color="C0", ls="--", label="90th percentile")
        ax.set_ylabel(name, rotation=0, ha="right", va="center")
        ax.text(
            0.99,
            0.8,
            f"median {med:.1f}, p90 {p90:.1f} cm",
            transform=ax.transAxes,
            ha="right",
            fontsize=8,
            bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.9},
        )
        ax.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=3))
    np.atleast_1d(axes)[-1].set_xlabel("end-point error, cm (the last bin holds the rest)")
    n = len(next(iter(errors.values())))
    caption = (
        f"End-point error per method, eyes free ({n} reaches each): the distance from the "
        "palm's contact point where the reach ended to the ball's surface where it was put. "
        "Red line: the median; blue dashed: the 90th percentile."
    )
    out = save_captioned(fig, path, caption, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def end_point_definition(path: Path) -> Path:
    """The end-point error drawn (a side view, to scale, centimetres): the hand's section
    along the palm's normal, the palm's contact point ``C``, the marker behind it, the ball,
    and ``| |C - b| - R |``; written to ``path`` with its caption."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Rectangle

    path.parent.mkdir(parents=True, exist_ok=True)
    cm = 100.0
    r = BALL_RADIUS * cm
    fig, ax = plt.subplots(figsize=(6.0, 3.6))
    b = np.array([0.0, 0.0])
    c = np.array([-5.5, 2.0])  # the palm's contact point, some way off the ball
    ax.add_patch(Circle(tuple(b), r, color="C3", alpha=0.8))
    ax.plot(*b, "k+")
    ax.annotate("b (centre)", _xy(b), xytext=(0.4, -0.8), fontsize=8)
    behind, front = (cm * d for d in HAND_SPAN)  # the hand along the palm's normal (+x here)
    ax.add_patch(Rectangle((c[0] - behind, c[1] - 4.0), behind + front, 8.0, color="0.8"))
    ax.plot([c[0], c[0]], [c[1] - 4.0, c[1] + 4.0], color="0.3", lw=2)
    m = c + np.array([HAND_MARKER[2] * cm, 0.0])
    ax.add_patch(Circle(tuple(m), MARKER_RADIUS * cm, color="C2"))
    ax.annotate(
        f"marker ({-HAND_MARKER[2] * cm:.0f} cm behind C)",
        _xy(m),
        xytext=(m[0] - 4.5, m[1] - 5.6),
        fontsize=8,
        arrowprops={"arrowstyle": "->"},
    )
    ax.plot(*c, "ko")
    ax.annotate(
        "C: palm's contact point",
        _xy(c),
        xytext=(c[0] - 1.0, c[1] + 4.8),
        fontsize=8,
        arrowprops={"arrowstyle": "->"},
    )
    ax.text(c[0] - 3.7, c[1] - 3.7, "the hand", fontsize=8, color="0.3")
    ax.annotate(
        "", _xy(c + np.array([1.6, 0.0])), _xy(c), arrowprops={"arrowstyle": "->", "color": "0.3"}
    )
    ax.text(c[0] + 0.3, c[1] + 0.4, "palm's normal", fontsize=7)
    u = (b - c) / np.linalg.norm(b - c)
    s = b - r * u
    ax.plot(*zip(c, s, strict=True), color="C0", lw=2)
    ax.plot(*zip(s, b, strict=True), color="C0", lw=1, ls=":")
    mid = 0.5 * (c + s)
    ax.annotate(
        "end-point error = | |C - b| - R |",
        _xy(mid),
        xytext=(mid[0] - 2.5, mid[1] - 5.5),
        fontsize=9,
        color="C0",
        arrowprops={"arrowstyle": "->", "color": "C0"},
    )
    ax.text(r * 0.75, r * 0.9, f"R = {r:.0f} cm", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlim(-11, 5)
    ax.set_ylim(-6, 7.5)
    ax.set_xlabel("cm")
    caption = (
        "The end-point error: the distance from the palm's contact point C (the palm site, "
        "the middle of the palm's surface) where the reach ended to the surface of the ball "
        f"(radius {r:.0f} cm) where the experimenter put it. A contact counts as the palm's "
        "when its point lies no more than 1 cm behind C along the palm's normal; the hand "
        f"(grey, to scale along the normal) reaches {behind:.1f} cm behind C, the green marker "
        f"the eyes see sits {-HAND_MARKER[2] * cm:.0f} cm behind it."
    )
    out = save_captioned(fig, path, caption, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def _xy(p: NDArray[np.float64]) -> tuple[float, float]:
    """A 2-D point as the pair matplotlib's annotations take."""
    return float(p[0]), float(p[1])


def film_and_eyes(first: Mapping[str, Any], seed: int, out_dir: Path) -> list[Path]:
    """``film.png``, a strip of the frames filmed during the learned chain's first reach
    (eyes free), and ``eyes.png``, both eyes' frames of a view of that ball with the arm at the
    learned posture and the detections drawn on (:func:`~sigmapi.experiments.icub.plots.
    plot_eyes`), from the first seed's record where it holds them; each with its caption."""
    import matplotlib.pyplot as plt

    from sigmapi.experiments.icub.plots import plot_eyes, save_film
    from sigmapi.experiments.icub.reaching import EYES

    paths: list[Path] = []

    def save(fig: Any, name: str, caption: str) -> None:
        paths.append(save_captioned(fig, out_dir / name, caption, dpi=110, bbox_inches="tight"))
        plt.close(fig)

    save_film(
        first.get("film") or [],
        save,
        f"Seed {seed}, 3-D box",
        "from a fixed camera during the learned chain's first reach (eyes free; the ball "
        "floats where the experimenter put it)",
    )
    eyes = first.get("eyes")
    if eyes is not None:
        h, w = eyes["l_eye"].shape[:2]
        found = sum(eyes[f"{e}_{t}_seen"] is not None for e in EYES for t in TARGETS)
        save(
            plot_eyes(eyes),
            "eyes.png",
            f"Seed {seed}, 3-D box: both eyes' {w}x{h} frames of one view of the first test "
            "ball, the arm at the posture the learned chain reads from that view; white and "
            "magenta x: where the detector finds the ball and the hand's marker in the pixels "
            f"({found} of 4 found); yellow circle and cyan cross: where the ball's centre and "
            "the palm project (the scorer's truth).",
        )
    return paths


_SLICE_COLOURS = ("tab:blue", "tab:orange", "tab:green")


def map_slices(
    units: Mapping[str, tuple[NDArray[np.float64], tuple[int, ...]]],
    scores: Mapping[str, Mapping[str, Any]],
    seed: int,
    path: Path,
) -> Path:
    """``map-slices.png``: per map, the three middle slices of its 3-D grid (one across each
    map axis) drawn at the units' mean true positions (``units``: per map the ``(n, 3)``
    positions in metres and the map's shape), joined along the grid's lines; captioned from
    ``scores`` (per map its order R², fold score and verdict)."""
    import matplotlib.pyplot as plt

    frames = {"map_head": "head-centred", "map_torso": "torso-centred"}
    fig = plt.figure(figsize=(10, 4.8), layout="constrained")
    words = []
    for k, (name, (pos, shape)) in enumerate(units.items()):
        ax = fig.add_subplot(1, len(units), k + 1, projection="3d")
        grid = (100.0 * pos).reshape(*shape, 3)  # cm
        for axis, colour in enumerate(_SLICE_COLOURS):
            sl = np.take(grid, shape[axis] // 2, axis=axis)  # (a, b, 3)
            for line in (*sl, *sl.transpose(1, 0, 2)):
                ax.plot(*line.T, color=colour, lw=1.0)
            ax.plot([], [], color=colour, label=f"middle slice across map axis {axis + 1}")
        s = scores[name]
        state = (
            f"folded (fold score {s['fold_score']:.2f})"
            if s["folded"]
            else f"not flagged (fold score {s['fold_score']:.2f})"
        )
        title = "map H" if name == "map_head" else "map T"
        ax.set_title(f"{title}: order R$^2$ {s['order_r2']:.2f}, {state}", fontsize=9)
        ax.set(xlabel="x cm", ylabel="y cm")
        ax.set_zlabel("z cm", labelpad=10)
        ax.set_box_aspect(tuple(np.ptp(grid.reshape(-1, 3), axis=0)))  # cm alike on every axis
        ax.tick_params(labelsize=7)
        words.append(
            f"{title} ({'x'.join(map(str, shape))}, {frames[name]}): order R^2 "
            f"{s['order_r2']:.2f}, {state}"
        )
        if k == 0:
            fig.legend(loc="outside lower center", ncol=3, fontsize=8)
    caption = (
        f"Seed {seed}, 3-D box: each map's units at their mean true position over the "
        "calibration views they win (a unit that wins none at the affine fit's place), joined "
        "along the map's grid lines, for the three middle slices of the grid (one across each "
        "map axis; centimetres, the map's own frame). " + "; ".join(words) + "."
    )
    out = save_captioned(fig, path, caption, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out
