"""The figure of ``sigmapi stream``: view consistency and fold rate over the dwell time.

Functions draw from the experiment's data, the dict of ``StreamResult.to_dict()`` (also its
``result.json``): ``methods``, one entry per method and dwell time with ``name``, ``dwell``
(None for the map on explicit pairs), the medians, ``fold_rate`` and ``per_seed`` values. They
take ``ax=None`` (a new figure when None) and return the Axes; :func:`stream_figure` lays out
both panels and returns the Figure. Nothing is shown.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from sigmapi.experiments.kit.figures import axes, legend_once
from sigmapi.metrics import FOLD_THRESHOLD

BAND = "best to worst seed (shaded)"
"""The label of the bands from the best to the worst seed (one legend entry for them all)."""


Entry = Mapping[str, Any]


def _lines(result: Mapping[str, Any]) -> tuple[dict[str, list[Entry]], Entry]:
    """The stream methods by name, each a list of entries sorted by dwell time, and the map
    on explicit pairs."""
    out: dict[str, list[Entry]] = {}
    for m in result["methods"]:
        if m["dwell"] is not None:
            out.setdefault(m["name"], []).append(m)
    pairs = next(m for m in result["methods"] if m["dwell"] is None)
    return {k: sorted(v, key=lambda m: m["dwell"]) for k, v in out.items()}, pairs


def _dwell_axis(ax: Axes, lines: dict[str, list[Entry]]) -> None:
    dwells = sorted({m["dwell"] for v in lines.values() for m in v})
    ax.set_xscale("log", base=2)
    ax.set_xticks(dwells, [str(d) for d in dwells])
    ax.set_xlabel("dwell time d (saccades per object position)")


def plot_view_consistency(
    result: Mapping[str, Any], ax: Axes | None = None, *, margin: float | None = None
) -> Axes:
    """View consistency over the dwell time: per stream method the median over seeds (line)
    and best to worst seed (band); the map on explicit pairs as a horizontal line and band.

    ``margin``: zoom in on the pairs' median +- 3 margins and shade +- ``margin`` around it
    (the acceptance's margin); values outside lie beyond the axis."""
    ax = axes(ax, (5.5, 4))
    lines, pairs = _lines(result)
    vals = pairs["per_seed"]["view_consistency"]
    ax.axhspan(min(vals), max(vals), color="k", alpha=0.1, lw=0, label=BAND)
    ax.axhline(pairs["view_consistency"], color="k", ls="--", label="explicit pairs")
    for i, (name, entries) in enumerate(lines.items()):
        d = [m["dwell"] for m in entries]
        per = np.array([m["per_seed"]["view_consistency"] for m in entries])
        lo, hi = per.min(axis=1), per.max(axis=1)
        ax.fill_between(d, lo, hi, color=f"C{i}", alpha=0.15, lw=0, label=BAND)
        ax.plot(d, [m["view_consistency"] for m in entries], "o-", color=f"C{i}", label=name)
    _dwell_axis(ax, lines)
    ax.set_ylabel("view consistency (same winner)")
    if margin is not None:
        mid = pairs["view_consistency"]
        label = f"explicit pairs +- {margin:g}"
        ax.axhspan(mid - margin, mid + margin, color="g", alpha=0.08, lw=0, label=label)
        ax.set_ylim(mid - 3 * margin, mid + 3 * margin)
        ax.set_title("near explicit pairs", fontsize=10)
    legend_once(ax, fontsize=8, loc="lower right")  # the bands share one entry, in grey
    return ax


def plot_fold_rate(result: Mapping[str, Any], ax: Axes | None = None) -> Axes:
    """Share of seeds whose map folded (:func:`sigmapi.metrics.fold_score`) over the dwell
    time, per stream method; the map on explicit pairs as a horizontal line."""
    ax = axes(ax, (5.5, 4))
    lines, pairs = _lines(result)
    ax.axhline(pairs["fold_rate"], color="k", ls="--", label="explicit pairs")
    n = len(lines)
    for i, (name, entries) in enumerate(lines.items()):
        d = np.array([m["dwell"] for m in entries], dtype=float)
        shift = 2.0 ** (0.06 * (i - (n - 1) / 2))  # side by side where rates coincide
        ax.plot(d * shift, [m["fold_rate"] for m in entries], "o-", color=f"C{i}", label=name)
    _dwell_axis(ax, lines)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel(f"fold rate (share of seeds with fold score >= {FOLD_THRESHOLD:g})")
    ax.legend(fontsize=8, loc="best")
    return ax


def stream_figure(result: Mapping[str, Any]) -> Figure:
    """Three panels side by side: :func:`plot_view_consistency` in full and near the map on
    explicit pairs (the acceptance's margin, ``result["acceptance"]["margin"]``), and
    :func:`plot_fold_rate`."""
    fig = Figure(figsize=(15, 4.2), layout="constrained")
    left, mid, right = fig.subplots(1, 3)
    plot_view_consistency(result, left)
    plot_view_consistency(result, mid, margin=result["acceptance"]["margin"])
    plot_fold_rate(result, right)
    n, preset = len(result["settings"]["seeds"]), result["settings"]["preset"]
    fig.suptitle(f"Learning from a stream ({preset}, {n} seed{'s' * (n > 1)})")
    return fig
