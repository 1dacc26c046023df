"""The reach experiment: one actor-critic, several state representations, many seeds.

:data:`REACH` (a :class:`ReachExperiment`) runs a
:class:`~sigmapi.experiments.reach.config.ReachConfig` on seeds and returns a
:class:`~sigmapi.experiments.reach.result.ReachResult`. Seed ``s``'s random streams are those
of :data:`PLAN`, each a child of ``SeedSequence(s)`` (:mod:`sigmapi.experiments.kit.seeds`):
``"views"`` the map's data (saccade views; the map is built with seed ``s``), ``"starts"`` the
episodes' start states and ``"agent"`` the learner's action choices (both the same for every
state representation: same learner, same episodes).

Examples
--------
>>> cfg = ReachConfig().replace(dim=1, grid=7, map_shape=(7,), iterations=500, episodes=20,
...                             block=10, final_episodes=10, states=("retina", "true_z"))
>>> res = REACH.run(cfg, seeds=[0])
>>> sorted(res.final_success())
['retina', 'true_z']
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.agents import ActorCritic
from sigmapi.envs import Features, PlacedViewSource, TrueZObservation, make_state_env
from sigmapi.errors import ConfigError
from sigmapi.executor import job_memory
from sigmapi.experiments.base import register
from sigmapi.experiments.kit.jobs import SeedEpisodes, SeedJob, SeedRuns, Tick, seed_episodes
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import GAZE_REACH, World
from sigmapi.experiments.reach.config import SMALL, ReachConfig
from sigmapi.experiments.reach.result import ReachResult
from sigmapi.metrics import evaluate
from sigmapi.model.som import SigmaPiSOM, load_model


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


PLAN = SeedPlan({"views": 5, "starts": 6, "agent": 7})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`)."""


