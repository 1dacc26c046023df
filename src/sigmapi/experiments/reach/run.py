"""The reach experiment: one actor-critic, several state representations, many seeds.

:data:`REACH` (a :class:`ReachExperiment`) runs a
:class:`~sigmapi.experiments.reach.config.ReachConfig` on a list of seeds and returns a
:class:`~sigmapi.experiments.reach.result.ReachResult`. Seed ``s``'s random streams are
those of :data:`PLAN`: ``"map"`` seeds the map's data (saccade views) and weights,
``"starts"`` the episodes' start states (identical for every state representation: same
learner, same episodes), ``"agent"`` the learner's action choices (the same stream for every
representation); each is child ``(s, key)`` of ``SeedSequence(0)``.

Examples
--------
>>> cfg = ReachConfig().replace(dim=1, grid=7, map_shape=(7,), iterations=500, episodes=20,
...                             block=10, final_episodes=10, states=("retina", "true_z"))
>>> res = REACH.run(cfg, seeds=[0])
>>> sorted(res.final_success())
['retina', 'true_z']
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.agents import ActorCritic
from sigmapi.envs import (
    Features,
    GazeReachConfig,
    PlacedViewSource,
    TrueZObservation,
    learn_map_in_env,
    make_state_env,
)
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import Experiment, check_seeds, register, run_all
from sigmapi.experiments.kit.jobs import SeedEpisodes, Tick, counted, seed_episodes
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import GAZE_REACH, World
from sigmapi.experiments.reach.config import SMALL_PRESET, ReachConfig, preset_setting
from sigmapi.experiments.reach.result import ReachResult
from sigmapi.metrics import evaluate
from sigmapi.model.som import SigmaPiSOM, load_model
from sigmapi.progress import Progress

__all__ = [
    "PLAN",
    "REACH",
    "ReachExperiment",
    "run_with_progress",
    "value_over_z",
]


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


PLAN = SeedPlan({"map": 0, "starts": 1, "agent": 2}, root=0)
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`)."""


def _map_for_seed(
    config: ReachConfig, world: World, seed: int, progress: Tick | None = None
) -> SigmaPiSOM:
    if config.map.model_path is not None:
        return load_model(Path(config.map.model_path))
    r = PLAN.rng(seed, "map")
    env_seed, som_seed = (int(v) for v in r.integers(0, 2**31 - 1, size=2))

    def callback(model: SigmaPiSOM) -> None:
        if progress is not None:
            progress(0, "learning the map")

    env, som = world.make_env(config.env), config.som_config(som_seed, world)
    return learn_map_in_env(env, som, seed=env_seed, callback=callback)


@dataclass(frozen=True)
class _SeedJob:
    config: ReachConfig
    world: World
    first: bool
    seed: int
    show: Progress | None = None
    """A bar of this seed's episodes (set only where the job runs in the caller's process)."""


def _run_seed(job: _SeedJob) -> SeedEpisodes:
    """Everything of one seed: its map, then every state's learner on the same episodes."""
    total = len(job.config.run.states) * job.config.run.episodes
    return counted(job.show, total, f"reach seed {job.seed}", lambda tick: _seed_runs(job, tick))


def _seed_runs(job: _SeedJob, progress: Tick | None) -> SeedEpisodes:
    cfg, world = job.config, job.world

    def make_map(seed: int, tick: Tick | None) -> tuple[SigmaPiSOM, dict[str, Any]]:
        model = _map_for_seed(cfg, world, seed, tick)
        return model, {"map_metrics": _map_quality(model)}

    def state_env(state: str, model: SigmaPiSOM | None) -> gym.Env[Features, Any]:
        env = world.make_env(cfg.env)
        return make_state_env(env, state, model, cfg.map.features, cfg.map.feature_width)

    def values(state: str, env: gym.Env[Features, Any], agent: ActorCritic) -> Any:
        return value_over_z(agent, env, n=21 if cfg.env.dim == 2 else 51)

    run, keep = cfg.run, values if job.first else None
    got = seed_episodes(
        job.seed,
        run.states,
        make_map,
        state_env,
        cfg.agent,
        PLAN,
        run.episodes,
        tick=progress,
        keep=keep,
    )
    got.model = None  # its scores travel back, not its weights
    return got


def _map_quality(model: SigmaPiSOM) -> dict[str, float | int]:
    """The project's map metrics (docs/algorithm.md) on a small test set, for the record."""
    return evaluate(model, n_test=2000).to_dict()


