"""The reach experiment: one actor-critic, several state representations, many seeds.

Per seed, everything random comes from one :class:`numpy.random.SeedSequence`: child 0 seeds
the map's data (saccade views) and weights, child 1 the episodes' start states (identical for
every state representation: same learner, same episodes), child 2 the learner's action
choices (the same stream for every representation).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from sigmapi.agents.actor_critic import ActorCritic
from sigmapi.envs.protocols import PlacedViewSource
from sigmapi.envs.views import learn_map_in_env
from sigmapi.envs.wrappers import Features, TrueZObservation, make_state_env
from sigmapi.errors import ConfigError
from sigmapi.executor import job_memory, plan_workers, run_jobs
from sigmapi.metrics import evaluate
from sigmapi.progress import counter
from sigmapi.reach.config import ReachConfig
from sigmapi.som import SigmaPiSOM, load_model

__all__ = [
    "ReachResult",
    "run_episodes",
    "run_reach",
    "run_with_progress",
    "value_over_z",
]

Progress = Callable[[int, str], None]


def value_over_z(
    agent: ActorCritic,
    state_env: gym.Env[Features, Any],
    n: int = 21,
    n_views: int = 8,
    seed: int = 0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The critic's value on a grid of z, averaged over ``n_views`` random gazes per z.

    The world under ``state_env`` must show a given z
    (:class:`~sigmapi.envs.PlacedViewSource`). Returns ``(z_axis, V)``: ``z_axis`` ``(n,)``
    and ``V`` of shape ``(n,) * z_dim`` (in 2-D indexed ``[z0, z1]``).
    """
    base = state_env.unwrapped
    if not isinstance(base, PlacedViewSource):
        raise ConfigError(
            f"the value over z needs a world that shows a given z (views_of, z_dim), got "
            f"{type(base).__name__}"
        )
    if not isinstance(state_env, (TrueZObservation, gym.ObservationWrapper)):
        raise TypeError(f"state_env must be made by make_state_env, got {type(state_env).__name__}")
    rng = np.random.default_rng(seed)
    axis = np.linspace(0.0, 1.0, n)
    dim = base.z_dim
    zs = np.stack(np.meshgrid(*([axis] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    out = np.empty(len(zs))
    for i, z in enumerate(zs):
        if isinstance(state_env, TrueZObservation):
            out[i] = agent.value(state_env.encode(z[None, :])[0])
            continue
        cx, cy = base.views_of(np.repeat(z[None, :], n_views, axis=0), rng)
        out[i] = np.mean(
            [
                agent.value(state_env.observation({"retina": a, "gaze": b}))
                for a, b in zip(cx, cy, strict=True)
            ]
        )
    return axis, out.reshape((n,) * dim)


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
    map_metrics: list[dict[str, float | int]] = field(default_factory=list)
    seconds: float = 0.0

    def final_success(self) -> dict[str, float]:
        """Success rate over the last ``final_episodes`` episodes, mean over seeds."""
        return {s: float(v.mean()) for s, v in self.final_success_per_seed().items()}

    def final_lost(self) -> dict[str, float]:
        """Fraction of the last ``final_episodes`` episodes that lost the object (seed mean)."""
        f = self.config.final_episodes
        return {s: float(v[:, -f:].mean()) for s, v in self.lost.items()}

    def final_timed_out(self) -> dict[str, float]:
        """Fraction of the last ``final_episodes`` episodes that neither reached nor lost the
        object (seed mean), counted (not ``1 - success - lost``, which rounds to -1e-17)."""
        f = self.config.final_episodes
        return {
            s: float((~v[:, -f:] & ~self.lost[s][:, -f:]).mean()) for s, v in self.success.items()
        }

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
            "timed_out": self.final_timed_out(),
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
) -> SigmaPiSOM:
    if config.model_path is not None:
        return load_model(Path(config.model_path))
    seq = np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 0))
    r = np.random.default_rng(seq)
    env_seed, som_seed = (int(v) for v in r.integers(0, 2**31 - 1, size=2))

    def callback(model: SigmaPiSOM) -> None:
        if progress is not None:
            progress(0, "learning the map")

    return learn_map_in_env(
        config.make_env(), config.som_config(som_seed), seed=env_seed, callback=callback
    )


