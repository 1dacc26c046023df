"""The robot experiment: the map learned from the body's own saccades, then docking on it.

Per seed, everything random comes from one :class:`numpy.random.SeedSequence` of the seed:
child 0 the map's training views and weights, child 1 the episodes' start states (the same
for every state: same learner, same episodes), child 2 the learner's action choices. The map
is scored on evaluation pairs drawn from :data:`~sigmapi.metrics.EVAL_SEED` (the same for
every seed, never moved). Then the actor-critic of the authors' docking model learns on each
state (:data:`~sigmapi.robot.states.STATES`) through ``gymnasium.make`` and the wrappers.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.executor import run_jobs
from sigmapi.metrics import EVAL_SEED
from sigmapi.reach.agent import ActorCritic
from sigmapi.robot.mapping import robot_som_config, score_map
from sigmapi.robot.states import STATES, make_state
from sigmapi.robot.views import RobotViewBatch, RobotViews
from sigmapi.som import SigmaPiSOM

__all__ = ["ENV_ID", "QUICK", "RobotConfig", "RobotResult", "run_robot"]

ENV_ID = "sigmapi/RobotDock-v0"
Progress = Callable[[int, str], None]


@dataclass(frozen=True)
class RobotConfig:
    """Everything one robot run depends on (the CLI's options are its fields)."""

    grid: int = 12
    """Units per axis of the retina and gaze codes."""
    code_width: float = 1.0
    """Width of the codes' hills, grid units."""
    map_shape: tuple[int, ...] = (8, 8)
    """Grid of the Sigma-Pi map."""
    map_pairs: int = 10_000
    """View pairs recorded from saccades for the map (body and ball still)."""
    map_iterations: int = 40_000
    """Learning iterations of the map (the pairs are used in passes)."""
    moved_share: float = 0.0
    """Share of recorded pairs in which the ball moved between the two views."""
    eval_pairs: int = 3000
    """Calibration and test pairs (each) that score the map against the true z."""
    retina: str = "projection"
    """Retinal position in the docking episodes: "projection" or "pixels" (slow)."""
    saccade_rate: float = 1.0
    """Probability of a saccade per docking step (1: the head looks around every step)."""
    max_steps: int = 100
    """Time limit of a docking episode (gymnasium's TimeLimit)."""
    episodes: int = 400
    """Docking episodes per seed and state."""
    final_episodes: int = 100
    """Final success is measured over this many last episodes."""
    block: int = 50
    """Episodes per point of the learning curves."""
    gamma: float = 0.9
    """Discount (the authors' docking: 0.9)."""
    critic_lr: float = 0.1
    """Critic's learning rate (the authors: 0.1)."""
    actor_lr: float = 0.1
    """Actor's learning rate (the authors: 0.1)."""
    beta: float = 2.0
    """Inverse temperature of the softmax (the authors: 2)."""
    states: tuple[str, ...] = STATES
    """States compared: map, retina, retina_gaze, true_z."""

    def __post_init__(self) -> None:
        for name in ("map_pairs", "map_iterations", "eval_pairs", "episodes", "final_episodes",
                     "block", "max_steps"):  # fmt: skip
            object.__setattr__(self, name, _validate.integer(name, getattr(self, name), 1))
        if self.final_episodes > self.episodes:
            raise ConfigError(
                f"final_episodes must be <= episodes ({self.episodes}), got {self.final_episodes}"
            )
        states = tuple(self.states)
        if not states or any(s not in STATES for s in states) or len(set(states)) != len(states):
            raise ConfigError(f"states must be distinct names from {STATES}, got {states!r}")
        object.__setattr__(self, "states", states)
        object.__setattr__(self, "map_shape", tuple(int(n) for n in self.map_shape))
        _validate.number("moved_share", self.moved_share, 0.0, 1.0)

    def replace(self, **changes: Any) -> RobotConfig:
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v
                for k, v in dataclasses.asdict(self).items()}  # fmt: skip


QUICK = RobotConfig(map_pairs=3000, map_iterations=12_000, eval_pairs=1000, episodes=150,
                    final_episodes=50, block=25)  # fmt: skip
"""``sigmapi robot --quick``: a smaller map run and fewer episodes (minutes, not tens)."""


def _child(seed: int, k: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k,)))


def evaluation_pairs(config: RobotConfig) -> tuple[RobotViewBatch, RobotViewBatch]:
    """Calibration and test pairs (unmoved) from :data:`EVAL_SEED`, the same for every seed."""
    source = RobotViews(config.grid, config.code_width)
    cal, test = (np.random.default_rng(s) for s in np.random.SeedSequence(EVAL_SEED).spawn(2))
    return source.sample_views_with_z(config.eval_pairs, cal), source.sample_views_with_z(
        config.eval_pairs, test
    )


