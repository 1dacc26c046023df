"""The robot experiment (``sigmapi robot``): the reach experiment's run in the robot's world,
with the robot's map (docs/guide/robot.md).

:data:`ROBOT` runs a :class:`~sigmapi.experiments.robot.config.RobotConfig` on seeds and returns
a :class:`~sigmapi.experiments.robot.result.RobotResult`. Seed ``s``'s random streams are those
of :data:`~sigmapi.experiments.robot.config.PLAN`: ``"views"`` (the map's recorded views; the
map is built with seed ``s``, its weights the seed's own), ``"starts"`` and ``"agent"`` (the
same for every state), ``"film"`` (the filmed episode's start). The map and its scores:
:mod:`~sigmapi.experiments.robot.map`.

Examples
--------
>>> cfg = QUICK.replace(train_pairs=300, iterations=600, eval_pairs=200, episodes=4,
...                     final_episodes=2, block=2, grid=6, map_shape=(4, 4), max_steps=20)
>>> sorted(ROBOT.run(cfg, seeds=[0]).to_dict()["success"])
['map', 'retina', 'retina_gaze', 'true_z']
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from sigmapi import _memory
from sigmapi._outputs import check_file
from sigmapi.agents import ActorCritic
from sigmapi.codes import PopulationCode
from sigmapi.envs import Features
from sigmapi.envs.robot.scene import check_rendering, mujoco_module
from sigmapi.envs.robot.views import RobotViewBatch
from sigmapi.executor import job_memory
from sigmapi.experiments.base import register
from sigmapi.experiments.kit.jobs import SeedEpisodes, Tick
from sigmapi.experiments.reach.run import ReachExperiment
from sigmapi.experiments.robot.config import PLAN, QUICK, ROBOT_WORLD, RobotConfig
from sigmapi.experiments.robot.map import (
    evaluation_pairs,
    learn_map,
    robot_som_config,
    score_map,
    unit_positions,
)
from sigmapi.experiments.robot.result import RobotResult
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress

Views = tuple[RobotViewBatch, RobotViewBatch]
"""The calibration and test views every seed's map is scored on."""


class RobotExperiment(ReachExperiment):
    """A simulated robot (MuJoCo) records view pairs from its saccades and learns the
    Sigma-Pi map; then an actor-critic docks on the map, the retina code, retina and gaze
    codes and the true z (the upper bound), over seeds.

    ``RobotExperiment(world)`` runs it in another world whose settings are a
    :class:`~sigmapi.experiments.robot.config.RobotEnvConfig` (default
    :data:`~sigmapi.experiments.robot.config.ROBOT_WORLD`, whose default seeds are the
    acceptance run's, none tuned on)."""

    name = "robot"
    summary = "a simulated robot learns the map from its own saccades, then docks on it"
    config_type = RobotConfig
    quick = QUICK
    quick_seeds = (0,)
    """The seed of ``--quick``: a tuning seed (a first look does not peek at the reported ones)."""
    quick_time = "about 20 s on two quiet cores, 80 s on two busy ones"
    extra = "robot"
    default_out = "robot"
    plan = PLAN
    info_keys = ("docked", "event")
    returns_map = True
    world = ROBOT_WORLD

    def before_writing(self, config: RobotConfig, *, force: bool) -> None:
        """What writing the figures needs, checked before the work: the ``--render`` file
        (:func:`~sigmapi._outputs.check_file`) and an offscreen renderer (``MUJOCO_GL``)."""
        if config.run.render is not None:
            check_file(config.run.render, force=force, what="--render file")
        check_rendering()

    def check(self, config: RobotConfig) -> int:
        """MuJoCo (and a renderer for the pixel retina) before any work, and the peak bytes of
        one job, an upper estimate (the main process records views too: checked first): the
        map's training and scoring (:func:`sigmapi.executor.job_memory`), its recorded and
        evaluation views and the episodes' records."""
        mujoco_module()  # says which extra to install
        if config.env.retina == "pixels":
            check_rendering()
        env, m = config.env, config.map
        code = PopulationCode((env.grid,) * 2, width=env.code_width)
        som = robot_som_config(code, m.map_shape, m.iterations, 0, m.backend)
        views = (m.train_pairs + 2 * m.eval_pairs) * 4 * env.grid**2 * 8
        episodes = 64 * config.run.episodes  # start seeds and each episode's records
        per_job = job_memory(som, n_test=m.eval_pairs) + views + episodes
        _memory.check(
            per_job,
            f"a robot job of grid={env.grid}, eval_pairs={m.eval_pairs:,}, train_pairs="
            f"{m.train_pairs:,}, episodes={config.run.episodes:,}",
            "use a smaller grid or map, or fewer pairs or episodes",
        )
        return per_job

    def prepare(self, config: RobotConfig, progress: Progress | None) -> Views | None:
        """The evaluation views every seed's map is scored on (where a state reads a map)."""
        if "map" not in config.run.states:
            return None
        Progress.of(progress).note("robot: recording the evaluation views")
        return evaluation_pairs(config)

    def make_map(
        self, config: RobotConfig, shared: Views, seed: int, tick: Tick | None
    ) -> tuple[SigmaPiSOM, dict[str, object]]:
        """Seed ``seed``'s map from recorded view pairs, its scores and each unit's
        preferred z on the evaluation views (``shared``)."""
        if tick is not None:
            tick(0, "learning the map")
        model = learn_map(config, seed, self.plan.rng(seed, "views"), self.world)
        cal, test = shared
        return model, {
            "map_metrics": score_map(model, cal, test),
            "unit_z": unit_positions(model, cal),
        }

    def state_env(
        self, config: RobotConfig, state: str, model: SigmaPiSOM | None
    ) -> gym.Env[Features, object]:
        """The docking world as ``state`` sees it (:meth:`RobotConfig.state_env
        <sigmapi.experiments.robot.config.RobotConfig.state_env>`)."""
        return config.state_env(state, model, self.world)

    def keep(
        self, config: RobotConfig, state: str, env: gym.Env[Features, object], agent: ActorCritic
    ) -> ActorCritic | None:
        """The first seed's map learner (the figures film it)."""
        return agent if state == "map" else None

    def collect(
        self, config: RobotConfig, seeds: tuple[int, ...], got: list[SeedEpisodes]
    ) -> RobotResult:
        """The result of the seeds' jobs (``got``, in the order of ``seeds``)."""
        res = RobotResult(config, seeds)
        for state in config.run.states:
            eps = [one.runs[state] for one in got]
            res.record(state, eps)
            res.docked[state] = np.stack([e.info["docked"].astype(bool) for e in eps])
        if "map" in config.run.states:
            for one in got:
                res.map_metrics.append(one.extras["map_metrics"])
                res.unit_z.append(one.extras["unit_z"])
            res.model, res.agent = got[0].model, got[0].kept["map"]
        return res


ROBOT = RobotExperiment()
register(ROBOT)
"""The robot experiment."""
