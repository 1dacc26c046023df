"""The outcome of an iCub run: per-seed records, the summaries computed from them, its JSON
form, its table and its figures (:mod:`~sigmapi.experiments.icub.plots`)."""

from __future__ import annotations

import functools
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi.experiments.icub.config import ICubConfig
from sigmapi.experiments.icub.reaching import METHODS
from sigmapi.experiments.kit.results import Column, Result, check_records, columns, render
from sigmapi.metrics import ORDERED_R2

TARGETS: dict[str, float] = {
    "pixel_rms_px": 0.5,
    "eye_frame_ms_median": 10.0,
    "order_r2": ORDERED_R2,
    "chain_error_ratio": 1.5,
    "learned_success": 0.9,
    "learned_over_true": 0.95,
    "learned_minus_retina": 0.3,
}
"""The acceptance bounds the result is checked against (``targets`` in the JSON)."""

SUMMARIES = (
    "maps",
    "success",
    "success_per_seed",
    "babbling_cm",
    "targets",
    "cpu_seconds_per_seed",
)
"""The keys of the JSON form computed from the per-seed records."""

_MAP_KEYS = (
    "order_r2",
    "direction_error_deg",
    "view_consistency",
    "view_within_one",
    "usage",
    "fold_score",
    "folded",
    "starved_units",
    "topographic_error",
)


def _scored(rows: list[dict[str, Any]], true: list[dict[str, Any]]) -> dict[str, object]:
    """A map's scores ``rows`` (one per seed) over the seeds: medians, the worst, how many
    seeds were ordered and flagged, its error over the true-direction map's ``true``."""
    ratio = [
        r["direction_error_deg"] / t["direction_error_deg"] for r, t in zip(rows, true, strict=True)
    ]
    return {
        "order_r2": float(np.median([r["order_r2"] for r in rows])),
        "direction_error_deg": float(np.median([r["direction_error_deg"] for r in rows])),
        "order_r2_worst": float(min(r["order_r2"] for r in rows)),
        "ordered_seeds": int(sum(r["order_r2"] >= ORDERED_R2 for r in rows)),
        "folded_seeds": int(sum(bool(r["folded"]) for r in rows)),
        "error_ratio_to_true_direction": float(np.median(ratio)),
        "error_ratio_worst": float(max(ratio)),
    }


def _per_seed(rows: list[dict[str, Any]]) -> list[dict[str, object]]:
    return [{k: r[k] for k in _MAP_KEYS} for r in rows]


def _degrees(*path: str) -> Callable[[Mapping[str, Any]], str]:
    return lambda m: f"{functools.reduce(operator.getitem, path, m):.2f}d"


MAP_COLUMNS = columns(
    "map:<6 order_r2:>10.3f order_r2_worst:>8.3f",
    Column("dir err", _degrees("direction_error_deg"), ">9"),
    Column("true map", _degrees("true_direction_map", "direction_error_deg"), ">10"),
    Column("cubic fit", _degrees("supervised", "direction_error_deg"), ">11"),
    "folded_seeds:>8d",
    order_r2="order R2",
    folded_seeds="folded",
)
"""The table's columns: one row per map (medians over seeds, in degrees)."""


