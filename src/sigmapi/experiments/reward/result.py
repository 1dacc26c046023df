"""The outcome of a reward-gating comparison: per-episode records and map scores per method
and seed, the summaries computed from them (median, worst, counts over seeds), its JSON form
(``"methods"``: one object per method), its table and its figure."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sigmapi.experiments.kit.episodes import block_rates
from sigmapi.experiments.kit.episodes_result import EpisodesResult
from sigmapi.experiments.reward.config import RewardConfig

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MAGNIFICATION_TARGET = 1.5
"""The gated map's magnification near the goal over the frozen map's that counts as shaped."""

SCORES = ("magnification", "units_near", "units_used", "view_consistency_away", "order_r2_away")
"""The map scores of :func:`~sigmapi.experiments.reward.run.map_scores`, per method and seed."""


def episodes_to_target(success: NDArray[np.bool_], block: int, target: float) -> int | None:
    """Episodes until a block of ``block`` episodes first succeeds at rate ``>= target``: the
    end of that block (blocks ``[0, block)``, ``[block, 2 block)``, ...); None if none does."""
    rates = block_rates(success[None, :], block)[0]
    hit = np.flatnonzero(rates >= target)
    return int((hit[0] + 1) * block) if hit.size else None


def _summary(values: list[float | None], higher: bool = True) -> dict[str, object]:
    """Median and worst over seeds (None, e.g. a target never reached, counts as worst)."""
    known = [v for v in values if v is not None and np.isfinite(v)]
    worst = None if len(known) < len(values) else float(min(known) if higher else max(known))
    filled = [
        v if v is not None and np.isfinite(v) else (-np.inf if higher else np.inf) for v in values
    ]
    med = float(np.median(filled)) if filled else float("nan")
    return {
        "median": med if np.isfinite(med) else None,
        "worst": worst,
        "per_seed": [None if v is None else float(v) for v in values],
    }


@dataclass
class RewardResult(EpisodesResult):
    """Outcome of :meth:`~sigmapi.experiments.reward.run.RewardExperiment.run`.

    Per method ``m``, the episode records of
    :class:`~sigmapi.experiments.kit.episodes_result.EpisodesResult`; ``scores[m][name]``:
    ``(len(seeds),)`` map scores after the episodes (``initial``: the learned map before
    them); ``units[m]``: the preferred z of each unit of the first seed's map ``(n_units,
    d)`` (NaN: wins nothing).
    """

    config: RewardConfig
    updates: dict[str, NDArray[np.int64]] = field(default_factory=dict)
    scores: dict[str, dict[str, NDArray[np.float64]]] = field(default_factory=dict)
    units: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    seconds: float = 0.0

    KEYS = (
        "methods",
        "initial_map",
        "n_seeds",
        "target: config.run.target",
        "magnification_target: MAGNIFICATION_TARGET",
        "curves",
        "config: config_and_seeds",
        "seconds",
    )
    """The JSON form: ``methods``, the map before the episodes (``initial_map``), the
    acceptance counts, the curves, the config (its parts and the seeds) and the time."""
    SEEDS_IN_CONFIG = True
    FIGURE = "reward.png"
    MAGNIFICATION_TARGET = MAGNIFICATION_TARGET

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]:
        """Per method: ``episode`` (block ends), ``success`` (rate per block, mean over
        seeds), ``success_sd``, ``success_min`` and ``success_max`` over seeds."""
        return self.success_curves(extremes=True)

    def methods(self) -> list[dict[str, object]]:
        """Per method its name, final success, episodes to the target rate, magnification
        near the goal and its ratio to the frozen map, the quality away from the goal (median,
        worst and per seed over the seeds)."""
        run = self.config.run
        finals = self.final()
        lost = self.final_share()
        frozen_ep = self._episodes("frozen") if "frozen" in self.success else None
        base_mag = self.scores["initial"]["magnification"]
        summed = ("units_near", "view_consistency_away", "order_r2_away")
        methods = []
        for m in run.methods:
            ep = self._episodes(m)
            mag = self.scores[m]["magnification"]
            ratio = mag / base_mag
            entry: dict[str, object] = {
                "name": m,
                "final_success": _summary(finals[m].tolist()),
                "lost": lost[m],
                "episodes_to_target": _summary(
                    [None if e is None else float(e) for e in ep], higher=False
                ),
                "reached_target": sum(e is not None for e in ep),
                "magnification": _summary(mag.tolist()),
                "magnification_ratio": _summary(ratio.tolist()),
                "magnification_ratio_met": int(np.sum(ratio >= MAGNIFICATION_TARGET)),
                **{k: _summary(self.scores[m][k].tolist()) for k in summed},
                "gated_updates": _summary(self.updates[m].astype(float).tolist()),
            }
            if frozen_ep is not None:
                entry["fewer_episodes_than_frozen"] = sum(
                    _earlier(a, b, run.episodes) for a, b in zip(ep, frozen_ep, strict=True)
                )
            methods.append(entry)
        return methods

    def initial_map(self) -> dict[str, dict[str, object]]:
        """The learned map's scores before the episodes (median, worst, per seed)."""
        return {k: _summary(v.tolist()) for k, v in self.scores["initial"].items()}

    def n_seeds(self) -> int:
        return len(self.seeds)

    def _episodes(self, m: str) -> list[int | None]:
        run = self.config.run
        return [episodes_to_target(s, run.block, run.target) for s in self.success[m]]

    def table(self) -> str:
        """Per method: final success, episodes to the target, magnification, away quality."""
        d = self.to_dict()
        lines = [
            f"{len(self.seeds)} seeds; median (worst) over seeds; target success "
            f"{d['target']:.0%} per block of {self.config.run.block}"
        ]
        for e in d["methods"]:
            et = e["episodes_to_target"]
            lines.append(
                f"  {e['name']:9s} final {_fmt(e['final_success'])}  episodes to target "
                f"{_fmt(et, 0)} reached {e['reached_target']}/{d['n_seeds']}  magnification "
                f"{_fmt(e['magnification'])} ratio {_fmt(e['magnification_ratio'])}  away: "
                f"consistency {_fmt(e['view_consistency_away'])} order "
                f"{_fmt(e['order_r2_away'])}"
            )
        return "\n".join(lines)

    def draw(self) -> Figure:
        """The comparison (:func:`~sigmapi.experiments.reward.figures.reward_figure`)."""
        from sigmapi.experiments.reward.figures import reward_figure  # matplotlib: only to draw

        return reward_figure(self)

    def caption(self) -> str:
        """The figure's caption, computed from the result."""
        from sigmapi.experiments.reward.figures import LABELS, drawn_units

        d, run = self.to_dict(), self.config.run
        n = len(self.seeds)
        final = ", ".join(
            f"{LABELS.get(e['name'], e['name'])} {_fmt(e['final_success'])}" for e in d["methods"]
        )
        text = (
            f"Gaze-and-reach, seed{'s' * (n > 1)} {', '.join(map(str, self.seeds))}: success "
            f"rate per block of {run.block} episodes (mean over seeds; band: min-max over "
            f"seeds), dotted: the target rate {run.target:.0%}. Final success over the last "
            f"{run.final_episodes} of {run.episodes} episodes, median (worst seed): {final}."
        )
        shown = drawn_units(self)
        if shown:
            mags = ", ".join(
                f"{LABELS.get(e['name'], e['name'])} x{e['magnification']['median']:.2f}"
                for e in d["methods"]
                if e["name"] in shown
            )
            text += (
                f" Right, seed {self.seeds[0]}, per method: each dot a unit at its preferred z, "
                "map neighbours, joined (grey lines); the goal (grey box) and the region near the "
                "goal (dashed), whose units the magnification counts (units per area near the "
                f"goal over units per area overall; median over seeds: {mags})."
            )
        return text


def _earlier(a: int | None, b: int | None, never: int) -> bool:
    """Whether ``a`` episodes is fewer than ``b`` (None: never, after ``never``)."""
    return (never + 1 if a is None else a) < (never + 1 if b is None else b)


def _fmt(s: dict[str, object], digits: int = 2) -> str:
    med, worst = s["median"], s["worst"]
    show = lambda v: "never" if v is None else f"{v:.{digits}f}"  # noqa: E731
    return f"{show(med)} ({show(worst)})"
