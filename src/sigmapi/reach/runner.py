"""Experiment runner: one actor-critic, several state representations, many seeds.

Per seed, everything random comes from one :class:`numpy.random.SeedSequence`: child 0 seeds
the map's data (saccade views) and weights, child 1 the episodes' start states (identical for
every state representation: same learner, same episodes), child 2 the learner's action
choices (the same stream for every representation).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.progress import counter
from sigmapi.reach.agent import ActorCritic
from sigmapi.reach.env import GazeReachEnv
from sigmapi.reach.views import collect_saccade_views
from sigmapi.reach.wrappers import FEATURES, STATES, TrueZObservation, make_state_env

__all__ = [
    "ReachConfig",
    "ReachResult",
    "learn_map_in_env",
    "run_reach",
    "run_with_progress",
    "value_over_z",
]

Progress = Callable[[int, str], None]


@dataclass(frozen=True)
class ReachConfig:
    """Everything one reach comparison depends on. Defaults: the 2-D task, saccade every step."""

    dim: int = 2
    """1 or 2: dimensions of the task."""
    grid: int = 7
    """Units per axis of the retina and gaze codes (7x7 in 2-D; the paper's maps read 15x15)."""
    code_width: float = 0.5
    """Width of the input hills in grid units (the paper: 0.5)."""
    step_size: float = 0.05
    """How far one move shifts z along an axis."""
    goal_radius: float = 0.1
    """Half-width of the goal box around z = 0.5 (straight ahead, within grasp range)."""
    saccade_rate: float = 1.0
    """Probability of a saccade per step (1: on every step, the hardest case)."""
    max_steps: int = 50
    """Time limit per episode (truncation): 3x the longest shortest path (16 moves in 2-D)."""
    map_shape: tuple[int, ...] = (7, 7)
    """Grid of the Sigma-Pi map learned in the environment."""
    map_pairs: int = 10_000
    """Saccade view pairs the map learns from (one SOM iteration each)."""
    backend: str = "reference"
    """Kernel that learns the map ("auto": the fast one when it is installed)."""
    model_path: str | None = None
    """A trained model file to use for every seed instead of learning a map per seed."""
    features: str = "response"
    """Map features: "response" (activations clipped at 0, L2-normalised; measured best) or
    "bump" (Gaussian around the winner on the map grid). 2-D, 5 seeds, 600 episodes: final
    success 0.971 with "response", 0.949 with "bump" (true z: 0.977)."""
    feature_width: float = 1.0
    """Width of the bump features (map and true-z codes), in grid units."""
    episodes: int = 600
    """Episodes of reinforcement learning per seed and state."""
    seeds: int = 5
    """Number of independent seeds (maps, start states, action choices)."""
    seed: int = 0
    """Root seed; seed i of the run uses SeedSequence(seed).spawn child i."""
    block: int = 50
    """Episodes per point of the learning curves."""
    final_episodes: int = 200
    """The final success rate is measured over this many last episodes."""
    gamma: float = 0.9
    critic_lr: float = 0.1
    actor_lr: float = 0.1
    beta: float = 2.0
    states: tuple[str, ...] = STATES
    """State representations to compare."""

    def __post_init__(self) -> None:
        for name in ("episodes", "seeds", "block", "final_episodes", "map_pairs"):
            object.__setattr__(self, name, _validate.integer(name, getattr(self, name), 1))
        if self.final_episodes > self.episodes:
            raise ConfigError(
                f"final_episodes must be <= episodes ({self.episodes}), got {self.final_episodes}"
            )
        object.__setattr__(self, "seed", _validate.integer("seed", self.seed, 0))
        states = tuple(self.states)
        bad = [s for s in states if s not in STATES]
        if not states or bad or len(set(states)) != len(states):
            raise ConfigError(f"states must be distinct names from {STATES}, got {states!r}")
        object.__setattr__(self, "states", states)
        _validate.choice("features", self.features, FEATURES)
        object.__setattr__(self, "map_shape", tuple(int(n) for n in self.map_shape))
        self.make_env()  # validates the task's parameters
        ActorCritic(1, 1, self.gamma, self.critic_lr, self.actor_lr, self.beta)

    def env_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :class:`GazeReachEnv` (also of ``gymnasium.make``)."""
        return {
            "dim": self.dim, "grid": self.grid, "code_width": self.code_width,
            "step_size": self.step_size, "goal_radius": self.goal_radius,
            "saccade_rate": self.saccade_rate, "max_steps": self.max_steps,
        }  # fmt: skip

    def make_env(self) -> GazeReachEnv:
        return GazeReachEnv(**self.env_kwargs())

    def som_config(self, seed: int) -> SOMConfig:
        """The map's config for ``map_pairs`` saccade views.

        The neighbourhood shrinks from the map's size to 30 % of it over the first 30 % of the
        run, then to 0.7 units at 80 %: a longer ordering phase and a wider final
        neighbourhood than the paper's 300,000-iteration 1-D schedule, because a 2-D map
        trained on only ~10^4 views twists under the paper's schedule shape (measured: order
        R^2 0.1 vs 0.5 on a 7x7 map, 10,000 views).
        """
        m = float(max(self.map_shape))
        inputs = (self.grid,) * self.dim
        return SOMConfig(
            map_shape=self.map_shape, x_shape=inputs, y_shape=inputs, code_width=self.code_width,
            iterations=self.map_pairs, backend=self.backend, seed=seed,
            sigma=((0.0, m), (0.3, max(m / 3.5, 1.0)), (0.8, 0.7)),
        )  # fmt: skip

    def replace(self, **changes: Any) -> ReachConfig:
        names = {f.name for f in dataclasses.fields(self)}
        bad = sorted(set(changes) - names)
        if bad:
            raise ConfigError(
                f"unknown ReachConfig field {bad[0]!r}; valid: {', '.join(sorted(names))}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return {
            k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()
        }


def learn_map_in_env(
    env: GazeReachEnv, config: SOMConfig, seed: int | None = None, callback: Any = None
) -> Any:
    """Train a :class:`~sigmapi.SigmaPiSOM` on saccade views gathered in ``env``.

    ``config.iterations`` view pairs are collected with
    :func:`~sigmapi.reach.collect_saccade_views` (no teacher, no access to z) and learned
    with ``partial_fit(views=...)``: the winner from one view, the update from the other.
    """
    from sigmapi.som import SigmaPiSOM

    views = collect_saccade_views(env, config.iterations, seed=seed)
    return SigmaPiSOM(config).partial_fit(views=views, callback=callback)


def value_over_z(
    agent: ActorCritic, state_env: Any, n: int = 21, n_views: int = 8, seed: int = 0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The critic's value on a grid of z, averaged over ``n_views`` random gazes per z.

    Returns ``(z_axis, V)``: ``z_axis`` ``(n,)`` and ``V`` of shape ``(n,)`` (1-D) or
    ``(n, n)`` (2-D, indexed ``[z0, z1]``).
    """
    base: GazeReachEnv = state_env.unwrapped
    rng = np.random.default_rng(seed)
    axis = np.linspace(0.0, 1.0, n)
    zs = np.stack(np.meshgrid(*([axis] * base.dim), indexing="ij"), axis=-1).reshape(-1, base.dim)
    out = np.empty(len(zs))
    for i, z in enumerate(zs):
        if isinstance(state_env, TrueZObservation):
            out[i] = agent.value(state_env.encode(z[None, :])[0])
            continue
        lo, hi = base.gaze_range(z)
        ys = lo + (hi - lo) * rng.random((n_views, base.dim))
        xs = np.clip(2.0 * z - ys, 0.0, 1.0)
        cx, cy = base.code.encode(xs).astype(np.float32), base.code.encode(ys).astype(np.float32)
        out[i] = np.mean(
            [
                agent.value(state_env.observation({"retina": a, "gaze": b}))
                for a, b in zip(cx, cy, strict=True)
            ]
        )
    return axis, out.reshape((n,) * base.dim)


