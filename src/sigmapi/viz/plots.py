"""Figures of the reproduction: thin drawing functions over the arrays of
:mod:`sigmapi.analysis.map_data`.

Every function takes ``ax=None`` and returns the Axes it drew into; with ``ax=None`` it opens a
new pyplot figure. Figures made of several panels (Fig. 8, the learning curves) draw their
panels as inset Axes inside ``ax`` (then hidden; the panels are ``ax.child_axes``), so they
too fit any layout. Nothing here calls ``plt.show()``; the report draws on Agg figures.

- :func:`plot_fig8`: Fig. 8 of the chapter (invariance and topography of the map response).
- :func:`plot_weight_tiles`: Fig. 6a-style Sigma-Pi weight matrices, one tile per unit.
- :func:`plot_net`: the map in input space (each unit at the z it responds to).
- :func:`plot_learning_curves`: metrics and cost against iterations, with the sigma schedule.
- :func:`plot_invariance`: the winner as a function of x and y.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from sigmapi.analysis.map_data import Fig8Data, InvarianceMatrix

__all__ = [
    "has_refinement",
    "plot_fig8",
    "plot_invariance",
    "plot_learning_curves",
    "plot_net",
    "plot_weight_tiles",
]

CODE_CMAP = "viridis"
WEIGHT_CMAP = "RdBu_r"
"""Weights of both signs (an untrained map): a diverging map centred on zero."""
WEIGHT_CMAP_POSITIVE = "magma_r"
"""Weights >= 0 (a trained map: they learn non-negative outer products): a sequential map."""


def _count_label(v: float, _: object = None) -> str:
    """An iteration count as a short tick label: 500, 2k, 100k, 1M (no colliding digits)."""
    if v >= 1e6:
        return f"{v / 1e6:g}M"
    return f"{v / 1e3:g}k" if v >= 1e3 else f"{v:g}"


def _axes(ax: Axes | None, figsize: tuple[float, float], container: bool = False) -> Axes:
    """``ax``, or the Axes of a new pyplot figure (filling it when it holds inset panels)."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=figsize)
    return fig.add_axes((0.0, 0.0, 1.0, 1.0)) if container else fig.add_subplot()


def _container(ax: Axes, title: str, fontsize: float = 12) -> None:
    """Hide ``ax`` (its panels are insets) and put the title inside its top edge."""
    ax.set_axis_off()
    ax.set_title(title, fontsize=fontsize, y=0.99, va="top", pad=0)


def _inset(ax: Axes, left: float, bottom: float, width: float, height: float) -> Axes:
    return ax.inset_axes((left, bottom, width, height))


# ----------------------------------------------------------------------------- Fig. 8


