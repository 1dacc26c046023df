"""The figure of ``sigmapi compare``: z error against labels, and view consistency.

Functions draw from the comparison's data, the dict of ``CompareResult.to_dict()`` (also its
``result.json``): ``methods`` (per method its medians: ``z_error_by_labels``,
``view_consistency``, ``unit_consistency``), ``quantisation_floor`` and ``config`` (``labels``,
``seeds``). They take ``ax=None`` (a new figure when None) and return the Axes;
:func:`compare_figure` lays out both panels and returns the Figure. Nothing is shown.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib import ticker
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from sigmapi.experiments.kit.figures import axes

STYLE = {
    "sigma-pi": ("C0", "-", "o"),
    "sigma-pi same view": ("C0", ":", "v"),
    "sigma-pi ordering none": ("C0", "--", "s"),
    "kohonen": ("C3", "-", "o"),
    "kohonen two-view": ("C3", ":", "v"),
    "minisom": ("C1", "--", "s"),
    "basis functions": ("C2", "-", "D"),
    "rbm": ("C4", "-", "^"),
}


def plot_labels_curve(result: Mapping[str, Any], ax: Axes | None = None) -> Axes:
    """z error (median over seeds) against the number of labelled samples, per method."""
    ax = axes(ax, (5.5, 4))
    for method in result["methods"]:
        name = method["name"]
        curve = {int(n): e for n, e in method["z_error_by_labels"].items()}
        color, ls, marker = STYLE.get(name, ("k", "-", "."))
        ref = name == "sigma-pi"  # on top, so a method with the same curve does not hide it
        style = {"color": color, "linestyle": ls, "marker": marker, "markersize": 4, "label": name}
        width, z = (2.5, 3) if ref else (1.2, 2)
        ax.plot(list(curve), list(curve.values()), **style, zorder=z, linewidth=width)
    floor = result["quantisation_floor"]
    ax.axhline(floor, color="0.5", linewidth=0.8, label=f"winner-only floor {floor:.2f}")
    at = (min(result["config"]["labels"]), floor)
    ax.annotate(
        "winner-only floor", at, xytext=(2, 3), textcoords="offset points", fontsize=7, color="0.4"
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    _plain_log_ticks(ax)
    ax.set_xlabel("labelled samples given to the read-out")
    ax.set_ylabel("z error (grid spacings)")
    n = len(result["config"]["seeds"])
    ax.set_title(f"z error vs labels, median of {n} seed{'s' * (n > 1)}")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    return ax


def _plain_log_ticks(ax: Axes) -> None:
    """Log axes labelled with plain numbers (``0.5``, ``2``, ``1000``; not ``5x10^-1``):
    ticks at 1, 2 and 5 times the powers of ten (more on an axis that spans less than about
    a decade, so that it has a few), the minor ticks unlabelled."""
    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        narrow = np.log10(hi / lo) < 1.3 if lo > 0 and hi > lo else False
        subs = (1.0, 1.5, 2.0, 3.0, 5.0, 7.0) if narrow else (1.0, 2.0, 5.0)
        axis.set_major_locator(ticker.LogLocator(base=10, subs=subs))
        axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(ticker.NullFormatter())


def plot_consistency(result: Mapping[str, Any], ax: Axes | None = None) -> Axes:
    """Same place for both views (with all labels) and same unit (no label), per method."""
    ax = axes(ax, (5.5, 4))
    names = [m["name"] for m in result["methods"]]
    pos = np.arange(len(names))
    place = [float(m["view_consistency"]) for m in result["methods"]]
    unit = [float(m["unit_consistency"]) for m in result["methods"]]
    ax.barh(pos + 0.2, place, height=0.4, color="C0", label="same place (read-out binned)")
    ax.barh(pos - 0.2, unit, height=0.4, color="0.6", label="same unit (no label)")
    ax.set_yticks(pos, names, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1)
    ax.set_xlabel("fraction of test z's whose two views agree")
    ax.set_title("view consistency")
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    return ax


def compare_figure(result: Mapping[str, Any]) -> Figure:
    """Both panels side by side (``result``: the comparison's dict, see the module docstring)."""
    fig = Figure(figsize=(11, 5), layout="constrained")
    left, right = fig.subplots(1, 2, width_ratios=(1.2, 1))
    plot_labels_curve(result, left)
    plot_consistency(result, right)
    return fig
