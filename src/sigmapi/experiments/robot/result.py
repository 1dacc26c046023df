"""The outcome of a robot run: per-episode records, the map's metrics, the rates and curves
computed from them, its JSON form, its table and its figures."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import ActorCritic
from sigmapi.experiments.kit.episodes_result import EpisodesResult
from sigmapi.experiments.kit.results import JSON, as_object, summaries
from sigmapi.experiments.robot.config import RobotConfig
from sigmapi.model.som import SigmaPiSOM


def _summary(values: NDArray[np.float64]) -> dict[str, float]:
    return {
        "mean": float(np.mean(values)),
        "median": float(np.median(values)),
        "min": float(np.min(values)),
    }


def _nan_stat(
    fn: Callable[[NDArray[np.float64]], float], values: NDArray[np.float64]
) -> float | None:
    return float(fn(values)) if np.any(np.isfinite(values)) else None


@dataclass
class RobotResult(EpisodesResult):
    """Outcome of :meth:`~sigmapi.experiments.robot.variant.RobotExperiment.run`.

    Per state, the episode records of
    :class:`~sigmapi.experiments.kit.episodes_result.EpisodesResult` (``success``: the hand
    touched the ball, ``info["is_success"]``) and ``docked[state]``, of the same shape:
    whether the base docked. ``map_metrics`` and ``unit_z`` (each unit's preferred z) per
    seed; ``model`` and ``agent``: the first seed's map and its learner (for the figures).
    """

    config: RobotConfig
    docked: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    map_metrics: list[JSON] = field(default_factory=list)
    unit_z: list[NDArray[np.float64]] = field(default_factory=list)
    model: SigmaPiSOM | None = None
    agent: ActorCritic | None = None
    seconds: float = 0.0
    _film: list[NDArray[np.uint8]] | None = field(default=None, repr=False)

    KEYS = (
        "*map_summary",
        "success: final_mean",
        "success_per_seed: final",
        "success_summary",
        "docked: docked_mean",
        "reach_given_docked: reach_given_docked_mean",
        "reach_given_docked_min",
        "ratio_map_to_true_z",
        "margins",
        "curves: success_curves",
        "map_metrics",
        "config",
        "seeds",
        "seconds",
    )
    """The JSON form: the maps' metrics (keys of ``sigmapi evaluate``), ``success`` per state
    (final, mean over seeds) with its median and worst seed, docking, the reach given
    docking, the map's margins over the other states, the curves and the config."""

    @classmethod
    def from_dict(cls, data: object) -> RobotResult:
        """The result a :meth:`to_dict` wrote (``result.json``): its config, seeds, maps'
        metrics and time, and its summaries as written (the file holds no episode records;
        the maps' summary has the keys of their metrics)."""
        obj = as_object(data)
        values = cls.read_fields(obj)
        metrics = [dict(as_object(m, "map_metrics entry")) for m in obj["map_metrics"]]
        mapped = (*metrics[0], "order_r2_min", "folded_seeds") if metrics else ()
        return cls(
            **{**values, "map_metrics": metrics}, written=summaries(obj, (*mapped, *cls.COMPUTED))
        )

    def reach_given_docked(self) -> dict[str, NDArray[np.float64]]:
        """Per state and seed, the share of the last ``final_episodes`` docked episodes in
        which the hand touched the ball (NaN for a seed that docked in none)."""
        success = self.window()
        out = {}
        for s, d in self.window("docked").items():
            n = d.sum(axis=1)
            hit = (success[s] & d).sum(axis=1)
            out[s] = np.where(n > 0, hit / np.maximum(n, 1), np.nan)
        return out

    def map_summary(self) -> dict[str, object]:
        """The maps' metrics with the keys of ``sigmapi evaluate`` (means over seeds;
        ``folded``: any seed folded), ``order_r2_min`` and ``folded_seeds``."""
        if not self.map_metrics:
            return {}
        out: dict[str, object] = {}
        for k, v in self.map_metrics[0].items():
            vals = [m[k] for m in self.map_metrics]
            out[k] = any(vals) if isinstance(v, bool) else float(np.mean(vals))
        out["order_r2_min"] = float(min(m["order_r2"] for m in self.map_metrics))
        out["folded_seeds"] = int(sum(bool(m["folded"]) for m in self.map_metrics))
        return out

    def success_summary(self) -> dict[str, dict[str, float]]:
        return {s: _summary(v) for s, v in self.final().items()}

    def docked_mean(self) -> dict[str, float]:
        """Per state, the final docking rate (mean over seeds)."""
        return self.final_mean("docked")

    def reach_given_docked_mean(self) -> dict[str, float | None]:
        return {s: _nan_stat(np.nanmean, v) for s, v in self.reach_given_docked().items()}

    def reach_given_docked_min(self) -> dict[str, float | None]:
        return {s: _nan_stat(np.nanmin, v) for s, v in self.reach_given_docked().items()}

    def margins(self) -> dict[str, dict[str, float]]:
        """The map's final success minus the retina's and the retina-and-gaze's, per seed."""
        final = self.final()
        if "map" not in final:
            return {}
        others = [s for s in ("retina", "retina_gaze") if s in final]
        return {f"map_minus_{s}": _summary(final["map"] - final[s]) for s in others}

    def ratio_map_to_true_z(self) -> dict[str, float] | None:
        """The map's final success over the true z's (per seed; ``mean``: of the means)."""
        final, success = self.final(), self.final_mean()
        if "map" not in success or not success.get("true_z"):
            return None
        per_seed = _summary(final["map"] / np.maximum(final["true_z"], 1e-12))
        return {**per_seed, "mean": success["map"] / success["true_z"]}

    def table(self) -> str:
        """A few lines for a terminal."""
        d = self.to_dict()
        lines = []
        if self.map_metrics:
            lines.append(
                f"map ({len(self.seeds)} seeds): order R^2 {d['order_r2']:.3f} "
                f"(min {d['order_r2_min']:.3f}), within one {d['view_within_one']:.3f}, "
                f"fold score {d['fold_score']:.2f}, folded {d['folded_seeds']}"
            )
        lines.append(
            f"final success over the last {self.config.run.final_episodes} of "
            f"{self.config.run.episodes} episodes:"
        )
        for s, v in d["success"].items():
            seeds = " ".join(f"{x:.2f}" for x in d["success_per_seed"][s])
            reach = d["reach_given_docked"][s]
            lines.append(
                f"  {s:12s} {v:.3f}  docked {d['docked'][s]:.3f}  reach|docked "
                f"{'-' if reach is None else f'{reach:.3f}'}   per seed: {seeds}"
            )
        if d["ratio_map_to_true_z"] is not None:
            lines.append(f"  map / true_z = {d['ratio_map_to_true_z']['mean']:.3f}")
        return "\n".join(lines)

    def film(self) -> list[NDArray[np.uint8]]:
        """Frames of one episode of the first seed's map learner (rendered once, then kept;
        :func:`~sigmapi.experiments.robot.figures.film_episode`)."""
        if self._film is None:
            from sigmapi.experiments.robot.figures import film_episode

            self._film = film_episode(self)
        return self._film

    def figure(self, out_dir: str | Path) -> list[Path]:
        """Write the figures into ``out_dir`` (:func:`~sigmapi.experiments.robot.figures.
        robot_figures`: the map on the table, the learning curves, a film strip) and, with
        ``config.run.render``, the filmed episode as an animated GIF at that path."""
        from sigmapi._outputs import save_gif
        from sigmapi.experiments.robot.figures import robot_figures

        folder = Path(out_dir)
        folder.mkdir(parents=True, exist_ok=True)
        paths = robot_figures(self, folder, self.film())
        if self.config.run.render is not None and self.film():
            paths.append(save_gif(self.film(), Path(self.config.run.render), fps=6))
        return paths
