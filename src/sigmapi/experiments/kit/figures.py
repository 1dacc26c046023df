"""What the experiments' figures share: series that may coincide drawn so that each one shows,
and said so (:func:`plot_apart`, :func:`coincide_sentence`); legends below a panel."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.legend import Legend

BELOW = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.16), "borderaxespad": 0.0}
"""Legend keywords: below the panel, under its x label."""

MARKERS = ("o", "s", "^", "D", "v", "P", "X")
"""One marker per series, in drawing order."""

SHRINK = 1.35
"""Each series' marker is this many times smaller than the one drawn before it."""


def axes(ax: Axes | None = None, size: tuple[float, float] = (5, 3.5)) -> Axes:
    """``ax``, or the Axes of a new figure of ``size`` inches (pyplot untouched)."""
    from matplotlib.figure import Figure  # matplotlib: only when drawing

    return Figure(figsize=size, layout="constrained").subplots() if ax is None else ax


def coinciding(series: Mapping[str, Sequence[float]]) -> dict[str, str]:
    """Per series name, the earlier series it equals at every point (within 1e-9), if any."""
    out: dict[str, str] = {}
    names = list(series)
    for i, m in enumerate(names):
        for other in names[:i]:
            a, b = np.asarray(series[m], float), np.asarray(series[other], float)
            if a.shape == b.shape and np.allclose(a, b, rtol=0.0, atol=1e-9):
                out[m] = out.get(other, other)
                break
    return out


def coincide_sentence(same: Mapping[str, str], where: str) -> str:
    """A caption's sentence on the coinciding series ``same`` (:func:`coinciding`)."""
    if not same:
        return f"No two series coincide {where}."
    pairs = "; ".join(f"{m} coincides with {o}" for m, o in same.items())
    return (
        f"{pairs} {where}: drawn with markers of decreasing size (the later one smaller, on "
        "top), so every series shows."
    )


def plot_apart(
    ax: Axes,
    x: Mapping[str, Sequence[float]],
    y: Mapping[str, Sequence[float]],
    *,
    labels: Mapping[str, str] | None = None,
    colours: Mapping[str, object] | None = None,
    largest: float = 13.0,
    width: float = 3.0,
    say: bool = True,
) -> dict[str, str]:
    """Draw each series of ``y`` over its ``x`` on ``ax`` (:func:`coinciding` on x and y):
    marker ``MARKERS[i]`` of size ``largest / SHRINK**i`` on top of the ones before (a series
    under another shows round it), line width from ``width`` down; ``labels`` and ``colours``
    per name (default: the name, ``C0``, ``C1``, ...). With ``say`` a coinciding series' label
    names the one it lies on (without, the caption must say so). Returns the coinciding series."""
    same = coinciding({m: [*x[m], *y[m]] for m in y})
    for i, m in enumerate(y):
        label = (labels or {}).get(m, m)
        if say and m in same:
            label += f" (coincides with {(labels or {}).get(same[m], same[m])})"
        colour = (colours or {}).get(m) or f"C{i}"
        ax.plot(
            x[m],
            y[m],
            "-",
            marker=MARKERS[i % len(MARKERS)],
            ms=largest / SHRINK**i,
            lw=max(0.6, width * (1.0 - 0.15 * i)),
            color=colour,
            label=label,
            zorder=2 + i,
        )
    return same


def legend_once(ax: Axes, **kwargs: Any) -> Legend:
    """The legend of ``ax`` (``kwargs`` to ``ax.legend``) with each label once, drawn by the
    first mark that has it (e.g. one entry for the bands of every series)."""
    handles, labels = ax.get_legend_handles_labels()
    once: dict[str, Artist] = {}
    for handle, label in zip(handles, labels, strict=True):
        once.setdefault(label, handle)
    return ax.legend(list(once.values()), list(once), **kwargs)


def film_strip(film: Sequence[object], title: str, across: bool = True) -> tuple[Any, Any]:
    """Six frames of ``film`` evenly apart (all of a shorter one) in one row (``across``) or
    one column, each titled ``title.format(i=index, k=index + 1, n=frames)``; returns the
    figure and the indices of the frames it shows."""
    import matplotlib.pyplot as plt  # matplotlib: only when drawing

    pick = np.linspace(0, len(film) - 1, min(6, len(film))).round().astype(int)
    shape, size = (
        ((1, len(pick)), (3.0 * len(pick), 2.4)) if across else ((len(pick), 1), (7, 3 * len(pick)))
    )
    fig, axes = plt.subplots(*shape, figsize=size)
    for a, i in zip(np.atleast_1d(axes), pick, strict=True):
        a.imshow(film[i])
        a.set_axis_off()
        a.set_title(title.format(i=i, k=i + 1, n=len(film)), fontsize=8 if across else 9)
    return fig, pick
