"""The figure of ``sigmapi neurons``, drawn from its result dict.

Every mark has a legend entry (or a colour bar, where colour carries a value); the legends sit
below their panels, off the data."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from sigmapi.experiments.kit.figures import BELOW
from sigmapi.experiments.kit.results import JSON

NOTE: dict[str, Any] = {"textcoords": "offset points", "xytext": (4, -12), "fontsize": 8}
"""Where a dendritic map's branch count is written: below right of its mark."""


def _bars(ax: Axes, methods: list[JSON], **kwargs: Any) -> None:
    """The view consistency of ``methods`` against their synapses per unit: the median, a bar
    down to the worst seed (``kwargs``: to ``errorbar``)."""
    vc = [m["view_consistency"] for m in methods]
    low = [m["view_consistency"] - m["view_consistency_worst"] for m in methods]
    x = [m["synapses"] for m in methods]
    ax.errorbar(x, vc, yerr=[low, [0.0] * len(methods)], capsize=3, **kwargs)


def neurons_figure(result: JSON) -> Figure:
    """Three panels: view consistency against synapses per unit (1-D maps), the spiking
    networks against the decision window at the reference rate, the branches of one map."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 6.2), layout="constrained")
    ax = axes[0]
    rate = [m for m in result["methods"] if m["kind"] == "rate" and m["task"] == "1d"]
    sp = next(m for m in rate if m["name"] == "sigma-pi")
    vc = sp["view_consistency"]
    ax.axhspan(vc - 0.02, vc, color="0.85", label="within 0.02 of Sigma-Pi")
    groups = (
        ("dendritic-D", "dense dendritic (median, worst)", "o"),
        ("dendritic-sparse-D", "sparse dendritic, 2 synapses per branch", "D"),
    )
    for prefix, label, marker in groups:
        dend = [m for m in rate if m["name"].startswith(prefix)]
        if not dend:
            continue
        _bars(ax, dend, marker=marker, label=label)
        for m in dend:
            ax.annotate(f"D={m['branches']}", (m["synapses"], m["view_consistency"]), **NOTE)
    for m, mk in ((sp, "s"), (next(m for m in rate if m["name"] == "basis-function"), "^")):
        _bars(ax, [m], marker=mk, linestyle="none", label=m["name"])
    ax.set_xlabel("synapses per map unit (the most in any unit)")
    ax.set_ylabel("view consistency (same winner)")
    ax.set_title("1-D maps of first-order neurons")
    ax.legend(fontsize=8, **BELOW)

    ax = axes[1]
    spk = [m for m in result["methods"] if m["kind"] == "spiking" and m["peak_rate"] == 100]
    for base, colour in (
        ("spiking-conjunction", "C0"),
        ("spiking-dendritic", "C1"),
        ("spiking-sparse-dendritic", "C2"),
    ):
        rows = sorted(
            (m for m in spk if m["name"].startswith(base + "-") and "-pool" not in m["name"]),
            key=lambda m: m["window_ms"],
        )
        if not rows:
            continue
        w = [m["window_ms"] for m in rows]
        lines = (
            ([m["vc_gap"] for m in rows], "o-", "view consistency - rate map's"),
            ([m["agreement"] - 1.0 for m in rows], "s--", "agreement - 1"),
        )
        for y, style, what in lines:
            ax.plot(w, y, style, color=colour, label=f"{base}: {what}")
    ax.axhline(-0.02, color="0.5", lw=0.8, ls=":", label="-0.02: the acceptance margin")
    ax.set_xscale("log")
    ticks = sorted({m["window_ms"] for m in spk})
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel("decision window (ms)")
    ax.set_ylabel("difference (median over seeds)")
    ax.set_title("spiking networks, 100 Hz peak rate")
    ax.legend(fontsize=7, **BELOW)

    ax = axes[2]
    b = result["branches"][0]
    unit = np.asarray(b["unit"])
    xc, yc = np.asarray(b["x_centre"])[:, 0], np.asarray(b["y_centre"])[:, 0]
    dots = ax.scatter(xc, yc, c=unit, cmap="viridis", s=18, label="a branch")
    fig.colorbar(dots, ax=ax, label="map unit of the branch")
    n = float(max(xc.max(), yc.max())) + 1.0
    for i, s in enumerate(np.arange(0, 2 * n, 2.0)):
        label = "retinal + gaze centre constant (one z)" if i == 0 else "_z"
        ax.plot([0, s], [s, 0], color="0.75", lw=0.6, zorder=0, label=label)
    ax.set_xlim(-0.5, n)
    ax.set_ylim(-0.5, n)
    ax.set_xlabel("retinal centre of a branch's synapses (grid units, axis 0)")
    ax.set_ylabel("gaze centre (grid units, axis 0)")
    ax.set_title(f"branches of the D={b['branches']} map (colour: unit)")
    ax.legend(fontsize=8, **BELOW)
    return fig
