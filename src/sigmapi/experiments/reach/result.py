"""The outcome of a reach comparison: per-episode records, the curves and rates computed from
them, its JSON form, its table and its figure."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sigmapi.experiments.kit.episodes_result import EpisodesResult
from sigmapi.experiments.reach.config import ReachConfig

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass
class ReachResult(EpisodesResult):
    """Outcome of :meth:`~sigmapi.experiments.reach.run.ReachExperiment.run`.

    Per state, the episode records of
    :class:`~sigmapi.experiments.kit.episodes_result.EpisodesResult` (``success``: reached
    the goal; ``lost``: lost the object); ``values[state]`` is the critic's value over z (the
    first seed), on ``z_axis``.
    """

    config: ReachConfig
    values: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    z_axis: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    map_metrics: list[dict[str, float | int]] = field(default_factory=list)
    seconds: float = 0.0

    KEYS = (
        "success: final_success",
        "success_per_seed: final",
        "lost: final_share",
        "timed_out: final_timed_out",
        "ratio_map_to_true_z",
        "final_rise",
        "final_rise_se",
        "levelled_off",
        "curves",
        "map_metrics",
        "config: config_and_seeds",
        "seconds",
    )
    """The JSON form: final success (mean and per seed), lost and timed-out shares, the rise
    over the final episodes and whether each learner levelled off, the curves (NaN: None),
    the maps' metrics, the config (its parts and the seeds) and the time."""
    LATER = ("final_rise", "final_rise_se", "levelled_off")
    SEEDS_IN_CONFIG = True
    FIGURE = "reach.png"

    def final_success(self) -> dict[str, float]:
        """Success rate over the last ``final_episodes`` episodes, mean over seeds."""
        return self.final_mean()

    def final_timed_out(self) -> dict[str, float]:
        """Fraction of the last ``final_episodes`` episodes that neither reached nor lost the
        object (seed mean), counted (not ``1 - success - lost``, which rounds to -1e-17)."""
        lost = self.window("lost")
        return {s: float((~w & ~lost[s]).mean()) for s, w in self.window().items()}

    def final_rise_per_seed(self) -> dict[str, NDArray[np.float64]]:
        """How much the success rate still rose over the last ``final_episodes`` episodes:
        per state and seed, the change across that window of a least-squares line through
        the episodes' outcomes (1 reached, 0 not), ``(len(seeds),)``."""
        f = self.config.run.final_episodes
        t = np.arange(f, dtype=np.float64) - (f - 1) / 2.0
        denom = float(t @ t)
        out = {}
        for s, w in self.window().items():
            y = w.astype(np.float64)
            slope = (y @ t) / denom if denom > 0 else np.zeros(len(y))
            out[s] = slope * (f - 1)
        return out

    def final_rise(self) -> dict[str, float]:
        """:meth:`final_rise_per_seed`, mean over seeds (the rise of the seeds' mean curve)."""
        return {s: float(v.mean()) for s, v in self.final_rise_per_seed().items()}

    def final_rise_se(self) -> dict[str, float | None]:
        """The standard error of :meth:`final_rise` over seeds (None with one seed): the
        rise of a learner that has levelled off scatters around 0 by about this much."""
        return {
            s: float(v.std(ddof=1) / np.sqrt(len(v))) if len(v) > 1 else None
            for s, v in self.final_rise_per_seed().items()
        }

    def still_rising(self) -> list[str]:
        """The states whose success rate had not levelled off at the last episode: a rise of
        at least ``plateau_rise`` over the last ``final_episodes`` (:meth:`final_rise`), so
        that their final rate is the episode budget's as much as the state's."""
        limit = self.config.run.plateau_rise
        return [s for s, r in self.final_rise().items() if r >= limit]

    def ratio_map_to_true_z(self) -> float | None:
        """Final success of the map over that of the true z (None without both or at 0)."""
        final = self.final_success()
        if "map" in final and "true_z" in final and final["true_z"] > 0:
            return final["map"] / final["true_z"]
        return None

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]:
        """Per state: ``episode`` (block ends), ``success`` and ``steps_to_reach`` per block.

        Each is ``(n_blocks,)`` mean over seeds, with ``success_sd`` the standard deviation
        over seeds; steps to reach average the successful episodes only (NaN when none), and
        ``steps_q25`` / ``steps_q75`` are the quartiles over the seeds of each seed's mean
        (the seeds with a success in the block; NaN when none has one).
        """
        b = self.config.run.block
        out = self.success_curves()
        for s, curve in out.items():
            succ, steps = self.success[s], self.steps[s].astype(np.float64)
            nb = succ.shape[1] // b
            sb = succ[:, : nb * b].reshape(succ.shape[0], nb, b)
            tb = steps[:, : nb * b].reshape(succ.shape[0], nb, b)
            with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # a block without a success
                reach_steps = np.where(sb, tb, 0.0).sum(axis=2) / sb.sum(axis=2)
                mean = np.nanmean(reach_steps, axis=0)
                q25, q75 = np.nanpercentile(reach_steps, (25, 75), axis=0)
            curve.update(steps_to_reach=mean, steps_q25=q25, steps_q75=q75)
        return out

    def levelled_off(self) -> dict[str, bool]:
        """Per state, whether its learner levelled off (:meth:`still_rising`)."""
        return {s: s not in self.still_rising() for s in self.success}

    def table(self) -> str:
        """The final success of each state as lines of text (per seed, and the lost share)."""
        run = self.config.run
        per_seed = self.final()
        lost, rise, se = self.final_share(), self.final_rise(), self.final_rise_se()
        lines = [
            f"final success rate over the last {run.final_episodes} of {run.episodes} "
            f"episodes, {len(self.seeds)} seeds:"
        ]
        for s, v in self.final_success().items():
            seeds = " ".join(f"{x:.3f}" for x in per_seed[s])
            spread = "" if se[s] is None else f" +- {se[s]:.3f}"
            lines.append(
                f"  {s:12s} {v:.3f}   per seed: {seeds}   (lost {lost[s]:.3f}, "
                f"rise {rise[s]:+.3f}{spread})"
            )
        ratio = self.ratio_map_to_true_z()
        if ratio is not None:
            lines.append(f"  map / true_z = {ratio:.3f}")
        lines.append(
            f"  rise: the change of the success rate across those episodes (a line "
            "fitted per seed; +- its standard error over seeds); "
            f"{self.levelling_note()}"
        )
        return "\n".join(lines)

    def levelling_note(self) -> str:
        """One sentence, from the data: which learners had not levelled off at the last
        episode (:meth:`still_rising`), or that all had."""
        run, rising = self.config.run, self.still_rising()
        window = f"over the last {run.final_episodes} of {run.episodes} episodes"
        if not rising:
            return f"every learner levelled off (rise < {run.plateau_rise:g} {window})"
        return (
            f"not levelled off (rise >= {run.plateau_rise:g} {window}): {', '.join(rising)}; "
            "their final rates are the episode budget's as much as the state's (--episodes)"
        )

    def draw(self) -> Figure:
        """The comparison (:func:`~sigmapi.experiments.reach.figures.reach_figure`)."""
        from sigmapi.experiments.reach.figures import reach_figure  # matplotlib: only to draw

        return reach_figure(self)

    def caption(self) -> str:
        """The figure's caption, computed from the result."""
        from sigmapi.experiments.reach.figures import LABELS, coinciding_curves

        run, env = self.config.run, self.config.env
        n = len(self.seeds)
        final = ", ".join(f"{LABELS.get(s, s)} {v:.2f}" for s, v in self.final_success().items())
        goal = "white square" if env.dim == 2 else "grey band"
        text = (
            f"Gaze-and-reach, {env.dim}-D, seed{'s' * (n > 1)} "
            f"{', '.join(map(str, self.seeds))}: the actor-critic's success rate per block of "
            f"{run.block} episodes (mean over seeds; band: 1 sd over seeds) and its steps to "
            f"reach (band: the quartiles over seeds), one line per state it reads. Final "
            f"success over the last {run.final_episodes} of {run.episodes} episodes: {final}; "
            f"{self.levelling_note()}. Bottom: the critic's value over z after training "
            f"(seed {self.seeds[0]}), the goal region a {goal}."
        )
        for metric, same in coinciding_curves(self).items():
            for state, other in same.items():
                text += (
                    f" The {metric} curves of {LABELS.get(state, state)} and "
                    f"{LABELS.get(other, other)} coincide at every block (drawn with markers "
                    "of decreasing size, so both show)."
                )
        return text