@dataclass
class ICubResult(Result):
    """Outcome of :meth:`~sigmapi.experiments.icub.run.ICubExperiment.run`: the frames check
    and one record per seed (maps' metrics, babbling curves, reaches)."""

    config: ICubConfig
    seeds: tuple[int, ...]
    frames: dict[str, Any]
    per_seed: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0
    _summary: dict[str, Any] = field(default_factory=dict, repr=False)
    """The summaries of a result read back (:meth:`from_dict`: the file holds them, not the
    per-seed records); None for a run's result."""

    KEYS = (
        "experiment",
        "config",
        "seeds",
        "frames",
        "maps",
        "success",
        "success_per_seed",
        "success_servo: servo",
        "babbling_cm: curves",
        "targets",
        "cpu_seconds_per_seed",
        "seconds",
    )
    """The JSON form: the config, seeds and frames check, the maps' and reaches' summaries,
    the acceptance bounds and whether each is met, the time."""
    COMPUTED = SUMMARIES
    LATER = ("success_servo",)
    experiment = "icub"

    @classmethod
    def from_dict(cls, data: Any) -> Any:
        """The result a :meth:`to_dict` wrote; a file of ``sigmapi icub --space box``
        (``"space": "box"``) reads back as an
        :class:`~sigmapi.experiments.icub.box.ICubBoxResult`."""
        if isinstance(data, Mapping) and data.get("space") == "box":
            from sigmapi.experiments.icub.box import ICubBoxResult

            return ICubBoxResult.from_dict(data)
        return super().from_dict(data)

    def maps(self) -> dict[str, dict[str, Any]]:
        """Per map: the medians over seeds, the per-seed values, the references."""
        out: dict[str, dict[str, Any]] = {}
        for name in ("map1", "map2"):
            rows = [s["maps"][name] for s in self.per_seed]
            true = [r["true_direction_map"] for r in rows]
            out[name] = {
                **_scored(rows, true),
                "true_direction_map": {
                    "order_r2": float(np.median([t["order_r2"] for t in true])),
                    "direction_error_deg": float(
                        np.median([t["direction_error_deg"] for t in true])
                    ),
                },
                "supervised": {
                    "direction_error_deg": float(
                        np.median([r["supervised"]["direction_error_deg"] for r in rows])
                    )
                },
                "per_seed": _per_seed(rows),
            }
            if "exact_map1" in rows[0]:
                # map 2 fed an exact map 1 (maps.exact_map1), and the chain's error over its
                ex = [r["exact_map1"] for r in rows]
                out[name]["exact_map1"] = {**_scored(ex, true), "per_seed": _per_seed(ex)}
                out[name]["error_ratio_to_exact_map1"] = float(
                    np.median(
                        [
                            r["direction_error_deg"] / e["direction_error_deg"]
                            for r, e in zip(rows, ex, strict=True)
                        ]
                    )
                )
        return out

    def success(self) -> dict[str, float]:
        """Per method, the share of all reaches (every seed) that touched the ball."""
        return {
            m: float(np.mean(np.concatenate([s["success"][m] for s in self.per_seed])))
            for m in self.methods()
        }

    def methods(self) -> tuple[str, ...]:
        """The reaching methods of the per-seed records, in :data:`METHODS`' order (a record
        written before ``random_posture`` lacks it)."""
        return tuple(m for m in METHODS if m in self.per_seed[0]["success"])

    def servo(self) -> dict[str, float]:
        """Per associated method, the share of all reaches that touched the ball after the
        learned servo (empty without it)."""
        rows = [s.get("servo", {}) for s in self.per_seed]
        return {m: float(np.mean(np.concatenate([r[m] for r in rows]))) for m in rows[0]}

    def success_per_seed(self) -> dict[str, list[float]]:
        """Per method, the share of each seed's reaches that touched the ball."""
        return {m: [float(np.mean(s["success"][m])) for s in self.per_seed] for m in self.methods()}

    def curves(self) -> dict[str, list[list[float]]]:
        """Per associated method, the babbling curve (babbles, median palm error in cm),
        the median over seeds."""
        out: dict[str, list[list[float]]] = {}
        for m in self.per_seed[0]["curves"]:
            pts = np.array([[e for _, e in s["curves"][m]] for s in self.per_seed])
            ns = [n for n, _ in self.per_seed[0]["curves"][m]]
            out[m] = [
                [float(n), 100.0 * float(e)]
                for n, e in zip(ns, np.median(pts, axis=0), strict=True)
            ]
        return out

    def targets(self) -> dict[str, object]:
        """Each acceptance bound and whether it is met."""
        maps, succ = self.maps(), self.success()
        n = len(self.seeds)
        return {
            "pixel_rms_px": self.frames["pixel_rms_px"] <= TARGETS["pixel_rms_px"],
            "eye_frame_ms_median": (
                self.frames["eye_frame_ms_median"] <= TARGETS["eye_frame_ms_median"]
            ),
            "maps_ordered_all_seeds": all(
                maps[k]["ordered_seeds"] == n and maps[k]["folded_seeds"] == 0 for k in maps
            ),
            "chain_error_ratio": (
                maps["map2"]["error_ratio_to_true_direction"] <= TARGETS["chain_error_ratio"]
            ),
            "learned_success": succ["learned"] >= TARGETS["learned_success"],
            "learned_over_true": (
                succ["learned"] >= TARGETS["learned_over_true"] * succ["true_direction"]
            ),
            "learned_minus_retina": (
                succ["learned"] - succ["retina"] >= TARGETS["learned_minus_retina"]
            ),
            "bounds": TARGETS,
        }

    def cpu_seconds_per_seed(self) -> list[float]:
        return [float(s["cpu_s"]) for s in self.per_seed]

    def table(self) -> str:
        """Console text: frames, maps, reaching."""
        f, maps, succ = self.frames, self.maps(), self.success()
        lines = [
            f"icub: seeds {list(self.seeds)}, {self.seconds:.0f} s",
            f"frames: rendered vs projected retina {f['pixel_rms_px']:.2f} px RMS "
            f"(max {f['pixel_max_px']:.2f}) over {f['scenes']} scenes; 64x64 eye frame "
            f"{f['eye_frame_ms_median']:.2f} ms median",
        ]
        lines += render(MAP_COLUMNS, [{"map": k, **m} for k, m in maps.items()], sep="")
        ex = maps["map2"].get("exact_map1")
        if ex is not None:
            lines.append(
                f"map 2 fed an exact map 1: order R2 {ex['order_r2']:.3f} (worst "
                f"{ex['order_r2_worst']:.3f}), {ex['direction_error_deg']:.2f}d, "
                f"{ex['error_ratio_to_true_direction']:.2f}x the true map's; folded "
                f"{ex['folded_seeds']}"
            )
        lines.append("reach success: " + ", ".join(f"{k} {v:.2f}" for k, v in succ.items()))
        if self.servo():
            loop = ", ".join(f"{k} {v:.2f}" for k, v in self.servo().items())
            lines.append(f"after the learned servo: {loop}")
        return "\n".join(lines)

    def figure(self, out_dir: Path) -> list[Path]:
        """The figures (:func:`~sigmapi.experiments.icub.plots.icub_figures`) and, with
        ``config.render``, the filmed reach as an animated GIF."""
        from sigmapi._outputs import save_gif
        from sigmapi.experiments.icub.plots import icub_figures

        check_records(self.per_seed, "sigmapi icub ... --out DIR")
        paths = icub_figures(self, Path(out_dir))
        film = self.per_seed[0].get("film")
        if self.config.render is not None and film:
            paths.append(save_gif(film, Path(self.config.render), fps=8))
        return paths