def learn_map(config: RobotConfig, seed: int) -> tuple[SigmaPiSOM, RobotViewBatch]:
    """The map of one seed: ``map_pairs`` recorded view pairs, ``fit(views)``."""
    rng = _child(seed, 0)
    source = RobotViews(config.grid, config.code_width, moved_share=config.moved_share)
    train = source.sample_views_with_z(config.map_pairs, rng)
    som_seed = int(rng.integers(0, 2**31 - 1))
    cfg = robot_som_config(config.grid, config.map_shape, config.map_iterations, som_seed,
                           config.code_width)  # fmt: skip
    return SigmaPiSOM(cfg).fit(train.views), train


def make_env(config: RobotConfig, **kwargs: Any) -> gym.Env[Any, Any]:
    """The docking environment of ``config`` through ``gymnasium.make`` (TimeLimit included)."""
    return gym.make(ENV_ID, grid=config.grid, code_width=config.code_width,
                    retina=config.retina, saccade_rate=config.saccade_rate,
                    max_episode_steps=config.max_steps, **kwargs)  # fmt: skip


def run_episodes(
    config: RobotConfig, state: str, model: SigmaPiSOM | None, seed: int
) -> tuple[dict[str, NDArray[Any]], ActorCritic]:
    """One learner on ``state``: per episode ``success``, ``docked``, ``steps``."""
    env = make_state(make_env(config), state, model)
    n_features = int(np.prod(env.observation_space.shape or (1,)))
    agent = ActorCritic(n_features, 4, config.gamma, config.critic_lr, config.actor_lr,
                        config.beta, seed=_child(seed, 2))  # fmt: skip
    starts = _child(seed, 1).integers(0, 2**31 - 1, size=config.episodes)
    out = {k: np.zeros(config.episodes, dtype=t)
           for k, t in (("success", bool), ("docked", bool), ("steps", np.int64))}  # fmt: skip
    for ep, start in enumerate(starts):
        phi, info = env.reset(seed=int(start))
        t = 0
        while True:
            a = agent.act(phi)
            phi2, r, terminated, truncated, info = env.step(a)
            agent.update(phi, a, float(r), phi2, terminated)
            phi, t = phi2, t + 1
            if terminated or truncated:
                break
        out["success"][ep], out["docked"][ep], out["steps"][ep] = (
            info["is_success"],
            info["docked"],
            t,
        )
    env.close()
    return out, agent


@dataclass(frozen=True)
class _SeedJob:
    config: RobotConfig
    seed: int
    evaluation: tuple[RobotViewBatch, RobotViewBatch] | None


def _run_seed(job: _SeedJob) -> dict[str, Any]:
    cfg = job.config
    out: dict[str, Any] = {"runs": {}, "map_metrics": None, "unit_z": None}
    model = None
    if "map" in cfg.states or "true_z" in cfg.states:
        model, _ = learn_map(cfg, job.seed)
        cal, test = job.evaluation or evaluation_pairs(cfg)
        out["map_metrics"] = score_map(model, cal, test)
        wc = model.winner(cal.x0, cal.y0, hard=True)
        out["unit_z"] = np.array(
            [cal.z[wc == k].mean(axis=0) if np.any(wc == k) else np.full(2, np.nan)
             for k in range(model.n_units)]
        )  # fmt: skip
        out["model"] = model
    for s in cfg.states:
        out["runs"][s], agent = run_episodes(cfg, s, model, job.seed)
        if s == "map":
            out["agent"] = agent
    return out


