"""The outcome of ``sigmapi stream``: every map's scores, their JSON form (and back), table and
figure."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi._outputs import save_captioned
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.results import Column, Result, columns, render
from sigmapi.experiments.kit.seeds import check_seeds
from sigmapi.experiments.stream.config import (
    StreamConfig,
)

__all__ = ["FIGURE", "METRICS", "MIN_DWELL", "VC_MARGIN", "StreamResult"]


METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "fold_score")
"""The scores of each map (:func:`sigmapi.evaluate`), besides ``folded``."""


VC_MARGIN = 0.02
"""Acceptance: stream learning at ``d >= 4`` within this much view consistency of pairs."""


MIN_DWELL = 4
"""Acceptance: the dwell times it applies to (``d >= MIN_DWELL``)."""


FIGURE = "stream.png"

COLUMNS = columns(
    "name:20s dwell:>5 view_consistency:9.3f view_consistency_worst:6.3f z_error:8.3f",
    "order_r2:9.3f order_r2_worst:6.3f",
    Column("folded", lambda m: f"{m['n_seeds'] - m['ordered']:3d}/{m['n_seeds']:<3d}", ">7s"),
)
"""The table's columns: one row per method and dwell time (medians, worst seeds)."""


def _name(trace: float | None) -> str:
    return "pairs" if trace is None else f"stream trace {trace:g}"