def _check_memory(config: ReachConfig, world: World) -> None:
    """Refuse a map (and its views) that this machine cannot hold, before anything is built."""
    run = config.run  # the start states and, per seed and state, three (episodes,) arrays
    _memory.check_count("episodes", run.episodes, 8 + 17 * len(run.states), "e.g. --episodes 600")
    if config.map.model_path is not None or "map" not in config.run.states:
        return
    som = SigmaPiSOM(config.som_config(0, world))
    n_x, n_y = int(np.prod(som.x_shape)), int(np.prod(som.y_shape))
    _memory.check(
        som.memory_estimate() + config.map.iterations * 2 * (n_x + n_y) * 8,
        f"the reach experiment's map ({'x'.join(map(str, som.map_shape))} units on "
        f"{n_x} x {n_y} inputs, {config.map.iterations} views)",
        "use a smaller grid, map_shape or iterations",
    )


def _check_model(config: ReachConfig) -> None:
    """A model file given for the map must exist (checked before any work starts)."""
    path = config.map.model_path
    if path is not None and "map" in config.run.states and not Path(path).is_file():
        raise ConfigError(
            f"model_path {path!r} does not exist; train one with `sigmapi train` or leave "
            "model_path out to learn a map per seed"
        )


class ReachExperiment(Experiment[ReachConfig]):
    """Gaze-and-reach task: the same actor-critic on the learned Sigma-Pi map, the retina
    code, retina and gaze codes, and the true z (the upper bound), over seeds.

    ``ReachExperiment(world)`` runs it in another registered world
    (:data:`~sigmapi.experiments.kit.worlds.WORLDS`) whose settings are a
    :class:`~sigmapi.envs.GazeReachConfig` (the config's ``env`` part); its default seeds are
    the world's.
    """

    name = "reach"
    summary = "learn to reach with an actor-critic on the learned map vs. other states"
    config_type = ReachConfig
    quick = ReachConfig().replace(episodes=150, final_episodes=50, **preset_setting(SMALL_PRESET))
    quick_seeds = (0,)
    default_out = "reach"

    def __init__(self, world: World = GAZE_REACH) -> None:
        if not issubclass(world.settings, GazeReachConfig):
            raise _validate.fail(
                f"settings of world {world.name!r}",
                "a GazeReachConfig (the reach config's env part)",
                world.settings.__name__,
            )
        self.world = world
        self.seeds = world.seeds

    def run(
        self,
        config: ReachConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> ReachResult:
        """Train the actor-critic on every state of ``config.run.states`` for every seed.

        Each seed is one job of ``executor`` (the result does not depend on where it runs);
        run one by one in this process, a seed shows a bar of its episodes. ``out`` is not
        used: the run writes nothing while it runs. Returns a
        :class:`~sigmapi.experiments.reach.result.ReachResult`.
        """
        if not isinstance(config, ReachConfig):
            raise _validate.fail("config", "a ReachConfig", config)
        seeds = check_seeds(seeds)
        _check_model(config)
        _check_memory(config, self.world)
        t0 = time.perf_counter()
        run = config.run
        shape = (len(seeds), run.episodes)
        res = ReachResult(config, seeds)
        for s in run.states:
            res.success[s] = np.zeros(shape, dtype=bool)
            res.steps[s] = np.zeros(shape, dtype=np.int64)
            res.lost[s] = np.zeros(shape, dtype=bool)
        jobs = [(str(s), _SeedJob(config, self.world, i == 0, s)) for i, s in enumerate(seeds)]
        values = run_all(
            _run_seed,
            jobs,
            executor=executor,
            per_job=job_memory(config.som_config(0, self.world), n_test=2000),
            progress=progress,
            desc="reach",
            verbose=lambda job: dataclasses.replace(job, show=progress),
            describe=lambda key, _: f"seed {key}",
        )
        for i, (key, _) in enumerate(jobs):
            got = values[key]
            if "map_metrics" in got.extras:
                res.map_metrics.append(got.extras["map_metrics"])
            for s, ep in got.runs.items():
                res.success[s][i], res.lost[s][i], res.steps[s][i] = ep.success, ep.failed, ep.steps
            for s, (axis, vals) in got.kept.items():
                res.values[s] = vals
                res.z_axis = axis
        res.seconds = time.perf_counter() - t0
        return res


REACH = ReachExperiment()
register(REACH)
"""The reach experiment."""


def run_with_progress(
    config: ReachConfig,
    seeds: Iterable[int],
    disable: bool | None = None,
    workers: int | None = None,
) -> ReachResult:
    """:meth:`REACH.run <ReachExperiment.run>` with progress on stderr and the seeds as jobs
    of a local process pool (``workers=None``: one per core, as memory allows)."""
    return REACH.run(
        config,
        seeds=list(seeds),
        executor=Executor(workers=workers),
        progress=Progress(disable=disable),
    )