@dataclass
class RobotResult:
    """Outcome of :func:`run_robot`: per state ``(seeds, episodes)`` arrays, map metrics per
    seed, each unit's preferred z (seed order), and the first seed's map."""

    config: RobotConfig
    seeds: tuple[int, ...]
    runs: dict[str, dict[str, NDArray[Any]]] = field(default_factory=dict)
    map_metrics: list[dict[str, Any]] = field(default_factory=list)
    unit_z: list[NDArray[np.float64]] = field(default_factory=list)
    model: SigmaPiSOM | None = None
    agent: ActorCritic | None = None
    seconds: float = 0.0

    def final(self, key: str = "success") -> dict[str, NDArray[np.float64]]:
        """Per state, the rate of ``key`` over the last ``final_episodes`` episodes, per seed."""
        f = self.config.final_episodes
        return {s: r[key][:, -f:].mean(axis=1) for s, r in self.runs.items()}

    def reach_given_docked(self) -> dict[str, float | None]:
        """Per state, the share of docked episodes (all episodes) in which the hand touched."""
        out: dict[str, float | None] = {}
        for s, r in self.runs.items():
            n = int(r["docked"].sum())
            out[s] = float((r["success"] & r["docked"]).sum() / n) if n else None
        return out

    def curves(self) -> dict[str, dict[str, list[float]]]:
        """Per state: block ends, success per block (mean and sd over seeds)."""
        b = self.config.block
        out = {}
        for s, r in self.runs.items():
            nb = r["success"].shape[1] // b
            rate = r["success"][:, : nb * b].reshape(-1, nb, b).mean(axis=2)
            out[s] = {
                "episode": [float((i + 1) * b) for i in range(nb)],
                "success": rate.mean(axis=0).tolist(),
                "success_sd": rate.std(axis=0).tolist(),
            }
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able: the map's metrics (seed means, keys of ``sigmapi evaluate``; ``folded``
        if any seed's map folded), per seed, and the success of each state."""
        summary: dict[str, Any] = {}
        if self.map_metrics:
            for k, v in self.map_metrics[0].items():
                vals = [m[k] for m in self.map_metrics]
                summary[k] = (any(vals) if isinstance(v, bool)
                              else float(np.mean(vals)))  # fmt: skip
            summary["order_r2_min"] = float(min(m["order_r2"] for m in self.map_metrics))
            summary["folded_seeds"] = int(sum(bool(m["folded"]) for m in self.map_metrics))
        success = {s: float(v.mean()) for s, v in self.final().items()}
        return {
            **summary, "success": success,
            "success_per_seed": {s: v.tolist() for s, v in self.final().items()},
            "docked": {s: float(v.mean()) for s, v in self.final("docked").items()},
            "reach_given_docked": self.reach_given_docked(),
            "ratio_map_to_true_z": (success["map"] / success["true_z"]
                                    if "map" in success and success.get("true_z") else None),
            "map_metrics": self.map_metrics, "curves": self.curves(),
            "config": self.config.to_dict(), "seeds": list(self.seeds), "seconds": self.seconds,
        }  # fmt: skip

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
        per_seed = d["success_per_seed"]
        for s, v in d["success"].items():
            seeds = " ".join(f"{x:.2f}" for x in per_seed[s])
            lines.append(
                f"  {s:12s} success {v:.3f}  docked {d['docked'][s]:.3f}   per seed: {seeds}"
            )
        return "\n".join(lines)


def run_robot(
    config: RobotConfig | None = None,
    *,
    seeds: tuple[int, ...] = (0,),
    workers: int = 1,
    progress: Progress | None = None,
) -> RobotResult:
    """Learn the map and dock on every state for each seed; ``workers > 1`` runs the seeds in
    parallel processes (the result does not depend on it).

    Examples
    --------
    >>> cfg = QUICK.replace(map_pairs=300, map_iterations=600, eval_pairs=200, episodes=4,
    ...                     final_episodes=2, block=2, grid=6, map_shape=(4, 4))
    >>> sorted(run_robot(cfg, seeds=(0,)).to_dict()["success"])
    ['map', 'retina', 'retina_gaze', 'true_z']
    """
    cfg = config or RobotConfig()
    seeds = tuple(_validate.integer("seed", s, 0) for s in seeds)
    if not seeds:
        raise ConfigError("seeds must name at least one seed, got ()")
    t0 = time.perf_counter()
    evaluation = evaluation_pairs(cfg) if "map" in cfg.states or "true_z" in cfg.states else None
    jobs = [(str(s), _SeedJob(cfg, s, evaluation)) for s in seeds]
    outcomes: dict[int, dict[str, Any]] = {}
    for o in run_jobs(_run_seed, jobs, workers=max(1, min(workers, len(seeds)))):
        if not o.ok:
            raise RuntimeError(f"robot seed {o.key} failed: {o.error}")
        outcomes[int(o.key)] = o.value
        if progress is not None:
            progress(1, f"seed {o.key} done")
    res = RobotResult(cfg, seeds)
    for s in cfg.states:
        res.runs[s] = {k: np.stack([outcomes[sd]["runs"][s][k] for sd in seeds])
                       for k in ("success", "docked", "steps")}  # fmt: skip
    for sd in seeds:
        if outcomes[sd]["map_metrics"] is not None:
            res.map_metrics.append(outcomes[sd]["map_metrics"])
            res.unit_z.append(outcomes[sd]["unit_z"])
    res.model = outcomes[seeds[0]].get("model")
    res.agent = outcomes[seeds[0]].get("agent")
    res.seconds = time.perf_counter() - t0
    return res


def write_outputs(result: RobotResult, out_dir: Path, render: Path | None = None) -> list[Path]:
    """``result.json``, the figures (:mod:`sigmapi.robot.plots`) and, with ``render``, a GIF
    of one episode of the first seed's map learner (third-person and head cameras)."""
    import json

    from sigmapi.robot.plots import film_episode, robot_figures, write_gif

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "result.json"
    path.write_text(json.dumps(result.to_dict(), indent=1) + "\n", encoding="utf-8")
    film = None
    if result.model is not None and result.agent is not None:
        env = make_env(result.config, render_mode="rgb_array")
        film = film_episode(env, result.model, result.agent, seed=result.seeds[0])
        env.close()
    paths = [path, *robot_figures(result, out_dir, film)]
    if render is not None and film:
        paths.append(write_gif(film, render))
    return paths
