"""Figures of the iCub experiment: both eyes' views, map 2's units over the table, reach
success over the table and over gaze, the babbling curves, a film strip of one reach.

Thin plot functions (``ax`` in, Axes out) and :func:`icub_figures`, which writes them for an
:class:`~sigmapi.experiments.icub.result.ICubResult`, each with its caption beside it
(:func:`~sigmapi._outputs.save_captioned`: ``NAME.txt``), computed from the data. Every mark
has a legend entry; legends sit beside the axes, off the data; series that coincide are drawn
with markers of decreasing size (each one shows) and their legend entries say so.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi._outputs import save_captioned
from sigmapi.envs.icub import REACH_REGION
from sigmapi.experiments.icub.reaching import METHODS
from sigmapi.experiments.kit.figures import (
    coincide_sentence,
    coinciding,
    film_strip,
    plot_apart,
)
from sigmapi.metrics import FOLD_THRESHOLD, ORDERED_R2

_TABLE = (0.09, 0.59, -0.5, 0.3)  # near and far edge, right and left side (world x, y)

_BESIDE = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0}
"""Legend keywords: beside the Axes, right of the data."""


def _table(ax: Any, robot: bool = True) -> None:
    """The table (tan), the region the test balls are drawn from (dashed) and, with ``robot``,
    the robot (grey disc), each with its legend label."""
    import matplotlib.pyplot as plt

    x0, x1, y0, y1 = _TABLE
    ax.add_patch(plt.Rectangle((-y1, x0), y1 - y0, x1 - x0, color=(0.85, 0.75, 0.6), label="table"))
    (rx0, rx1), (ry0, ry1) = REACH_REGION
    ax.add_patch(
        plt.Rectangle(
            (-ry1, rx0),
            ry1 - ry0,
            rx1 - rx0,
            fill=False,
            ls="--",
            color="0.3",
            lw=0.8,
            label="region of the test balls",
        )
    )
    if robot:
        ax.add_patch(plt.Circle((0.0, 0.0), 0.07, color="0.5", label="robot (torso)"))
    ax.set(
        xlim=(-0.35, 0.55),
        ylim=(-0.1, 0.62),
        aspect="equal",
        xlabel="right of the robot (m)",
        ylabel="ahead of the robot (m)",
    )


def verdicts(record: Mapping[str, Any]) -> tuple[str, str]:
    """A map's order and fold verdicts in words from its metrics ``record`` (``order_r2``,
    ``folded``, and ``fold_score`` where known), with the bound and the fold score's scale."""
    r2 = float(record["order_r2"])
    order = (
        f"order R$^2$ {r2:.3f}, "
        + ("ordered" if r2 >= ORDERED_R2 else "twisted")
        + f" (ordered at >= {ORDERED_R2:g})"
    )
    fold = "flagged folded" if record["folded"] else "not flagged folded"
    score = record.get("fold_score")
    fold += " by the fold detector"
    rule = f"flagged at >= {FOLD_THRESHOLD:g}"
    if score is None:
        return order, f"{fold} (fold score {rule})"
    return order, f"{fold}: fold score {float(score):.2f} ({rule})"


