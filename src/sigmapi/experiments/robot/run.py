"""The robot experiment: the map learned from the body's own saccades, then docking on it.

:data:`ROBOT` (a :class:`RobotExperiment`) runs a
:class:`~sigmapi.experiments.robot.config.RobotConfig` on a list of seeds and returns a
:class:`~sigmapi.experiments.robot.result.RobotResult`. Per seed, everything random comes from
the streams of :data:`PLAN`, children of ``SeedSequence(seed)``: ``"map"`` seeds the map's
recorded views and weights, ``"starts"`` the episodes' start states (the same for every state:
same learner, same episodes), ``"agent"`` the learner's action choices, ``"film"`` the start of
the filmed episode. The map is scored on evaluation pairs drawn from
:data:`~sigmapi.metrics.EVAL_SEED` (the same for every seed, never moved). The actor-critic of
the authors' docking model then learns on each state (:data:`~sigmapi.envs.STATES`) through
``gymnasium.make("sigmapi/RobotDock-v0")`` and the state wrappers
(:meth:`RobotConfig.state_env <sigmapi.experiments.robot.config.RobotConfig.state_env>`), and
:func:`~sigmapi.agents.run_episodes`: the reach experiment's protocol
(:func:`~sigmapi.experiments.kit.jobs.seed_episodes`), in the robot's world.

Each seed is one job of the :class:`~sigmapi.executor.Executor` (its map, then every state's
learner); the result does not depend on how the jobs ran. ``sigmapi robot`` is generated from
:data:`ROBOT` and :class:`~sigmapi.experiments.robot.config.RobotConfig` (the experiment
registry).

Examples
--------
>>> cfg = QUICK.replace(train_pairs=300, iterations=600, eval_pairs=200, episodes=4,
...                     final_episodes=2, block=2, grid=6, map_shape=(4, 4), max_steps=20)
>>> sorted(ROBOT.run(cfg, seeds=[0]).to_dict()["success"])
['map', 'retina', 'retina_gaze', 'true_z']
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi import _memory, _validate
from sigmapi._outputs import check_file
from sigmapi.agents import ActorCritic
from sigmapi.codes import PopulationCode
from sigmapi.envs.robot.scene import check_rendering, mujoco_module
from sigmapi.envs.robot.views import RobotViewBatch
from sigmapi.executor import Executor
from sigmapi.executor import job_memory as _som_job_memory
from sigmapi.experiments.base import Experiment, check_seeds, register, run_all
from sigmapi.experiments.kit.jobs import SeedEpisodes, Tick, counted, seed_episodes
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

__all__ = ["INFO_KEYS", "PLAN", "QUICK", "ROBOT", "RobotExperiment", "job_memory"]

INFO_KEYS = ("docked", "event")
"""What the experiment keeps of each episode's last ``info`` besides ``is_success``."""


@dataclass(frozen=True)
class _Job:
    config: RobotConfig
    seed: int
    evaluation: tuple[RobotViewBatch, RobotViewBatch] | None
    show: Progress | None = None
    """A bar of this job's episodes (set only where the job runs in the caller's process)."""


def _run_job(job: _Job) -> SeedEpisodes:
    """Everything of one seed: its map (learned and scored), then every state's learner on the
    same episodes (:func:`~sigmapi.experiments.kit.jobs.seed_episodes`, as reach runs)."""
    total = len(job.config.run.states) * job.config.run.episodes
    return counted(job.show, total, f"robot seed {job.seed}", lambda tick: _learners(job, tick))


def _learners(job: _Job, tick: Tick | None) -> SeedEpisodes:
    cfg = job.config

    def make_map(seed: int, tick: Tick | None) -> tuple[SigmaPiSOM, dict[str, Any]]:
        if tick is not None:
            tick(0, "learning the map")
        model = learn_map(cfg, PLAN.rng(seed, "map"))
        assert job.evaluation is not None
        cal, test = job.evaluation
        return model, {
            "map_metrics": score_map(model, cal, test),
            "unit_z": unit_positions(model, cal),
        }

    def keep(state: str, env: Any, agent: ActorCritic) -> ActorCritic | None:
        return agent if state == "map" else None  # the figures film the map's learner

    return seed_episodes(
        job.seed,
        cfg.run.states,
        make_map,
        cfg.state_env,
        cfg.agent,
        PLAN,
        cfg.run.episodes,
        tick=tick,
        info_keys=INFO_KEYS,
        keep=keep,
    )