def run_episodes(
    config: ReachConfig,
    state: str,
    model: SigmaPiSOM | None,
    starts: NDArray[np.int64],
    agent_seed: np.random.SeedSequence,
    progress: Progress | None = None,
) -> tuple[
    NDArray[np.bool_], NDArray[np.bool_], NDArray[np.int64], ActorCritic, gym.Env[Features, Any]
]:
    """Train one learner on ``state`` over the episodes that start from seeds ``starts``."""
    env = make_state_env(config.make_env(), state, model, config.features, config.feature_width)
    n_features = int(np.prod(env.observation_space.shape or (1,)))
    space = env.action_space
    if not isinstance(space, gym.spaces.Discrete):
        raise ConfigError(
            f"the actor-critic chooses among discrete actions; the environment's action space "
            f"is {space}; give the environment a Discrete action space"
        )
    n_actions, first = int(space.n), int(space.start)
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
            phi2, r, terminated, truncated, info = env.step(first + a)
            agent.update(phi, a, float(r), phi2, terminated)
            phi = phi2
            t += 1
            if terminated or truncated:
                break
        success[ep] = bool(info["is_success"])
        lost[ep] = terminated and not success[ep]  # ended by the world without success
        steps[ep] = t
        if progress is not None:
            progress(1, state)
    return success, lost, steps, agent, env


@dataclass(frozen=True)
class _SeedJob:
    config: ReachConfig
    index: int
    seq: np.random.SeedSequence


def _run_seed(job: _SeedJob, progress: Progress | None = None) -> dict[str, Any]:
    """Everything of one seed: its map, then every state's learner on the same episodes."""
    cfg, ss, i = job.config, job.seq, job.index
    model = _map_for_seed(cfg, ss, progress) if "map" in cfg.states else None
    out: dict[str, Any] = {"map_metrics": _map_quality(model) if model is not None else None,
                           "runs": {}, "values": {}}  # fmt: skip
    start_rng = np.random.default_rng(
        np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 1))
    )
    starts = start_rng.integers(0, 2**31 - 1, size=cfg.episodes)
    agent_seq = np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, 2))
    for s in cfg.states:
        succ, lost, steps, agent, env = run_episodes(cfg, s, model, starts, agent_seq, progress)
        out["runs"][s] = (succ, lost, steps)
        if i == 0:
            out["values"][s] = value_over_z(agent, env, n=21 if cfg.dim == 2 else 51)
    return out


def run_reach(
    config: ReachConfig | None = None,
    progress: Progress | None = None,
    *,
    workers: int = 1,
    **overrides: Any,
) -> ReachResult:
    """Train the actor-critic on every state of ``config.states`` for every seed.

    ``progress(n, phase)`` is called with the number of episodes just finished and a short
    description of the phase (for a progress bar; the total is ``seeds * len(states) *
    episodes``; map learning reports 0 episodes). ``workers > 1`` runs the seeds in parallel
    processes (:mod:`sigmapi.executor`; the result does not depend on it), and progress then
    counts whole seeds. Returns a :class:`ReachResult`.

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
    seqs = np.random.SeedSequence(cfg.seed).spawn(cfg.seeds)
    parallel = workers > 1 and cfg.seeds > 1
    if parallel:
        jobs = [(str(i), _SeedJob(cfg, i, ss)) for i, ss in enumerate(seqs)]
        outcomes = {}
        for o in run_jobs(_run_seed, jobs, workers=min(workers, cfg.seeds)):
            if not o.ok:
                raise RuntimeError(f"reach seed {o.key} failed: {o.error}")
            outcomes[int(o.key)] = o.value
            if progress is not None:
                progress(len(cfg.states) * cfg.episodes, f"seed {o.key} done")
        per_seed = [outcomes[i] for i in range(cfg.seeds)]
    else:
        per_seed = [_run_seed(_SeedJob(cfg, i, ss), progress) for i, ss in enumerate(seqs)]
    for i, out in enumerate(per_seed):
        if out["map_metrics"] is not None:
            res.map_metrics.append(out["map_metrics"])
        for s, (succ, lost, steps) in out["runs"].items():
            res.success[s][i], res.lost[s][i], res.steps[s][i] = succ, lost, steps
        for s, (axis, values) in out["values"].items():
            res.values[s] = values
            res.z_axis = axis
    res.seconds = time.perf_counter() - t0
    return res


def run_with_progress(
    cfg: ReachConfig, disable: bool | None = None, workers: int | None = None
) -> ReachResult:
    """:func:`run_reach` with a progress bar on stderr (episodes, and the current phase).

    ``workers=None``: one seed per core, as many as fit in half the available memory
    (:func:`sigmapi.executor.plan_workers`).
    """
    if workers is None:
        per_seed = job_memory(cfg.som_config(cfg.seed), n_test=2000)
        workers = plan_workers(None, per_seed, n_jobs=cfg.seeds).workers
    progress, bar = counter(cfg.seeds * len(cfg.states) * cfg.episodes, "reach", "ep", disable)
    with bar:
        return run_reach(cfg, progress=progress, workers=workers)


def _map_quality(model: SigmaPiSOM) -> dict[str, float | int]:
    """The project's map metrics (docs/algorithm.md) on a small test set, for the record."""
    return evaluate(model, n_test=2000).to_dict()
