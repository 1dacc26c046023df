"""The outcome of ``sigmapi compare``: every method's scores, their JSON form, table and figure."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi._outputs import save_captioned
from sigmapi.experiments.compare.config import (
    METHODS,
    SEEDS,
    CompareConfig,
)
from sigmapi.experiments.kit.results import Result, columns, render
from sigmapi.metrics import grid_spacing
from sigmapi.model.som import SigmaPiSOM

__all__ = ["FIGURE", "MATCH_SHARE", "CompareResult", "MethodScore"]


FIGURE = "compare.png"
"""The comparison's figure in its output folder (its caption beside it, ``compare.txt``)."""


MATCH_SHARE = 1.1
"""labels needed: the z error within this factor of the error with all labels."""

COLUMNS = columns(
    "name:24s view_consistency:10.3f unit_consistency:9.3f z_error:8.3f labels_used:7d",
    "labels_needed:7d labels_to_match_sigma_pi:>8",
    view_consistency="same place",
    unit_consistency="same unit",
    labels_used="labels",
    labels_needed="needed",
    labels_to_match_sigma_pi="to match",
)
"""The table's columns: one row per method (medians over seeds)."""


@dataclass
class MethodScore:
    """One method's scores over seeds (lists in the order of the seeds)."""

    name: str
    view_consistency: list[float] = field(default_factory=list)
    unit_consistency: list[float] = field(default_factory=list)
    z_error_by_labels: list[dict[int, float]] = field(default_factory=list)
    seconds: list[float] = field(default_factory=list)

    def median_curve(self) -> dict[int, float]:
        """Median z error over seeds per number of labels."""
        keys = self.z_error_by_labels[0]
        return {n: float(np.median([c[n] for c in self.z_error_by_labels])) for n in keys}

    @property
    def z_error(self) -> float:
        curve = self.median_curve()
        return curve[max(curve)]

    def labels_needed(self) -> int:
        curve = self.median_curve()
        return min(n for n, e in curve.items() if e <= MATCH_SHARE * self.z_error)

    def labels_to_match(self, target: float) -> int | None:
        hits = [n for n, e in self.median_curve().items() if e <= MATCH_SHARE * target]
        return min(hits) if hits else None


@dataclass
class CompareResult(Result):
    """Scores of every method (:class:`MethodScore`) and the run's settings. A result read
    back from its JSON form (:meth:`from_dict`) holds no scores per seed and number of
    labels: its summaries are ``written``, as the file has them."""

    config: CompareConfig
    scores: dict[str, MethodScore] = field(default_factory=dict)
    seconds: float = 0.0
    seeds: tuple[int, ...] = SEEDS
    """The seeds, in the order of the scores' lists."""
    written: dict[str, Any] | None = field(default=None, repr=False)
    """The summaries of a result read back (:meth:`from_dict`); None for a run's result."""

    KEYS = (
        "methods",
        "config: config_json",
        "z_error_unit",
        "quantisation_floor: floor",
        "seconds",
    )
    """The JSON form: ``methods`` (name, view consistency, z error, labels used, ...), the
    config with its seeds and labels, the z error's unit and its quantisation floor."""
    COMPUTED = ("methods", "z_error_unit", "quantisation_floor")
    SEEDS_IN_CONFIG = True
    z_error_unit = "input grid spacings"

    @property
    def reference(self) -> MethodScore:
        return self.scores["sigma-pi"]

    @property
    def floor(self) -> float:
        """z error of the best decoder that sees only the winner of a map of this size.

        z uniform over the relation's range, cut into ``map_shape`` equal cells per axis: the
        error of the cell's centre is ``cell width / sqrt(12)`` per axis (in grid spacings).
        """
        som_cfg = self.config.som_config
        lo, hi = SigmaPiSOM(som_cfg).sampler.relation.z_range
        spacing = grid_spacing(som_cfg.x_shape, som_cfg.periodic)
        width = (hi - lo) / np.asarray(som_cfg.map_shape, dtype=np.float64)
        return float(np.sqrt(np.sum((width * spacing) ** 2 / 12.0)))

    def config_json(self) -> dict[str, Any]:
        """The config's fields, the seeds after its preset and overrides, and its labels."""
        cfg = dataclasses.asdict(self.config)
        head = {"preset": cfg.pop("preset"), "overrides": cfg.pop("overrides")}
        return {**head, "seeds": list(self.seeds), **cfg, "labels": list(self.config.labels)}

    def methods(self) -> list[dict[str, Any]]:
        """Per method its medians over seeds, the labels it used and needed (and to match
        the Sigma-Pi map's z error), its z error by labels and its values per seed."""
        target = self.reference.z_error
        labels_used = max(self.config.labels)
        methods = []
        for name, s in self.scores.items():
            curve = s.median_curve()
            methods.append(
                {
                    "name": name,
                    "description": METHODS[name],
                    "view_consistency": float(np.median(s.view_consistency)),
                    "unit_consistency": float(np.median(s.unit_consistency)),
                    "z_error": s.z_error,
                    "labels_used": labels_used,
                    "labels_needed": s.labels_needed(),
                    "labels_to_match_sigma_pi": s.labels_to_match(target),
                    "z_error_by_labels": {str(n): e for n, e in curve.items()},
                    "per_seed": {
                        "view_consistency": s.view_consistency,
                        "unit_consistency": s.unit_consistency,
                        "z_error": [c[labels_used] for c in s.z_error_by_labels],
                        "seconds": s.seconds,
                    },
                }
            )
        return methods

    def table(self) -> str:
        """The comparison as a plain-text table (medians over seeds)."""
        shape = "x".join(map(str, self.config.som_config.map_shape))
        return "\n".join(
            [
                *render(COLUMNS, self.to_dict()["methods"]),
                f"z error in grid spacings; a map's winner alone cannot beat {self.floor:.3f} "
                f"(z cut into {shape} cells)",
            ]
        )

    def figure(self, out_dir: Path) -> list[Path]:
        """``compare.png`` (:func:`.figures.compare_figure`) and its caption beside it,
        ``compare.txt``; returns the figure's path."""
        from .figures import compare_figure  # matplotlib: only when drawing

        out = Path(out_dir) / FIGURE
        return [save_captioned(compare_figure(self.to_dict()), out, self.caption(), dpi=120)]

    def caption(self) -> str:
        """A caption computed from the result."""
        cfg, ref = self.config, self.reference
        n = len(self.seeds)
        parts = [
            f"{cfg.preset} task, {cfg.train_pairs:,} recorded view pairs per seed, median of {n} "
            f"seed{'s' * (n > 1)}. The Sigma-Pi map puts both views of one z on the same unit "
            f"in {np.median(ref.view_consistency):.2f} of test cases, z error "
            f"{ref.z_error:.2f} grid spacings (a winner alone cannot beat {self.floor:.2f}) with "
            f"its units named by {ref.labels_needed()} labels (within 10 % of its error with "
            "all of them)."
        ]
        for name, s in self.scores.items():
            if name == "sigma-pi":
                continue
            match = s.labels_to_match(ref.z_error)
            reach = (
                f"comes within 10 % of the map's z error with {match:,} labels"
                if match is not None
                else f"not within 10 % of the map's z error with {max(cfg.labels):,} labels"
            )
            parts.append(
                f"{name}: same place {np.median(s.view_consistency):.2f}, z error "
                f"{s.z_error:.2f}, {reach}."
            )
        return " ".join(parts)