def plot_units_on_table(
    points: NDArray[np.float64],
    map_shape: tuple[int, ...],
    ax: Any = None,
    record: Mapping[str, Any] | None = None,
) -> Any:
    """Top view of the table with map 2's units at the table point of their preferred
    torso-centred direction, joined along the map's rows and columns, the region of the test
    balls (dashed) and the robot (grey disc), legend beside the Axes. ``record`` (the map's
    metrics: ``order_r2``, ``folded``, ``fold_score``) puts its verdicts in the title, so a
    twisted map is called twisted and a folded one folded."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(7.5, 4.5)).add_subplot()
    _table(ax)
    grid = points.reshape(*map_shape, 2)
    for i, line in enumerate((*grid, *grid.transpose(1, 0, 2))):
        label = "map 2's rows and columns" if i == 0 else "_rows"
        ax.plot(-line[:, 1], line[:, 0], color="tab:blue", lw=0.8, label=label)
    ax.plot(-points[:, 1], points[:, 0], "o", color="tab:red", ms=3, label="a unit's direction")
    title = "map 2: each unit's preferred direction, on the table"
    if record is not None:
        order, fold = verdicts(record)
        title += f"\n{order}\n{fold}"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8, **_BESIDE)
    return ax


def plot_success_table(
    ball: NDArray[np.float64],
    success: Mapping[str, NDArray[np.bool_]],
    methods: tuple[str, ...] = METHODS,
) -> Any:
    """One top view per method: each reach's ball, a green dot when touched, a red cross
    otherwise; one legend below the panels."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        1, len(methods), figsize=(3.2 * len(methods), 2.6), sharey=True, layout="constrained"
    )
    for ax, m in zip(np.atleast_1d(axes), methods, strict=True):
        _table(ax, robot=False)
        ok = np.asarray(success[m], dtype=bool)
        ax.plot(-ball[ok, 1], ball[ok, 0], "o", color="tab:green", ms=3, label="touched")
        ax.plot(-ball[~ok, 1], ball[~ok, 0], "x", color="tab:red", ms=4, label="missed")
        ax.set_title(f"{m}: {ok.mean():.2f}", fontsize=10)
        ax.set(xlim=(-0.15, 0.42), ylim=(0.08, 0.36))
    handles, labels = np.atleast_1d(axes)[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize=8)
    return fig