def _draw_code(ax: Axes, code: NDArray[np.float64], shape: tuple[int, ...]) -> Any:
    """One input code or map response, scaled to its peak; returns the image (2-D) or None."""
    peak = float(np.max(np.abs(code)))
    v = code / peak if peak > 0 else code
    if len(shape) == 1:
        ax.stairs(v, np.arange(shape[0] + 1) - 0.5, fill=True, color="C0")  # one patch: fast
        ax.set_ylim(min(0.0, float(v.min()) * 1.1), 1.1)
        ax.set_xlim(-0.7, shape[0] - 0.3)
        ax.set_xticks([0, shape[0] // 2, shape[0] - 1])
        ax.set_yticks([0.0, 0.5, 1.0])
        ax.tick_params(labelsize=7)
        return None
    img = ax.imshow(v.reshape(shape), cmap=CODE_CMAP, vmin=0.0, vmax=1.0, interpolation="nearest")
    ax.set_xticks([])
    ax.set_yticks([])
    return img


def plot_fig8(data: Fig8Data, ax: Axes | None = None, title: str | None = None) -> Axes:
    """Fig. 8 of the chapter: rows x, y and the map response h; one column per input pair.

    Left columns: random (x, y) pairs with the same body-centred z; the response must look the
    same in all of them (invariance). Right columns: a pattern (an "L" in 2-D, two hills in
    1-D) on one input with a single hill on the other; the pattern reappears on the map
    (topography), oriented as the map's polarity dictates (named in the title). Every panel is
    scaled to its own peak.
    """
    d = len(data.x_shape)
    ax = _axes(ax, (11.0, 5.6) if d == 2 else (12.0, 5.0), container=True)
    zs = ", ".join(f"{v:.2f}" for v in data.z)
    _container(
        ax,
        title
        or f"Fig. 8: map response h to {data.n_pairs} (x, y) pairs with the same z = ({zs}) "
        f"(left) and to patterns (right)\nmap polarity: {data.polarity.name}",
        fontsize=11,
    )
    n_cols = data.x.shape[0]
    gap = 0.6  # extra space between the pair columns and the pattern columns, in columns
    left, right, bottom, top = 0.08, 0.90, 0.03, 0.84
    col_w = (right - left) / (n_cols + gap)
    row_h = (top - bottom) / 3.0
    rows = [
        ("x (retinal)", data.x, data.x_shape, "x unit"),
        ("y (gaze)", data.y, data.y_shape, "y unit"),
        ("map response h", data.h, data.map_shape, "map unit"),
    ]
    img = None
    for r, (name, codes, shape, unit) in enumerate(rows):
        for c in range(n_cols):
            x0 = left + col_w * (c + (gap if c >= data.n_pairs else 0.0))
            y0 = top - row_h * (r + 1)
            panel = _inset(ax, x0 + 0.1 * col_w, y0 + 0.24 * row_h, 0.8 * col_w, 0.66 * row_h)
            out = _draw_code(panel, codes[c], shape)
            img = out if out is not None else img
            if r == 0:
                panel.set_title(data.labels[c], fontsize=9)
            if c == 0:
                if d == 1:
                    panel.set_ylabel(f"{name}\n(of peak)", fontsize=9)
                    panel.set_xlabel(unit, fontsize=8)
                else:
                    panel.set_ylabel(f"{name}\naxis 0", fontsize=9)
                    panel.set_xlabel(f"{unit}, axis 1", fontsize=8)
    if img is not None:
        cax = _inset(ax, 0.93, bottom + 0.24 * row_h, 0.015, top - bottom - 0.34 * row_h)
        ax.figure.colorbar(img, cax=cax, label="activity (fraction of the panel's peak)")
    return ax


# ----------------------------------------------------------------------------- weights


def plot_weight_tiles(
    tiles: NDArray[np.float64],
    map_shape: tuple[int, ...],
    ax: Axes | None = None,
    title: str | None = None,
    x_label: str = "x unit i",
    y_label: str = "y unit j",
) -> Axes:
    """Fig. 6a-style weights: each unit's matrix ``tiles[k]`` (x on rows, y on columns).

    Tiles sit where their unit sits on the map (a 1-D map: one row, map unit k left to right),
    separated by a blank line; one diverging colour scale centred on 0 for all tiles.
    """
    k, a, b = tiles.shape
    if int(np.prod(map_shape)) != k:
        raise ValueError(f"map_shape {map_shape} does not hold {k} tiles")
    one_d = len(map_shape) == 1
    if one_d:  # wrap a 1-D map into a few rows, read left to right, top to bottom
        m0 = int(np.ceil(np.sqrt(k / 2.0)))
        m1 = int(np.ceil(k / m0))
    else:
        m0, m1 = map_shape[0], map_shape[1]
    ax = _axes(ax, (max(5.0, 0.9 * m1 + 1.5), max(3.0, 0.9 * m0 + 1.2)))
    gap = max(2, a // 4) if one_d else 1  # blank rows between tile rows (room for "k=...")
    top = gap if one_d else 0
    mosaic = np.full((top + m0 * (a + gap) - gap, m1 * (b + 1) - 1), np.nan)
    for u in range(k):
        r, c = divmod(u, m1)
        r0 = top + r * (a + gap)
        mosaic[r0 : r0 + a, c * (b + 1) : c * (b + 1) + b] = tiles[u]
    # a few saturated weights (border units) would wash out every anti-diagonal: scale to the
    # 99.5th percentile and mark the clipped range on the colour bar
    top_abs = float(np.nanmax(np.abs(mosaic)))
    vmax = float(np.nanpercentile(np.abs(mosaic), 99.5)) or top_abs or 1.0
    import matplotlib as mpl

    signed = float(np.nanmin(mosaic)) < -1e-3 * vmax  # negligible negatives: a trained map
    name = WEIGHT_CMAP if signed else WEIGHT_CMAP_POSITIVE
    cmap = mpl.colormaps[name].with_extremes(bad="white")
    img = ax.imshow(
        mosaic, cmap=cmap, vmin=-vmax if signed else 0.0, vmax=vmax, interpolation="nearest"
    )
    if one_d:
        for u in range(k):
            r, c = divmod(u, m1)
            ax.text(
                c * (b + 1) + (b - 1) / 2,
                top + r * (a + gap) - 0.7,
                f"k={u}",
                ha="center",
                va="bottom",
                fontsize=8,
            )
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_xlabel(f"one tile per map unit k; within a tile: {y_label} left to right")
        ax.set_ylabel(f"within a tile: {x_label}\ntop to bottom")
    else:
        ax.set_xticks([c * (b + 1) + (b - 1) / 2 for c in range(m1)], [str(c) for c in range(m1)])
        ax.set_yticks([r * (a + 1) + (a - 1) / 2 for r in range(m0)], [str(r) for r in range(m0)])
        ax.tick_params(labelsize=7, length=0)
        ax.set_xlabel(f"map axis 1 (one tile per unit); within a tile: {y_label} left to right")
        ax.set_ylabel(f"map axis 0; within a tile:\n{x_label} top to bottom")
    ax.set_title(
        title or "Sigma-Pi weights w_kij of each map unit k (Fig. 6a)", pad=12 if one_d else 6
    )
    clipped = top_abs > vmax * (1 + 1e-9)
    label = "weight (colour clipped at the 99.5th percentile)" if clipped else "weight"
    extend = ("both" if signed else "max") if clipped else "neither"
    ax.figure.colorbar(img, ax=ax, label=label, fraction=0.046, pad=0.02, extend=extend)
    return ax


# ----------------------------------------------------------------------------- net


def plot_net(
    centres: NDArray[np.float64],
    map_shape: tuple[int, ...],
    ax: Axes | None = None,
    z_range: tuple[float, float] = (0.0, 1.0),
    title: str | None = None,
) -> Axes:
    """The map in input space: each unit at the z it responds to, grid neighbours joined.

    1-D maps: the centre against the unit index (an ordered map is monotonic). 2-D maps: the
    classic SOM net in the (z0, z1) plane; unit (0, 0) and the end of map axis 1 are marked so
    that the map's orientation can be read.
    """
    d = centres.shape[1]
    ax = _axes(ax, (6.0, 4.0) if d == 1 else (5.6, 5.4))
    if len(map_shape) == 1 and d == 1:
        k = np.arange(map_shape[0])
        ax.plot(k, centres[:, 0], "-o", color="C0", ms=5)
        ax.set_xlabel("map unit k")
        ax.set_ylabel("z the unit responds to")
        ax.set_ylim(*z_range)
        ax.set_title(title or "The map in input space: receptive-field centre of each unit")
        ax.grid(alpha=0.3)
        return ax
    if len(map_shape) != 2 or d != 2:
        raise ValueError(
            f"plot_net draws 1-D maps of 1-D z or 2-D maps of 2-D z, got map "
            f"{map_shape} and z of {d} dimensions"
        )
    g = centres.reshape(map_shape[0], map_shape[1], 2)
    rows = [g[r] for r in range(map_shape[0])] + [g[:, c] for c in range(map_shape[1])]
    for i, line in enumerate(rows):
        label = "grid neighbours, joined" if i == 0 else "_neighbours"
        ax.plot(line[:, 0], line[:, 1], "-", color="C0", lw=1, label=label)
    ax.plot(g[..., 0].ravel(), g[..., 1].ravel(), "o", color="C0", ms=3, label="a unit")
    ax.plot(*g[0, 0], "s", color="C3", ms=8, label="unit (0, 0)")
    ax.plot(*g[0, -1], "^", color="C2", ms=8, label=f"unit (0, {map_shape[1] - 1})")
    ax.plot(*g[-1, 0], "v", color="C1", ms=8, label=f"unit ({map_shape[0] - 1}, 0)")
    ax.legend(loc="upper left", fontsize=8, bbox_to_anchor=(1.01, 1.0))
    ax.set_xlim(*z_range)
    ax.set_ylim(*z_range)
    ax.set_aspect("equal")
    ax.set_xlabel("z0 (axis 0 of z)")
    ax.set_ylabel("z1 (axis 1 of z)")
    ax.set_title(title or "The map in input space: each unit at its receptive-field centre")
    ax.grid(alpha=0.3)
    return ax


# ----------------------------------------------------------------------------- learning curves


def has_refinement(curves: Sequence[Mapping[str, Sequence[float]]]) -> bool:
    """Whether any curve holds records of refinement rounds (``refined > 0``)."""
    return any(any(float(r) > 0 for r in c.get("refined", [])) for c in curves)


def _split(c: Mapping[str, Sequence[float]]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Masks of a curve's training records and of its refinement records (the latter with
    the last training record first: the refinement starts from it)."""
    n = len(c["t"])
    refined = np.asarray(c.get("refined", [0.0] * n), dtype=float)
    train = refined == 0
    rounds = refined > 0
    if rounds.any() and train.any():
        rounds[np.flatnonzero(train)[-1]] = True
    return train, rounds


def plot_learning_curves(
    curves: Sequence[Mapping[str, Sequence[float]]],
    ax: Axes | None = None,
    reference: Mapping[str, float] | None = None,
    schedule: tuple[Sequence[float], Sequence[float]] | None = None,
    title: str | None = None,
    ceiling: Mapping[str, float] | None = None,
) -> Axes:
    """Learning curves: view consistency, z error and cost against iterations, and sigma.

    ``curves``: one mapping per seed with columns ``t``, ``refined``, ``view_consistency``,
    ``view_within_one``, ``z_error``, ``cost``, ``cost_winner``, ``sigma`` (as written by
    :meth:`sigmapi.analysis.curves.LearningCurve.to_dict`); thin lines per seed, a thick line for
    the mean. Records of the training (``refined`` 0) go on a log axis of iterations; those
    of the refinement rounds after it (``refined`` > 0) on a linear axis of refinement pairs
    to its right, starting from the last training record. ``reference``: dashed horizontal
    lines for ``view_consistency``, ``view_within_one``, ``z_error`` and ``z_error_floor``.
    ``ceiling``: dash-dot lines of the learning rule's ceiling for the same metrics
    (:func:`sigmapi.analysis.fixed_point.fixed_point`), across both axes. ``schedule``: ``(t,
    sigma)`` of the full sigma schedule, drawn under the checkpoints.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

    ax = _axes(ax, (10.0, 9.0), container=True)
    _container(ax, title or "Learning curves (measured at checkpoints during training)")
    curves = [c for c in curves if len(c.get("t", [])) > 0]
    if not curves:
        raise ValueError("curves must hold at least one curve with checkpoints")
    ref, top_line = dict(reference or {}), dict(ceiling or {})
    refine = has_refinement(curves)
    panels = [
        (
            "view consistency,\nunit usage",
            [
                ("view_consistency", "view consistency"),
                ("view_within_one", "view within one"),
                ("usage", "usage"),
            ],
        ),
        ("z error (grid spacings)", [("z_error", "z error")]),
        ("cost E (sec. 6.3)", [("cost", "at the current sigma"), ("cost_winner", "winner only")]),
        ("sigma (map units)", [("sigma", "at checkpoints")]),
    ]
    n = len(panels)
    left, right, bottom, top, gap = 0.10, 0.70, 0.06, 0.93, 0.035
    main_right = right - 0.17 if refine else right
    h = (top - bottom - gap * (n - 1)) / n
    axes, raxes = [], []
    for p, (label, series) in enumerate(panels):
        y0 = top - (p + 1) * h - p * gap
        pa = _inset(ax, left, y0, main_right - left, h)
        ra = _inset(ax, main_right + 0.015, y0, right - main_right - 0.015, h) if refine else None
        if ra is not None:
            ra.sharey(pa)
            raxes.append(ra)
        axes.append(pa)
        for s, (key, name) in enumerate(series):
            colour = f"C{s}"
            have = [c for c in curves if key in c]
            parts = [_split(c) for c in have]
            for part, target in ((0, pa), (1, ra)):
                if target is None:
                    continue
                xs = [
                    np.asarray(c["t" if part == 0 else "refined"], dtype=float)[m[part]]
                    for c, m in zip(have, parts, strict=True)
                ]
                vs = [
                    np.asarray(c[key], dtype=float)[m[part]]
                    for c, m in zip(have, parts, strict=True)
                ]
                if key == "sigma":  # log axis: sigma 0 (the refinement's winner alone) left out
                    pos = [v > 0 for v in vs]
                    xs = [x[k] for x, k in zip(xs, pos, strict=True)]
                    vs = [v[k] for v, k in zip(vs, pos, strict=True)]
                same = bool(xs) and all(
                    len(x) == len(xs[0]) and len(x) > 0 and np.allclose(x, xs[0]) for x in xs
                )
                # each seed's line, unless every seed's is the mean's (e.g. the schedule's
                # sigma): one line then, not several hidden under it
                if not same or any(not np.allclose(v, vs[0]) for v in vs[1:]):
                    for x, v in zip(xs, vs, strict=True):
                        target.plot(x, v, "-", color=colour, lw=0.8, alpha=0.4)
                if same:
                    many = len(vs) > 1
                    target.plot(
                        xs[0],
                        np.mean(vs, axis=0),
                        "-o",
                        color=colour,
                        lw=1.8,
                        ms=3,
                        label=(f"{name} (mean of {len(vs)})" if many else name)
                        if part == 0
                        else None,
                    )
            lines = []  # (value, line style, width, legend) of the horizontal lines
            if key in ref:
                lines.append((ref[key], "--", 1.0, f"reference {ref[key]:g}"))
            if key in top_line:
                legend = f"the rule's ceiling (fixed point) {top_line[key]:.3f}"
                lines.append((top_line[key], "-.", 1.2, legend))
            for target in (pa, ra) if ra is not None else (pa,):
                for value, ls, lw, text in lines:
                    target.axhline(
                        value, color=colour, ls=ls, lw=lw, label=text if target is pa else None
                    )
        if label.startswith("z error") and "z_error_floor" in ref:
            for target in (pa, ra):
                if target is not None:
                    target.axhline(
                        ref["z_error_floor"],
                        color="0.4",
                        ls=":",
                        lw=1,
                        label=f"quantisation floor {ref['z_error_floor']:g}"
                        if target is pa
                        else None,
                    )
        if label.startswith("sigma") and schedule is not None:
            st, sv = (np.asarray(v, dtype=float) for v in schedule)
            keep = st > 0
            pa.plot(st[keep], sv[keep], "-", color="0.5", lw=1, label="schedule")
        if label.startswith("sigma"):
            pa.set_yscale("log")
        pa.set_xscale("log")
        pa.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        pa.xaxis.set_major_formatter(FuncFormatter(_count_label))
        pa.xaxis.set_minor_formatter(NullFormatter())
        pa.set_ylabel(label)
        pa.grid(alpha=0.3, which="both")
        legend_of = ra if ra is not None else pa
        handles, names = pa.get_legend_handles_labels()
        legend_of.legend(handles, names, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        if ra is not None:
            ra.grid(alpha=0.3)
            ra.tick_params(labelleft=False)
            ra.xaxis.set_major_locator(MaxNLocator(nbins=3, integer=True))
            ra.xaxis.set_major_formatter(FuncFormatter(_count_label))
            if p == 0:
                ra.set_title("refinement", fontsize=9)
        if p < n - 1:
            pa.tick_params(labelbottom=False)
            if ra is not None:
                ra.tick_params(labelbottom=False)
    axes[-1].set_xlabel("training iteration")
    if raxes:
        raxes[-1].set_xlabel("refinement pairs")
    train_t = [np.asarray(c["t"], dtype=float)[_split(c)[0]] for c in curves]
    lo = min(float(np.min(t)) for t in train_t if t.size)
    hi = max(float(np.max(t)) for t in train_t if t.size)
    for pa in axes:
        pa.set_xlim(lo * 0.9, hi * 1.1)
    if raxes:
        top_r = max(float(np.max(c.get("refined", [0.0]))) for c in curves)
        for ra in raxes:
            ra.set_xlim(-0.06 * top_r, top_r * 1.06)
    return ax


# ----------------------------------------------------------------------------- invariance


def plot_invariance(
    inv: InvarianceMatrix, ax: Axes | None = None, title: str | None = None
) -> Axes:
    """The winner as a function of x (rows) and y (columns): constant anti-diagonals = invariance.

    Matrix layout (row 0 at the top), so constant z = (x + y) / 2 runs along the
    anti-diagonals, bottom-left to top-right.
    """
    ax = _axes(ax, (5.6, 4.6))
    n = inv.positions.size
    step = 1.0 / (n - 1) if n > 1 else 1.0
    ext = (-step / 2, 1 + step / 2, 1 + step / 2, -step / 2)
    img = ax.imshow(inv.value, cmap="viridis", extent=ext, interpolation="nearest")
    ax.set_xlabel(f"y position (axis {inv.axis})")
    ax.set_ylabel(f"x position (axis {inv.axis})")
    ax.set_title(
        title
        or f"Winner as a function of x and y: anti-diagonals (constant z) "
        f"should be constant\n{100 * inv.constancy:.1f} % of cells agree with their anti-diagonal",
        fontsize=10,
    )
    ax.figure.colorbar(img, ax=ax, label=inv.value_label)
    return ax