@dataclass
class ReachResult:
    """Outcome of :func:`run_reach`.

    ``success[state]``, ``lost[state]`` and ``steps[state]`` have shape ``(seeds,
    episodes)``: whether each episode reached the goal, whether it lost the object (left the
    workspace; the rest timed out) and how many steps it took; ``values[state]`` is the critic's
    value over z (seed 0), on ``z_axis``.
    """

    config: ReachConfig
    success: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    steps: dict[str, NDArray[np.int64]] = field(default_factory=dict)
    lost: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    values: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    z_axis: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    map_metrics: list[dict[str, Any]] = field(default_factory=list)
    seconds: float = 0.0

    def final_success(self) -> dict[str, float]:
        """Success rate over the last ``final_episodes`` episodes, mean over seeds."""
        return {s: float(v.mean()) for s, v in self.final_success_per_seed().items()}

    def final_lost(self) -> dict[str, float]:
        """Fraction of the last ``final_episodes`` episodes that lost the object (seed mean)."""
        f = self.config.final_episodes
        return {s: float(v[:, -f:].mean()) for s, v in self.lost.items()}

    def final_success_per_seed(self) -> dict[str, NDArray[np.float64]]:
        f = self.config.final_episodes
        return {s: v[:, -f:].mean(axis=1) for s, v in self.success.items()}

    def curves(self) -> dict[str, dict[str, NDArray[np.float64]]]:
        """Per state: ``episode`` (block ends), ``success`` and ``steps_to_reach`` per block.

        Each is ``(n_blocks,)`` mean over seeds, with ``*_sd`` the standard deviation over
        seeds; steps to reach average the successful episodes only (NaN when none).
        """
        b = self.config.block
        out: dict[str, dict[str, NDArray[np.float64]]] = {}
        for s in self.success:
            succ, steps = self.success[s], self.steps[s].astype(np.float64)
            nb = succ.shape[1] // b
            sb = succ[:, : nb * b].reshape(succ.shape[0], nb, b)
            tb = steps[:, : nb * b].reshape(succ.shape[0], nb, b)
            rate = sb.mean(axis=2)
            with np.errstate(invalid="ignore", divide="ignore"):
                reach_steps = np.where(sb, tb, 0.0).sum(axis=2) / sb.sum(axis=2)
            ok = np.isfinite(reach_steps)
            cnt = ok.sum(axis=0)
            mean_steps = np.where(
                cnt > 0, np.where(ok, reach_steps, 0.0).sum(axis=0) / np.maximum(cnt, 1), np.nan
            )
            out[s] = {
                "episode": (np.arange(nb) + 1.0) * b,
                "success": rate.mean(axis=0),
                "success_sd": rate.std(axis=0),
                "steps_to_reach": mean_steps,
            }
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-able summary: config, final success (mean and per seed), curves, timing."""
        curves = self.curves()
        return {
            "success": self.final_success(),
            "success_per_seed": {s: v.tolist() for s, v in self.final_success_per_seed().items()},
            "lost": self.final_lost(),
            "timed_out": {
                s: 1.0 - self.final_success()[s] - self.final_lost()[s] for s in self.success
            },
            "ratio_map_to_true_z": (
                self.final_success()["map"] / self.final_success()["true_z"]
                if "map" in self.success
                and "true_z" in self.success
                and self.final_success()["true_z"] > 0
                else None
            ),
            "curves": {
                s: {k: [None if not np.isfinite(x) else float(x) for x in v] for k, v in c.items()}
                for s, c in curves.items()
            },
            "map_metrics": self.map_metrics,
            "config": self.config.to_dict(),
            "seconds": self.seconds,
        }


def _map_for_seed(
    config: ReachConfig, ss: np.random.SeedSequence, progress: Progress | None = None
) -> Any:
    if config.model_path is not None:
        from sigmapi.som import load_model

        return load_model(Path(config.model_path))
    seq = np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 0))
    r = np.random.default_rng(seq)
    env_seed, som_seed = (int(v) for v in r.integers(0, 2**31 - 1, size=2))

    def callback(model: Any) -> None:
        if progress is not None:
            progress(0, f"map {model.t_}/{config.map_pairs}")

    return learn_map_in_env(
        config.make_env(), config.som_config(som_seed), seed=env_seed, callback=callback
    )


def run_episodes(
    config: ReachConfig,
    state: str,
    model: Any,
    starts: NDArray[np.int64],
    agent_seed: np.random.SeedSequence,
    progress: Progress | None = None,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.int64], ActorCritic, Any]:
    """Train one learner on ``state`` over the episodes that start from seeds ``starts``."""
    env = make_state_env(config.make_env(), state, model, config.features, config.feature_width)
    n_features = int(np.prod(env.observation_space.shape or (1,)))
    n_actions = int(env.unwrapped.action_space.n)  # type: ignore[attr-defined]
    agent = ActorCritic(
        n_features,
        n_actions,
        config.gamma,
        config.critic_lr,
        config.actor_lr,
        config.beta,
        seed=np.random.default_rng(agent_seed),
    )
    n = len(starts)
    success = np.zeros(n, dtype=bool)
    lost = np.zeros(n, dtype=bool)
    steps = np.zeros(n, dtype=np.int64)
    for ep in range(n):
        phi, info = env.reset(seed=int(starts[ep]))
        t = 0
        while True:
            a = agent.act(phi)
            phi2, r, terminated, truncated, info = env.step(a)
            agent.update(phi, a, float(r), phi2, terminated)
            phi = phi2
            t += 1
            if terminated or truncated:
                break
        success[ep] = info["event"] == "reached"
        lost[ep] = info["event"] == "left_view"
        steps[ep] = t
        if progress is not None:
            progress(1, state)
    return success, lost, steps, agent, env


def run_reach(
    config: ReachConfig | None = None, progress: Progress | None = None, **overrides: Any
) -> ReachResult:
    """Train the actor-critic on every state of ``config.states`` for every seed.

    ``progress(n, phase)`` is called with the number of episodes just finished and a short
    description of the phase (for a progress bar; the total is ``seeds * len(states) *
    episodes``; map learning reports 0 episodes). Returns a :class:`ReachResult`.

    Examples
    --------
    >>> res = run_reach(dim=1, grid=7, map_shape=(7,), map_pairs=500, episodes=20, seeds=1,
    ...                 block=10, final_episodes=10, states=("retina", "true_z"))
    >>> sorted(res.final_success())
    ['retina', 'true_z']
    """
    cfg = (config or ReachConfig()).replace(**overrides) if overrides else (config or ReachConfig())
    t0 = time.perf_counter()
    res = ReachResult(cfg)
    for s in cfg.states:
        res.success[s] = np.zeros((cfg.seeds, cfg.episodes), dtype=bool)
        res.steps[s] = np.zeros((cfg.seeds, cfg.episodes), dtype=np.int64)
        res.lost[s] = np.zeros((cfg.seeds, cfg.episodes), dtype=bool)
    root = np.random.SeedSequence(cfg.seed)
    for i, ss in enumerate(root.spawn(cfg.seeds)):
        model = _map_for_seed(cfg, ss, progress) if "map" in cfg.states else None
        if model is not None:
            res.map_metrics.append(_map_quality(model))
        start_rng = np.random.default_rng(
            np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 1))
        )
        starts = start_rng.integers(0, 2**31 - 1, size=cfg.episodes)
        agent_seq = np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 2))
        for s in cfg.states:
            succ, lost, steps, agent, env = run_episodes(cfg, s, model, starts, agent_seq, progress)
            res.success[s][i], res.lost[s][i], res.steps[s][i] = succ, lost, steps
            if i == 0:
                axis, res.values[s] = value_over_z(agent, env, n=21 if cfg.dim == 2 else 51)
                res.z_axis = axis
    res.seconds = time.perf_counter() - t0
    return res


def run_with_progress(cfg: ReachConfig, disable: bool | None = None) -> ReachResult:
    """:func:`run_reach` with a progress bar on stderr (episodes, and the current phase)."""
    progress, bar = counter(cfg.seeds * len(cfg.states) * cfg.episodes, "reach", "ep", disable)
    with bar:
        return run_reach(cfg, progress=progress)


def _map_quality(model: Any) -> dict[str, Any]:
    """The project's map metrics (ALGORITHM.md) on a small test set, for the record."""
    from sigmapi.metrics import evaluate

    try:
        return dict(evaluate(model, n_test=2000).to_dict())
    except Exception as exc:  # metrics are a record, not the experiment: never fail the run
        return {"error": f"{type(exc).__name__}: {exc}"}
