"""The robot experiment: the map learned from the body's own saccades, then docking on it.

:data:`ROBOT` (a :class:`RobotExperiment`) runs a
:class:`~sigmapi.experiments.robot_config.RobotConfig` on a list of seeds and returns a
:class:`~sigmapi.experiments.robot_result.RobotResult`. Per seed, everything random comes from
``SeedSequence(seed)``: its child 0 seeds the map's recorded views and weights, child 1 the
episodes' start states (the same for every state: same learner, same episodes), child 2 the
learner's action choices. The map is scored on evaluation pairs drawn from
:data:`~sigmapi.metrics.EVAL_SEED` (the same for every seed, never moved). The actor-critic of
the authors' docking model then learns on each state (:data:`~sigmapi.envs.STATES`) through
``gymnasium.make("sigmapi/RobotDock-v0")`` and the state wrappers
(:meth:`RobotConfig.state_env <sigmapi.experiments.robot_config.RobotConfig.state_env>`), and
:func:`~sigmapi.agents.run_episodes`.

Each (seed, state) is one job, the map state's job learning that seed's map first, so that an
executor spreads the learners over its workers; the result does not depend on how they ran.

Examples
--------
>>> cfg = QUICK.replace(map_pairs=300, map_iterations=600, eval_pairs=200, episodes=4,
...                     final_episodes=2, block=2, grid=6, map_shape=(4, 4), max_steps=20)
>>> sorted(ROBOT.run(cfg, seeds=[0]).to_dict()["success"])
['map', 'retina', 'retina_gaze', 'true_z']
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sigmapi import _validate
from sigmapi.agents import actor_critic_for, run_episodes
from sigmapi.codes import PopulationCode
from sigmapi.envs.robot.views import RobotViewBatch
from sigmapi.executor import Outcome, run_jobs
from sigmapi.executor import job_memory as _som_job_memory
from sigmapi.experiments.robot_config import QUICK, RobotConfig
from sigmapi.experiments.robot_map import (
    evaluation_pairs,
    learn_map,
    robot_som_config,
    score_map,
    unit_positions,
)
from sigmapi.experiments.robot_result import RobotResult
from sigmapi.progress import counter

__all__ = ["INFO_KEYS", "QUICK", "ROBOT", "RobotExperiment", "job_memory", "run_with_progress"]

Progress = Callable[[int, str], None]
"""``progress(n, phase)``: ``n`` episodes just finished (0 while the map learns), and what runs."""
Executor = Callable[[Callable[[Any], Any], Sequence[tuple[str, Any]]], Iterable[Outcome]]
"""Runs ``fn`` on each ``(key, arg)`` job and yields an :class:`~sigmapi.executor.Outcome` per
job, e.g. ``functools.partial(sigmapi.executor.run_jobs, workers=2)``."""

INFO_KEYS = ("docked", "event")
"""What the experiment keeps of each episode's last ``info`` besides ``is_success``."""


def _child(seed: int, k: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(k,)))


@dataclass(frozen=True)
class _Job:
    config: RobotConfig
    seed: int
    state: str
    evaluation: tuple[RobotViewBatch, RobotViewBatch] | None


def _run_job(job: _Job) -> dict[str, Any]:
    """One learner on one state of one seed (the map's job learns and scores the map first)."""
    cfg = job.config
    out: dict[str, Any] = {}
    model = None
    if job.state == "map":
        model = learn_map(cfg, _child(job.seed, 0))
        assert job.evaluation is not None
        cal, test = job.evaluation
        out["map_metrics"] = score_map(model, cal, test)
        out["unit_z"] = unit_positions(model, cal)
        out["model"] = model
    env = cfg.state_env(job.state, model)
    agent = actor_critic_for(env, cfg.agent(), seed=_child(job.seed, 2))
    starts = _child(job.seed, 1).integers(0, 2**31 - 1, size=cfg.episodes)
    out["episodes"] = run_episodes(env, agent, starts, info_keys=INFO_KEYS)
    out["agent"] = agent
    env.close()
    return out


