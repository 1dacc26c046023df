"""The per-seed job of an experiment and its progress (:func:`counted`, :class:`Steps`), one
experiment of a job per seed written once (:class:`SeedRuns`), and the protocol of the embodied
experiments: a seed's map, then the same learner on every state compared (:func:`seed_episodes`)."""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import gymnasium as gym

from sigmapi.agents import ActorCritic, ActorCriticConfig, Episodes, actor_critic_for, run_episodes
from sigmapi.experiments.base import C, Experiment, Run, run_all
from sigmapi.experiments.kit.results import JSON, Result
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress

T = TypeVar("T")

Tick = Callable[[int, str], None]
"""``tick(n, phase)``: ``n`` episodes just finished (0 while the map learns), and what runs."""


def counted(
    show: Progress | None,
    total: int,
    desc: str,
    work: Callable[[Tick | None], T],
    unit: str = "ep",
) -> T:
    """``work(tick)`` with a bar of ``total`` units (episodes) named ``desc`` where ``show``
    is given (:func:`~sigmapi.experiments.base.run_all`'s ``verbose``), else ``work(None)``."""
    if show is None:
        return work(None)
    tick, bar = show.counter(total, desc, unit)
    with bar:
        return work(tick)


def iterations_counted(
    tick: Tick | None, name: str, iterations: int
) -> Callable[[Any], None] | None:
    """A ``fit`` callback (``callback(model)``) that counts one map's training iterations, up
    to ``iterations``, on ``tick`` as phase ``name``; None where nothing is shown."""
    if tick is None:
        return None
    seen = 0

    def callback(model: Any) -> None:
        nonlocal seen
        t = min(int(model.t_), iterations)
        tick(t - seen, name)
        seen = t

    return callback


class Steps:
    """The named steps of a job, shown through ``tick`` (None: nothing shown): the first
    is shown as it starts; :meth:`next` counts the step that ran and shows the next one."""

    def __init__(self, tick: Tick | None, names: Sequence[str]) -> None:
        self.tick, self.names, self.i = tick, tuple(names), 0
        if tick is not None and self.names:
            tick(0, self.names[0])

    def next(self) -> None:
        """The current step is done; the next one starts."""
        if self.tick is None or self.i >= len(self.names):
            return
        self.tick(1, self.names[self.i])
        self.i += 1
        if self.i < len(self.names):
            self.tick(0, self.names[self.i])


@dataclass
class SeedEpisodes:
    """What :func:`seed_episodes` gives of one seed: its map (None when no state reads one)
    and what the map's maker added (its scores), each state's episode records and what
    ``keep`` kept of each state's learner."""

    model: SigmaPiSOM | None
    extras: JSON
    runs: dict[str, Episodes] = field(default_factory=dict)
    kept: dict[str, Any] = field(default_factory=dict)


def seed_episodes(
    seed: int,
    states: Sequence[str],
    make_map: Callable[[int, Tick | None], tuple[SigmaPiSOM, JSON]],
    state_env: Callable[[str, SigmaPiSOM | None], gym.Env[Any, Any]],
    agent: ActorCriticConfig,
    plan: SeedPlan,
    episodes: int,
    *,
    tick: Tick | None = None,
    info_keys: Sequence[str] = (),
    keep: Callable[[str, gym.Env[Any, Any], ActorCritic], Any] | None = None,
) -> SeedEpisodes:
    """One seed of an embodied experiment (reach, robot): the map ``make_map(seed, tick)`` where
    a state reads it (``"map"`` in ``states``); then per state, its world ``state_env(state,
    model)`` and the same learner on the same episodes (streams ``"agent"`` and ``("starts",
    i)`` of ``plan``: :func:`~sigmapi.agents.run_episodes`), ``tick(1, state)`` after each;
    ``keep(state, env, learner)``, where given, what to keep of it."""
    model, extras = make_map(seed, tick) if "map" in states else (None, {})
    out = SeedEpisodes(model, extras)
    for state in states:
        env = state_env(state, model)
        done = None if tick is None else functools.partial(tick, 1, state)
        learner = actor_critic_for(env, agent, seed=plan.rng(seed, "agent"))
        starts = plan.rngs(seed, "starts", episodes)  # fresh for each state: the same starts
        out.runs[state] = run_episodes(env, learner, starts, on_episode=done, info_keys=info_keys)
        if keep is not None:
            out.kept[state] = keep(state, env, learner)
        env.close()
    return out


@dataclass(frozen=True)
class SeedJob:
    """One seed's job of a :class:`SeedRuns` experiment."""

    config: Any
    seed: int
    first: bool = False
    """Whether it is the first seed's (the one whose learners and maps the figures show)."""
    shared: Any = None
    """What every seed's job reads and the run made once (:meth:`SeedRuns.prepare`)."""
    show: Progress | None = None
    """A bar of this job's steps (set only where the job runs in the caller's process)."""


class SeedRuns(Experiment[C]):
    """An experiment of one job per seed (or per seed and part), its run written once:
    :meth:`check` (before any work; the peak bytes of one job), :meth:`prepare` (what every
    job reads), :meth:`jobs`, each job's :meth:`seed_run` (with a bar of its :meth:`steps`
    where it runs in the caller's process) through the executor, then :meth:`collect`."""

    unit = "ep"
    """What the bar of a job counts (:meth:`steps`)."""

    def check(self, config: C) -> int:
        """Refuse a run that cannot go before any work; the peak bytes of one job."""
        raise NotImplementedError

    def prepare(self, config: C, progress: Progress | None) -> object:
        """What every seed's job reads and the run makes once (here: nothing)."""
        return None

    def jobs(self, config: C, seeds: tuple[int, ...], shared: object) -> list[tuple[str, Any]]:
        """The jobs by key: one per seed (:class:`SeedJob`)."""
        return [(str(s), SeedJob(config, s, i == 0, shared)) for i, s in enumerate(seeds)]

    def steps(self, job: Any) -> int:
        """How many steps the bar of ``job`` counts."""
        raise NotImplementedError

    def desc(self, job: Any) -> str:
        """The name of the bar of ``job``."""
        return f"{self.name} seed {job.seed}"

    def describe(self, key: str, value: Any) -> str:
        """The line of a finished job."""
        return f"seed {key}"

    def seed_run(self, job: Any, tick: Tick | None) -> Any:
        """Everything of one job (``tick``: its progress, None where nothing is shown)."""
        raise NotImplementedError

    def collect(self, config: C, seeds: tuple[int, ...], values: list[Any]) -> Result:
        """The result of the jobs' values (in the order of :meth:`jobs`)."""
        raise NotImplementedError

    def run_job(self, job: Any) -> Any:
        """:meth:`seed_run` with a bar of its steps where ``job.show`` is given."""
        run = functools.partial(self.seed_run, job)
        return counted(job.show, self.steps(job), self.desc(job), run, self.unit)

    def execute(self, config: C, run: Run) -> Any:
        """Every job of ``config`` and the run's seeds through its executor (the result does not
        depend on where they run); ``run.out`` is not used: the run writes nothing as it runs."""
        per_job = self.check(config)
        t0 = time.perf_counter()
        jobs = self.jobs(config, run.seeds, self.prepare(config, run.progress))
        values = run_all(
            self.run_job,
            jobs,
            executor=run.executor,
            per_job=per_job,
            progress=run.progress,
            desc=self.name,
            verbose=lambda job: dataclasses.replace(job, show=run.progress),
            describe=self.describe,
        )
        res: Any = self.collect(config, run.seeds, [values[key] for key, _ in jobs])
        res.seconds = time.perf_counter() - t0
        return res
