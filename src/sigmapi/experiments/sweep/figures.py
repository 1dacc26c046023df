"""The sweep's summary figure: a metric against the first grid parameter."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from sigmapi import _validate
from sigmapi._outputs import save_captioned
from sigmapi.experiments.kit.figures import legend_once
from sigmapi.experiments.sweep.table import METRIC_COLUMNS
from sigmapi.metrics import FOLD_THRESHOLD
from sigmapi.metrics.circular import CIRCULAR_KEYS

if TYPE_CHECKING:
    from matplotlib.axes import Axes

METRICS = (*METRIC_COLUMNS, *CIRCULAR_KEYS)
"""What the summary figure may show."""


class Spec(Protocol):
    """What the figure reads of a :class:`~sigmapi.experiments.sweep.run.SweepSpec`."""

    @property
    def preset(self) -> str: ...
    @property
    def seeds(self) -> Sequence[int]: ...
    @property
    def grid(self) -> Mapping[str, Any]: ...


DOT: dict[str, Any] = {"s": 14, "alpha": 0.6, "zorder": 3, "label": "a seed"}
"""How :func:`plot_sweep` marks a seed's run (in its line's colour)."""
CROSS: dict[str, Any] = {"s": 40, "marker": "x", "color": "crimson", "zorder": 4}
"""How :func:`plot_sweep` marks a folded run (labelled :data:`FOLDED`)."""
FOLDED = f"folded run (fold score >= {FOLD_THRESHOLD:g})"


def draw_summary(
    spec: Spec, rows: list[dict[str, object]], path: str | Path, metric: str = "order_r2"
) -> Path:
    """``metric`` against the first grid parameter (lines: the other parameters' values),
    median and spread over seeds, folded runs marked; written to ``path``, its
    :func:`caption` beside it (``path`` with the suffix ``.txt``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _validate.choice("metric", metric, METRICS)
    keys = sorted(spec.grid)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    if keys:
        plot_sweep(rows, keys[0], metric, group_by=keys[1:], ax=ax)
    else:
        plot_sweep([{**r, "preset": spec.preset} for r in rows], "preset", metric, ax=ax)
    ok = sum(str(r.get("status")) == "ok" for r in rows)
    folded = sum(_folded(r) for r in rows)
    ax.set_title(
        f"sweep of {spec.preset}: {ok} runs ok, {len(rows) - ok} failed, "
        f"{folded} folded; seeds {list(spec.seeds)}",
        fontsize=9,
    )
    p = Path(path)
    text = caption(spec, rows, metric)
    save_captioned(fig, p, text, dpi=120, bbox_inches="tight", facecolor="white")
    plt.close(fig)
    return p


def caption(spec: Spec, rows: list[dict[str, object]], metric: str) -> str:
    """The summary figure's caption, computed from the table's ``rows``."""
    keys = sorted(spec.grid)
    ok = [r for r in rows if str(r.get("status")) == "ok"]
    folded = sum(_folded(r) for r in ok)
    over = f"against {keys[0]}" if keys else "for the preset"
    lines = f"; one line per value of {', '.join(keys[1:])}" if keys[1:] else ""
    return (
        f"Sweep of {spec.preset}, seeds {', '.join(map(str, spec.seeds))}: {metric} {over} "
        f"({len(ok)} of {len(rows)} runs ok){lines}. Line: the median over seeds; band: min-max "
        f"over seeds; dots: each seed; red crosses: the {folded} folded run"
        f"{'s' * (folded != 1)} (fold score >= {FOLD_THRESHOLD:g}, the fold detector's "
        "threshold)."
    )


def _number(v: Any) -> float | None:
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def _folded(row: Mapping[str, Any]) -> bool:
    """Whether a table row (values may be strings, as read from CSV) is a folded run."""
    v = row.get("folded", False)
    return v is True or str(v).strip().lower() in ("true", "1")


def plot_sweep(
    rows: Sequence[Mapping[str, Any]],
    param: str,
    metric: str,
    group_by: Sequence[str] = (),
    *,
    ax: Axes,
) -> Axes:
    """``metric`` against ``param`` over a sweep's rows: each seed a dot, the median a line
    with the spread over seeds (min to max) as a band, folded runs as red crosses.

    ``rows`` are sweep table rows (values may be strings, as read from CSV); rows whose
    ``status`` is not ``ok`` are left out. One line per combination of ``group_by`` values.
    A parameter whose values are not all numbers is drawn on a categorical axis.
    """
    ok = [r for r in rows if r.get("status", "ok") == "ok"]
    raw = list(dict.fromkeys(str(r[param]) for r in ok))
    numeric = all(_number(v) is not None for v in raw)
    if numeric:
        raw.sort(key=float)
    pos = {v: (float(v) if numeric else float(i)) for i, v in enumerate(raw)}
    groups = list(dict.fromkeys(tuple(str(r[g]) for g in group_by) for r in ok))
    for gi, key in enumerate(groups):
        color = f"C{gi % 10}"
        label = ", ".join(f"{g} {v}" for g, v in zip(group_by, key, strict=True)) or None
        mine = [r for r in ok if tuple(str(r[g]) for g in group_by) == key]
        points = []  # x, median, min and max over seeds
        for v in raw:
            sel = [r for r in mine if str(r[param]) == v]
            vals = np.array([float(r[metric]) for r in sel])
            if vals.size == 0:
                continue
            x = pos[v]
            points.append((x, float(np.median(vals)), float(vals.min()), float(vals.max())))
            folded = np.array([_folded(r) for r in sel])
            ax.scatter(np.full(int((~folded).sum()), x), vals[~folded], color=color, **DOT)
            if folded.any():
                ax.scatter(np.full(int(folded.sum()), x), vals[folded], label=FOLDED, **CROSS)
        xs, med, lo, hi = zip(*points, strict=True)
        ax.plot(xs, med, "-o", color=color, label=label or "median over seeds", zorder=2)
        ax.fill_between(xs, lo, hi, color=color, alpha=0.15, lw=0, label="min-max over seeds")
    if not numeric:
        ax.set_xticks([float(i) for i in range(len(raw))], raw)
    ax.set_xlabel(param)
    ax.set_ylabel(f"{metric} (median, min-max over seeds)")
    legend_once(ax, fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    return ax