class ReachExperiment(SeedRuns[Any]):
    """Gaze-and-reach task: the same actor-critic on the learned Sigma-Pi map, the retina
    code, retina and gaze codes, and the true z (the upper bound), over seeds.

    ``ReachExperiment(world)`` runs it in another registered world
    (:data:`~sigmapi.experiments.kit.worlds.WORLDS`) whose settings are the config's ``env``
    part (:class:`~sigmapi.envs.GazeReachConfig`); its default seeds are the world's. A world
    variant with a protocol of its own (the robot: its map learned from recorded view pairs
    and scored on the true z, its own result) is a subclass that overrides the hooks
    :meth:`check`, :meth:`prepare`, :meth:`make_map`, :meth:`state_env`, :meth:`keep` and
    :meth:`collect`; the run is :class:`~sigmapi.experiments.kit.jobs.SeedRuns`.
    """

    name = "reach"
    summary = "learn to reach with an actor-critic on the learned map vs. other states"
    config_type: type[Any] = ReachConfig
    quick: Any = SMALL.replace(episodes=150, final_episodes=50)
    quick_seeds = (0,)
    quick_time = "about 12 s on two busy cores"
    default_out = "reach"
    plan: SeedPlan = PLAN
    """The streams of a seed."""
    info_keys: tuple[str, ...] = ()
    """What is kept of each episode's last ``info`` besides ``is_success``."""
    returns_map = False
    """Whether the first seed's map travels back from its job (for the result's figures)."""

    world: World = GAZE_REACH
    """The world it runs in (``ReachExperiment(world)``: another)."""

    def __init__(self, world: World | None = None) -> None:
        world = world or self.world
        env = self.config_type.PARTS["env"]
        if not issubclass(world.settings, env):
            raise _validate.fail(
                f"settings of world {world.name!r}",
                f"a {env.__name__} (the {self.name} config's env part)",
                world.settings.__name__,
            )
        self.world = world
        self.seeds = world.seeds

    def check(self, config: Any) -> int:
        """Refuse a run that cannot go (a missing model file, a map this machine cannot
        hold) before any work; returns the peak bytes of one seed's job."""
        run, path = config.run, config.map.model_path
        if path is not None and "map" in run.states and not Path(path).is_file():
            raise ConfigError(
                f"model_path {path!r} does not exist; train one with `sigmapi train` or leave "
                "model_path out to learn a map per seed"
            )
        # the start states and, per seed and state, three (episodes,) arrays
        _memory.check_count(
            "episodes", run.episodes, 8 + 17 * len(run.states), "e.g. --episodes 600"
        )
        if path is None and "map" in run.states:  # the map and its views
            som = SigmaPiSOM(config.som_config(0, self.world))
            n_x, n_y = int(np.prod(som.x_shape)), int(np.prod(som.y_shape))
            _memory.check(
                som.memory_estimate() + config.map.iterations * 2 * (n_x + n_y) * 8,
                f"the reach experiment's map ({'x'.join(map(str, som.map_shape))} units on "
                f"{n_x} x {n_y} inputs, {config.map.iterations} views)",
                "use a smaller grid, map_shape or iterations",
            )
        return job_memory(config.som_config(0, self.world), n_test=2000)

    def steps(self, job: SeedJob) -> int:
        """A seed's episodes: every state's."""
        return len(job.config.run.states) * job.config.run.episodes

    def seed_run(self, job: SeedJob, tick: Tick | None) -> SeedEpisodes:
        """Everything of one seed: its map, then every state's learner on the same episodes
        (:func:`~sigmapi.experiments.kit.jobs.seed_episodes`) with the variant's map, state
        worlds and what it keeps of the first seed's learners."""
        cfg = job.config
        got = seed_episodes(
            job.seed,
            cfg.run.states,
            functools.partial(self.make_map, cfg, job.shared),
            functools.partial(self.state_env, cfg),
            cfg.agent,
            self.plan,
            cfg.run.episodes,
            tick=tick,
            info_keys=self.info_keys,
            keep=functools.partial(self.keep, cfg) if job.first else None,
        )
        if not (job.first and self.returns_map):
            got.model = None  # its scores travel back, not its weights
        return got

    def make_map(
        self, config: Any, shared: Any, seed: int, tick: Tick | None
    ) -> tuple[SigmaPiSOM, dict[str, object]]:
        """Seed ``seed``'s map (learned in the world, or the config's model file) and, for the
        record, the project's map metrics (docs/algorithm.md) on a small test set."""
        path = config.map.model_path
        if path is None:
            views = self.plan.rng(seed, "views")
            model = config.map.learn(self.world, config.env, seed, views, tick)
        else:
            model = load_model(Path(path))
        return model, {"map_metrics": evaluate(model, n_test=2000).to_dict()}

    def state_env(self, config: Any, state: str, model: SigmaPiSOM | None) -> gym.Env[Any, Any]:
        """The world as ``state`` sees it (:func:`~sigmapi.envs.make_state_env`)."""
        env = self.world.make_env(config.env)
        return make_state_env(env, state, model, config.map.features, config.map.feature_width)

    def keep(self, config: Any, state: str, env: gym.Env[Any, Any], agent: ActorCritic) -> Any:
        """What is kept of the first seed's learner on ``state``: its critic's value over z."""
        return value_over_z(agent, env, n=21 if config.env.dim == 2 else 51)

    def collect(self, config: Any, seeds: tuple[int, ...], got: list[SeedEpisodes]) -> Any:
        """The result of the seeds' jobs (``got``, in the order of ``seeds``)."""
        res = ReachResult(config, seeds)
        for s in config.run.states:
            res.record(s, [one.runs[s] for one in got])
        for one in got:
            if "map_metrics" in one.extras:
                res.map_metrics.append(one.extras["map_metrics"])
            for s, (axis, vals) in one.kept.items():
                res.values[s] = vals
                res.z_axis = axis
        return res


REACH = ReachExperiment()
register(REACH)
"""The reach experiment."""