@dataclass
class StreamResult(Result):
    """Every map's scores (:func:`stream_job`) and the settings they ran with."""

    config: StreamConfig
    seeds: tuple[int, ...]
    runs: list[dict[str, Any]]
    seconds: float

    KEYS = ("methods", "acceptance", "settings", "seconds")
    """The JSON form: :meth:`methods`, :meth:`acceptance`, :meth:`settings` and the whole
    run's wall time."""

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StreamResult:
        """The result a :meth:`to_dict` wrote (e.g. read back from ``result.json``)."""
        st = data["settings"]
        config = StreamConfig(
            preset=st["preset"],
            overrides=tuple(st["overrides"]),
            dwells=tuple(st["dwells"]),
            traces=tuple(st["traces"]),
            n_test=st["n_test"],
        )
        seeds = tuple(st["seeds"])
        runs = [
            {
                "seed": seed,
                "dwell": m["dwell"],
                "trace": m["trace"],
                **{k: m["per_seed"][k][i] for k in (*METRICS, "folded", "seconds")},
            }
            for m in data["methods"]
            for i, seed in enumerate(seeds)
        ]
        return cls(config, seeds, runs, float(data["seconds"]))

    @classmethod
    def combine(cls, parts: Sequence[StreamResult]) -> StreamResult:
        """The runs of several results of one config on different seeds, as one result (its
        ``seconds`` the sum of theirs)."""
        if not parts or any(p.config != parts[0].config for p in parts):
            raise ConfigError("results to combine must share one config (and be at least one)")
        seeds = check_seeds([s for p in parts for s in p.seeds], "seeds of the results")
        return cls(
            parts[0].config,
            seeds,
            [r for p in parts for r in p.runs],
            sum(p.seconds for p in parts),
        )

    def _rows(self, trace: float | None, dwell: int | None) -> list[dict[str, Any]]:
        rows = [r for r in self.runs if r["trace"] == trace and r["dwell"] == dwell]
        return sorted(rows, key=lambda r: self.seeds.index(r["seed"]))

    def methods(self) -> list[dict[str, Any]]:
        """One entry per method and dwell time: ``name``, ``dwell`` (None for pairs),
        ``trace``, the median of each metric, its worst seed (``*_worst``: lowest view
        consistency and order, highest z error and fold score), ``fold_rate``, ``ordered``
        (seeds not folded), ``n_seeds`` and ``per_seed`` (the values in seed order)."""
        keys = [(None, None)] + [(t, d) for t in self.config.traces for d in self.config.dwells]
        out = []
        for trace, dwell in keys:
            rows = self._rows(trace, dwell)
            entry: dict[str, Any] = {"name": _name(trace), "dwell": dwell, "trace": trace}
            for k in METRICS:
                vals = [r[k] for r in rows]
                worst = max(vals) if k in ("z_error", "fold_score") else min(vals)
                entry.update({k: float(np.median(vals)), f"{k}_worst": float(worst)})
            folded = [r["folded"] for r in rows]
            entry.update(
                fold_rate=float(np.mean(folded)),
                ordered=int(len(rows) - sum(folded)),
                n_seeds=len(rows),
                per_seed={k: [r[k] for r in rows] for k in (*METRICS, "folded", "seconds")},
            )
            out.append(entry)
        return out

    def acceptance(self) -> dict[str, Any]:
        """Per trace constant and dwell time ``>= MIN_DWELL``: the view consistency of the
        stream minus that of pairs, seed by seed (median, worst), how many seeds are within
        :data:`VC_MARGIN` and ordered, and whether every seed is."""
        pairs = {r["seed"]: r for r in self._rows(None, None)}
        out: dict[str, Any] = {"margin": VC_MARGIN, "min_dwell": MIN_DWELL, "cases": []}
        for trace in self.config.traces:
            for dwell in (d for d in self.config.dwells if d >= MIN_DWELL):
                rows = self._rows(trace, dwell)
                gap = [r["view_consistency"] - pairs[r["seed"]]["view_consistency"] for r in rows]
                met = [g >= -VC_MARGIN and not r["folded"] for g, r in zip(gap, rows, strict=True)]
                out["cases"].append(
                    {
                        "trace": trace,
                        "dwell": dwell,
                        "vc_gap_median": float(np.median(gap)),
                        "vc_gap_worst": float(min(gap)),
                        "met": int(sum(met)),
                        "n_seeds": len(rows),
                        "all_met": bool(all(met)),
                    }
                )
        return out

    def settings(self) -> dict[str, Any]:
        """The config, the seeds and the resolved map config."""
        c = self.config
        return {
            "preset": c.preset,
            "overrides": list(c.overrides),
            "dwells": list(c.dwells),
            "traces": list(c.traces),
            "n_test": c.n_test,
            "seeds": list(self.seeds),
            "config": c.som_config.to_dict(),
        }

    def table(self) -> str:
        """Medians per method and dwell time, then the acceptance lines."""
        rows = render(COLUMNS, self.methods())
        for case in self.acceptance()["cases"]:
            rows.append(
                f"trace {case['trace']:g}, dwell {case['dwell']}: {case['met']} of "
                f"{case['n_seeds']} seeds within {VC_MARGIN} view consistency of pairs and "
                f"ordered (gap median {case['vc_gap_median']:+.3f}, worst "
                f"{case['vc_gap_worst']:+.3f})"
            )
        return "\n".join(rows)

    def caption(self) -> str:
        """The figure's caption, computed from the result."""
        pairs = self.methods()[0]
        n = len(self.seeds)
        best = max(
            self.acceptance()["cases"], key=lambda c: (c["met"], c["vc_gap_median"]), default=None
        )
        text = (
            f"{self.config.preset}, {n} seed{'s' * (n > 1)} ({', '.join(map(str, self.seeds))}): "
            f"view consistency and fold rate of maps learned from a stream in which the object "
            f"stays for d saccades, against explicit pairs (median "
            f"{pairs['view_consistency']:.3f}, {pairs['ordered']} of {n} ordered). Lines: "
            f"medians over seeds; bands: best to worst seed."
        )
        if best is not None:
            text += (
                f" At d >= {MIN_DWELL} the closest is trace {best['trace']:g} at d = "
                f"{best['dwell']}: {best['met']} of {best['n_seeds']} seeds within "
                f"{VC_MARGIN} of pairs and ordered (median gap {best['vc_gap_median']:+.3f})."
            )
        return text

    def figure(self, out_dir: Path) -> list[Path]:
        """``stream.png`` (:func:`.figures.stream_figure`) and its caption beside it,
        ``stream.txt``; returns the figure's path."""
        from .figures import stream_figure  # matplotlib: only when drawing

        out = Path(out_dir) / FIGURE
        return [save_captioned(stream_figure(self.to_dict()), out, self.caption(), dpi=120)]
