"""The outcome of ``sigmapi chain``: both routes per seed, their summary, table and JSON form."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sigmapi.config import SOMConfig
from sigmapi.experiments.kit.results import Result, columns, render

__all__ = ["SUMMARY_KEYS", "TARGET_RATIO", "ChainResult"]


TARGET_RATIO = 2.0
"""The acceptance bound of the chain of frames: the chain's z error at most this many times
the single map's."""


SUMMARY_KEYS = ("z_error", "view_consistency", "order_r2", "usage", "weights", "train_seconds")
"""The scores summarised per route (medians over seeds)."""

ROUTES = ("chain", "single")

COLUMNS = columns(
    "seed:<5d route:7s z_error:7.3f view_consistency:12.3f order_r2:10.3f usage:6.2f",
    "weights:8d train_seconds:8.1f",
    view_consistency="same winner",
)
"""The table's columns: one row per seed and route."""


@dataclass
class ChainResult(Result):
    """Both routes per seed (:func:`chain_seed`) and the settings they ran with."""

    config: SOMConfig
    train_pairs: int
    n_test: int
    code: str
    per_seed: list[dict[str, Any]]

    KEYS = ("settings", "seeds: per_seed", "summary")
    """The JSON form: the settings, one dict per seed and the summary."""

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ChainResult:
        """The result that :meth:`to_dict` wrote (``result.json``)."""
        settings = data["settings"]
        config = SOMConfig.from_dict(settings["config"])
        return cls(
            config,
            settings["train_pairs"],
            settings["n_test"],
            settings["code"],
            list(data["seeds"]),
        )

    def summary(self) -> dict[str, Any]:
        """The medians of both routes, the median and worst ratio and how many seeds meet
        ``ratio <= TARGET_RATIO``."""
        per_seed = self.per_seed

        def med(route: str, key: str) -> float:
            return float(np.median([r[route][key] for r in per_seed]))

        ratios = [r["ratio"] for r in per_seed]
        out: dict[str, Any] = {route: {k: med(route, k) for k in SUMMARY_KEYS} for route in ROUTES}
        out.update(
            ratio_median=float(np.median(ratios)),
            ratio_worst=float(max(ratios)),
            met=int(sum(r <= TARGET_RATIO for r in ratios)),
            n_seeds=len(per_seed),
            target_ratio=TARGET_RATIO,
            map_a_order_r2_min=min(r["map_a"]["order_r2"] for r in per_seed),
        )
        return out

    def settings(self) -> dict[str, Any]:
        """The map config, the training pairs, test points, code and the seeds."""
        return {
            "config": self.config.to_dict(),
            "train_pairs": self.train_pairs,
            "n_test": self.n_test,
            "code": self.code,
            "seeds": [r["seed"] for r in self.per_seed],
        }

    def table(self) -> str:
        """Both routes per seed, then the summary line."""
        rows = [{"seed": r["seed"], "route": k, **r[k]} for r in self.per_seed for k in ROUTES]
        s = self.summary()
        return "\n".join(
            [
                *render(COLUMNS, rows),
                f"{s['met']} of {s['n_seeds']} seeds: chain z error <= {s['target_ratio']:g} x "
                f"the single map's (median ratio {s['ratio_median']:.2f}, worst "
                f"{s['ratio_worst']:.2f})",
            ]
        )
