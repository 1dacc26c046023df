"""The sweep's summary figure: a metric against the first grid parameter."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Protocol

from sigmapi import _validate
from sigmapi._outputs import save_figure
from sigmapi.analysis.circular import CIRCULAR_KEYS
from sigmapi.experiments.sweep.table import METRIC_COLUMNS

__all__ = ["METRICS", "draw_summary"]

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
    median and spread over seeds, folded runs marked; written to ``path``."""
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
    save_figure(fig, p, dpi=120, bbox_inches="tight", facecolor="white")
    plt.close(fig)
    return p
