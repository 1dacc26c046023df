"""The sweep's summary figure: a metric against the first grid parameter."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

from sigmapi import _validate
from sigmapi._outputs import save_captioned
from sigmapi.experiments.sweep.table import METRIC_COLUMNS
from sigmapi.metrics import FOLD_THRESHOLD
from sigmapi.metrics.circular import CIRCULAR_KEYS

__all__ = ["METRICS", "caption", "draw_summary"]

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


def draw_summary(
    spec: Spec, rows: list[dict[str, Any]], path: str | Path, metric: str = "order_r2"
) -> Path:
    """``metric`` against the first grid parameter (lines: the other parameters' values),
    median and spread over seeds, folded runs marked; written to ``path``, its
    :func:`caption` beside it (``path`` with the suffix ``.txt``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sigmapi.viz.plots import plot_sweep

    _validate.choice("metric", metric, METRICS)
    keys = sorted(spec.grid)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    if keys:
        plot_sweep(rows, keys[0], metric, group_by=keys[1:], ax=ax)
    else:
        plot_sweep([{**r, "preset": spec.preset} for r in rows], "preset", metric, ax=ax)
    ok = sum(str(r.get("status")) == "ok" for r in rows)
    folded = sum(str(r.get("folded")).lower() in ("true", "1") for r in rows)
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


def caption(spec: Spec, rows: list[dict[str, Any]], metric: str) -> str:
    """The summary figure's caption, computed from the table's ``rows``."""
    keys = sorted(spec.grid)
    ok = [r for r in rows if str(r.get("status")) == "ok"]
    folded = sum(str(r.get("folded")).lower() in ("true", "1") for r in ok)
    over = f"against {keys[0]}" if keys else "for the preset"
    lines = f"; one line per value of {', '.join(keys[1:])}" if keys[1:] else ""
    return (
        f"Sweep of {spec.preset}, seeds {', '.join(map(str, spec.seeds))}: {metric} {over} "
        f"({len(ok)} of {len(rows)} runs ok){lines}. Line: the median over seeds; band: min-max "
        f"over seeds; dots: each seed; red crosses: the {folded} folded run"
        f"{'s' * (folded != 1)} (fold score >= {FOLD_THRESHOLD:g}, the fold detector's "
        "threshold)."
    )