def gaze_bins(
    gaze: NDArray[np.float64], success: Mapping[str, NDArray[np.bool_]], bins: int = 4
) -> tuple[list[float], dict[str, list[float]]]:
    """The gaze's horizontal direction (neck yaw - eye version, degrees; positive: to the
    robot's left) in ``bins`` equal-count bins: the bins' centres and each method's success."""
    look = np.degrees(gaze[:, 5] - gaze[:, 1])
    bins = max(1, min(bins, look.size // 2))
    which = np.argsort(np.argsort(look)) * bins // look.size  # equal-count bins
    centres = [float(np.mean(look[which == b])) for b in range(bins)]
    rates = {m: [float(ok[which == b].mean()) for b in range(bins)] for m, ok in success.items()}
    return centres, rates


def plot_success_gaze(
    gaze: NDArray[np.float64],
    success: Mapping[str, NDArray[np.bool_]],
    bins: int = 4,
    ax: Any = None,
) -> Any:
    """Success per method over the gaze's horizontal direction (:func:`gaze_bins`), one marker
    per method (series that coincide all show, their legend entries say so)."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(8, 4)).add_subplot()
    centres, rates = gaze_bins(gaze, success, bins)
    plot_apart(ax, dict.fromkeys(rates, centres), rates)
    ax.set(
        xlabel="gaze direction: neck yaw - eye version (deg, + left)",
        ylabel="success (share of reaches)",
        ylim=(-0.05, 1.08),
        title="reach success over the gaze",
    )
    ax.legend(fontsize=8, **_BESIDE)
    return ax


def _log_ticks(ax: Any, values: Sequence[float], apart: float = 0.15) -> None:
    """Major ticks of a log x axis at ``values``, labelled plainly, each at least ``apart``
    decades from the last one kept (so no two labels touch); no minor tick labels."""
    from matplotlib.ticker import NullFormatter, NullLocator

    kept: list[float] = []
    for v in sorted(set(values)):
        if v > 0 and (not kept or np.log10(v) - np.log10(kept[-1]) >= apart):
            kept.append(v)
    ax.set_xticks(kept, [f"{v:g}" for v in kept])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


def plot_babbling(curves: Mapping[str, Sequence[Sequence[float]]], ax: Any = None) -> Any:
    """Median palm error (cm) on held-out babbles against the babbles learned from (log
    axis), one marker per method (:func:`~sigmapi.experiments.kit.figures.plot_apart`)."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(8, 4)).add_subplot()
    pts = {m: np.asarray(p, dtype=float).reshape(-1, 2) for m, p in curves.items()}
    plot_apart(
        ax,
        {m: p[:, 0].tolist() for m, p in pts.items()},
        {m: p[:, 1].tolist() for m, p in pts.items()},
    )
    ax.set(
        xscale="log",
        xlabel="babbles learned from",
        ylabel="palm error, median (cm)",
        title="babbling: reach error on held-out babbles",
    )
    _log_ticks(ax, [float(n) for p in pts.values() for n in p[:, 0]])
    ax.legend(fontsize=8, **_BESIDE)
    return ax


def plot_servo(
    first_view: Mapping[str, float], servo: Mapping[str, float], upper: float, ax: Any = None
) -> Any:
    """Success per associated method: the posture of the first view alone and after the
    learned servo, side by side; ``upper`` (scripted IK) as a dashed line; legend beside."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure(figsize=(8, 4)).add_subplot()
    names = list(servo)
    at = np.arange(len(names))
    for shift, values, label in ((-0.2, first_view, "first view"), (0.2, servo, "after servo")):
        bars = ax.bar(at + shift, [values[m] for m in names], 0.4, label=label)
        ax.bar_label(bars, fmt="%.2f", fontsize=8)
    ax.axhline(upper, ls="--", color="0.3", lw=0.8, label=f"scripted IK {upper:.2f}")
    ax.set_xticks(at, names)
    ax.set(ylabel="success", ylim=(0, 1.1), title="reaches: first view alone, then the servo")
    ax.legend(fontsize=8, **_BESIDE)
    return ax


def plot_eyes(eyes: Mapping[str, Any]) -> Any:
    """Both eyes' frames, the ball's (yellow circle) and the palm's (cyan cross) projections,
    the detector's ball (white x) and hand marker (magenta x); one legend below the panels."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(7, 4.0), layout="constrained")
    for ax, eye, title in zip(axes, ("l_eye", "r_eye"), ("left eye", "right eye"), strict=True):
        img = eyes[eye]
        ax.imshow(img, extent=(0, img.shape[1], img.shape[0], 0))
        (bu, bv), (pu, pv) = eyes[f"{eye}_ball"], eyes[f"{eye}_palm"]
        ax.plot([bu], [bv], "o", mfc="none", mec="yellow", ms=12, mew=1.5, label="ball")
        ax.plot([pu], [pv], "+", color="cyan", ms=12, mew=2, label="palm")
        for target, colour in (("ball", "white"), ("hand", "magenta")):
            seen = eyes.get(f"{eye}_{target}_seen")
            if seen is not None:
                ax.plot([seen[0]], [seen[1]], "x", color=colour, ms=8, mew=1.5,
                        label=f"{target} detected")  # fmt: skip
        ax.set(xlim=(0, img.shape[1]), ylim=(img.shape[0], 0), title=title)
        ax.set_xlabel(f"ball ({bu:.1f}, {bv:.1f}) px, palm ({pu:.1f}, {pv:.1f}) px", fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    labels = [t if "detected" in t else f"{t}, projected into the eye" for t in labels]
    leg = fig.legend(handles, labels, loc="outside lower center", ncol=2)
    leg.get_frame().set_facecolor("0.6")  # the yellow circle shows on grey
    return fig


def _rates(values: Mapping[str, float]) -> str:
    return ", ".join(f"{m} {v:.2f}" for m, v in values.items())


def icub_figures(result: Any, out_dir: Path) -> list[Path]:
    """Write ``eyes.png``, ``map-on-table.png``, ``success-table.png``, ``success-gaze.png``,
    ``babbling.png``, ``film.png`` and, with the servo, ``servo.png`` (from the first seed; the
    success figures pool every seed's reaches), each with its caption ``NAME.txt``."""
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    first = result.per_seed[0]
    seed = result.seeds[0]
    seeds = ("seed " if len(result.seeds) == 1 else "seeds ") + ", ".join(map(str, result.seeds))
    over = "median over " if len(result.seeds) > 1 else ""
    paths: list[Path] = []

    def save(fig: Any, name: str, caption: str) -> None:
        paths.append(save_captioned(fig, out_dir / name, caption, dpi=110, bbox_inches="tight"))
        plt.close(fig)

    if "eyes" in first:
        eyes = first["eyes"]
        h, w = eyes["l_eye"].shape[:2]
        save(
            plot_eyes(eyes),
            "eyes.png",
            f"Seed {seed}: both eyes' {w}x{h} frames with the arm at the posture the learned "
            "method reaches to for the first test ball; yellow circle: where the ball projects "
            "into each eye, cyan cross: where the palm projects; white and magenta x: where the "
            "detector finds the ball and the hand's marker in the pixels.",
        )
    if "unit_table" in first:
        record = first["maps"]["map2"]
        order, fold = verdicts(record)
        rows, cols = result.config.map_shape
        save(
            plot_units_on_table(first["unit_table"], result.config.map_shape, record=record).figure,
            "map-on-table.png",
            f"Seed {seed}, top view: map 2's {rows}x{cols} units, each drawn (red dot) at the "
            "table point of its preferred torso-centred direction and joined (blue) along the "
            f"map's rows and columns; {order.replace('R$^2$', 'R^2')}; {fold}. Tan: the table; "
            "dashed: the region the test balls are drawn from; grey disc: the robot.",
        )
    ball = np.concatenate([s["ball"] for s in result.per_seed])
    gaze = np.concatenate([s["gaze"] for s in result.per_seed])
    succ = {m: np.concatenate([s["success"][m] for s in result.per_seed]) for m in result.methods()}
    total = result.success()
    save(
        plot_success_table(ball, succ, tuple(succ)),
        "success-table.png",
        f"Every test ball of {seeds} ({ball.shape[0]} reaches per method), top view, one "
        "panel per method: green dot, touched; red cross, missed; dashed, the region the balls "
        f"are drawn from. Success: {_rates(total)}.",
    )
    centres, rates = gaze_bins(gaze, succ)
    save(
        plot_success_gaze(gaze, succ).figure,
        "success-gaze.png",
        f"Reach success per method ({seeds}, {ball.shape[0]} reaches each) over the "
        f"gaze's horizontal direction in {len(centres)} bins of equal count, centred at "
        + ", ".join(f"{c:+.0f}" for c in centres)
        + " degrees. "
        + coincide_sentence(coinciding(rates), "in every bin"),
    )
    served = result.servo()
    if served:
        save(
            plot_servo(total, served, total["scripted_ik"]).figure,
            "servo.png",
            f"Success per associated method ({seeds}): the posture of the first view "
            f"alone ({_rates({m: total[m] for m in served})}) and after the learned servo "
            f"({_rates(served)}); dashed: scripted IK, {total['scripted_ik']:.2f}.",
        )
    curves = result.curves()
    ax = plot_babbling(curves)
    last = {m: pts[-1][1] for m, pts in curves.items()}
    n_last = int(next(iter(curves.values()))[-1][0])
    save(
        ax.figure,
        "babbling.png",
        f"Median palm error (cm; {over}{seeds}) on held-out babbles against the "
        f"number of babbles learned from (log axis); after {n_last} babbles: "
        + ", ".join(f"{m} {v:.1f} cm" for m, v in last.items())
        + ". "
        + coincide_sentence(
            coinciding({m: [e for _, e in p] for m, p in curves.items()}), "at every point"
        ),
    )
    save_film(
        first.get("film") or [], save, f"Seed {seed}", "during the learned method's first reach"
    )
    return paths


def save_film(film: Sequence[NDArray[np.uint8]], save: Any, lead: str, what: str) -> None:
    """Where ``film`` holds frames, ``save(figure, "film.png", caption)`` a strip of some of
    them (:func:`~sigmapi.experiments.kit.figures.film_strip`), captioned ``lead``, how many
    of how many frames, ``what`` (how they were filmed)."""
    if film:
        fig, pick = film_strip(film, "frame {k} of {n}")
        save(
            fig,
            "film.png",
            f"{lead}: {len(pick)} of the {len(film)} frames filmed {what}, in order.",
        )