def job_memory(config: RobotConfig) -> int:
    """Peak bytes of one job (an upper estimate): the map's training and scoring
    (:func:`sigmapi.executor.job_memory`), its recorded and evaluation views and the
    episodes' records."""
    n = config.env.grid**2
    som = robot_som_config(
        PopulationCode((config.env.grid,) * 2, width=config.env.code_width),
        config.map.map_shape,
        config.map.iterations,
        0,
        config.map.backend,
    )
    views = (config.map.train_pairs + 2 * config.map.eval_pairs) * 4 * n * 8
    episodes = 64 * config.run.episodes  # start seeds and each episode's records
    return _som_job_memory(som, n_test=config.map.eval_pairs) + views + episodes


class RobotExperiment(Experiment[RobotConfig]):
    """A simulated robot (MuJoCo) records view pairs from its saccades and learns the
    Sigma-Pi map; then an actor-critic docks on the map, the retina code, retina and gaze
    codes and the true z (the upper bound), over seeds."""

    name = "robot"
    summary = "a simulated robot learns the map from its own saccades, then docks on it"
    config_type = RobotConfig
    quick = QUICK
    seeds = ROBOT_WORLD.seeds
    """The seeds of the acceptance run: none of them was tuned on (tuning used 0-2)."""
    quick_seeds = (0,)
    """The seed of ``--quick``: a tuning seed (a first look does not peek at the reported
    ones)."""
    default_out = "robot"

    def before_writing(self, config: RobotConfig, *, force: bool) -> None:
        """What writing the figures needs, checked before the work: the ``--render`` file
        (:func:`~sigmapi._outputs.check_file`) and an offscreen renderer (``MUJOCO_GL``)."""
        if config.run.render is not None:
            check_file(config.run.render, force=force, what="--render file")
        check_rendering()

    def run(
        self,
        config: RobotConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> RobotResult:
        """Learn the map and dock on every state of ``config.run.states`` for every seed.

        Each seed is one job of ``executor``; run one by one in this process, a job shows a
        bar of its episodes. ``out`` is not used: the run writes nothing while it
        runs. Returns a :class:`~sigmapi.experiments.robot.result.RobotResult`.
        """
        if not isinstance(config, RobotConfig):
            raise _validate.fail("config", "a RobotConfig", config)
        seeds = check_seeds(seeds)
        mujoco_module()  # before any work: says which extra to install
        if config.env.retina == "pixels":
            check_rendering()
        per_job = job_memory(config)  # the main process records views too: checked first
        _memory.check(
            per_job,
            f"a robot job of grid={config.env.grid}, eval_pairs="
            f"{config.map.eval_pairs:,}, train_pairs={config.map.train_pairs:,}, episodes="
            f"{config.run.episodes:,}",
            "use a smaller grid or map, or fewer pairs or episodes",
        )
        t0 = time.perf_counter()
        evaluation = None
        if "map" in config.run.states:
            Progress.of(progress).note("robot: recording the evaluation views")
            evaluation = evaluation_pairs(config)
        jobs = [(str(seed), _Job(config, seed, evaluation)) for seed in seeds]
        values = run_all(
            _run_job,
            jobs,
            executor=executor,
            per_job=per_job,
            progress=progress,
            desc="robot",
            verbose=lambda job: dataclasses.replace(job, show=progress),
            describe=lambda key, _: f"seed {key}",
        )
        res = RobotResult(config, seeds)
        for state in config.run.states:
            eps = [values[str(seed)].runs[state] for seed in seeds]
            res.success[state] = np.stack([e.success for e in eps])
            res.docked[state] = np.stack([e.info["docked"].astype(bool) for e in eps])
            res.steps[state] = np.stack([e.steps for e in eps])
        if "map" in config.run.states:
            for seed in seeds:
                res.map_metrics.append(values[str(seed)].extras["map_metrics"])
                res.unit_z.append(values[str(seed)].extras["unit_z"])
            first = values[str(seeds[0])]
            res.model, res.agent = first.model, first.kept["map"]
        res.seconds = time.perf_counter() - t0
        return res


ROBOT = RobotExperiment()
register(ROBOT)
"""The robot experiment."""