def job_memory(config: RobotConfig) -> int:
    """Peak bytes of one job (an upper estimate): the map's training and scoring
    (:func:`sigmapi.executor.job_memory`) and its recorded and evaluation views."""
    n = config.grid**2
    som = robot_som_config(PopulationCode((config.grid,) * 2, width=config.code_width),
                           config.map_shape, config.map_iterations, 0, config.backend)  # fmt: skip
    views = (config.map_pairs + 2 * config.eval_pairs) * 4 * n * 8
    return _som_job_memory(som, n_test=config.eval_pairs) + views


def _seeds(seeds: Iterable[int]) -> tuple[int, ...]:
    out = tuple(seeds)
    if not out or len(set(out)) != len(out):
        raise _validate.fail("seeds", "a non-empty list of distinct ints >= 0", list(out))
    return tuple(_validate.integer("seeds", s, 0) for s in out)


class RobotExperiment:
    """Learn the map on the simulated robot, then dock on each state (``sigmapi robot``)."""

    name = "robot"
    summary = "a simulated robot learns the map from its own saccades, then docks on it"
    config_type = RobotConfig
    quick = QUICK
    default_seeds: tuple[int, ...] = (100, 101, 102, 103, 104)
    """The seeds of the acceptance run: none of them was tuned on (tuning used 0-2)."""
    quick_seeds: tuple[int, ...] = (0,)
    """The seed of ``--quick``: a tuning seed (a first look should not peek at the reported
    ones)."""

    def run(
        self,
        config: RobotConfig,
        *,
        seeds: Iterable[int],
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> RobotResult:
        """Learn the map and dock on every state of ``config.states`` for every seed.

        ``progress(n, phase)`` is called with the episodes just finished (a job's whole run
        when an ``executor`` runs the jobs, in parallel processes say; the result does not
        depend on it). Returns a :class:`~sigmapi.experiments.robot_result.RobotResult`.
        """
        if not isinstance(config, RobotConfig):
            raise _validate.fail("config", "a RobotConfig", config)
        seeds = _seeds(seeds)
        t0 = time.perf_counter()
        evaluation = evaluation_pairs(config) if "map" in config.states else None
        jobs = [(f"{seed}/{state}", _Job(config, seed, state, evaluation if state == "map"
                                          else None))
                for seed in seeds for state in config.states]  # fmt: skip
        outcomes: dict[str, dict[str, Any]] = {}
        if executor is None:
            for key, job in jobs:
                if progress is not None:
                    progress(0, f"seed {job.seed} {job.state}")
                outcomes[key] = _run_job(job)
                if progress is not None:
                    progress(config.episodes, f"seed {job.seed} {job.state} done")
        else:
            for o in executor(_run_job, jobs):
                if not o.ok:
                    raise RuntimeError(f"robot job {o.key} failed: {o.error}")
                outcomes[o.key] = o.value
                if progress is not None:
                    progress(config.episodes, f"{o.key} done")
        res = RobotResult(config, seeds)
        for state in config.states:
            eps = [outcomes[f"{seed}/{state}"]["episodes"] for seed in seeds]
            res.success[state] = np.stack([e.success for e in eps])
            res.docked[state] = np.stack([e.info["docked"].astype(bool) for e in eps])
            res.steps[state] = np.stack([e.steps for e in eps])
        if "map" in config.states:
            for seed in seeds:
                res.map_metrics.append(outcomes[f"{seed}/map"]["map_metrics"])
                res.unit_z.append(outcomes[f"{seed}/map"]["unit_z"])
            first = outcomes[f"{seeds[0]}/map"]
            res.model, res.agent = first["model"], first["agent"]
        res.seconds = time.perf_counter() - t0
        return res


ROBOT = RobotExperiment()
"""The robot experiment."""


def run_with_progress(
    config: RobotConfig,
    seeds: Iterable[int],
    disable: bool | None = None,
    workers: int = 1,
) -> RobotResult:
    """:meth:`ROBOT.run <RobotExperiment.run>` with a progress bar on stderr (episodes, and the
    current phase), the jobs in ``workers`` parallel processes."""
    seeds = _seeds(seeds)
    n_jobs = len(seeds) * len(config.states)
    executor = None
    if workers > 1 and n_jobs > 1:
        executor = functools.partial(run_jobs, workers=min(workers, n_jobs))
    progress, bar = counter(n_jobs * config.episodes, "robot", "ep", disable)
    with bar:
        return ROBOT.run(config, seeds=seeds, executor=executor, progress=progress)
