"""The per-seed job of an experiment and its progress: one function, run where the executor
puts it, that shows a bar of its episodes only where it runs in the caller's process; and the
one learner of the embodied experiments (:func:`learn_on_state`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import gymnasium as gym

from sigmapi.agents import ActorCritic, ActorCriticConfig, Episodes, actor_critic_for, run_episodes
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.progress import Progress

__all__ = ["Tick", "counted", "learn_on_state"]

T = TypeVar("T")

Tick = Callable[[int, str], None]
"""``tick(n, phase)``: ``n`` episodes just finished (0 while the map learns), and what runs."""


def counted(show: Progress | None, total: int, desc: str, work: Callable[[Tick | None], T]) -> T:
    """``work(tick)`` with a bar of ``total`` episodes named ``desc`` where ``show`` is given
    (the job runs in the caller's process, :func:`~sigmapi.experiments.base.run_all`'s
    ``verbose``), else ``work(None)``."""
    if show is None:
        return work(None)
    tick, bar = show.counter(total, desc, "ep")
    with bar:
        return work(tick)


def learn_on_state(
    env: gym.Env[Any, Any],
    agent: ActorCriticConfig,
    plan: SeedPlan,
    seed: int,
    episodes: int,
    *,
    on_episode: Callable[[], None] | None = None,
    info_keys: Sequence[str] = (),
) -> tuple[Episodes, ActorCritic]:
    """The actor-critic of ``agent`` learning over ``episodes`` episodes of ``env`` (a state
    the learner sees): its action choices from stream ``"agent"`` of ``seed``'s ``plan``, the
    episodes' starts from stream ``"starts"`` (so every state of a seed meets the same
    episodes). The episodes' records (:func:`~sigmapi.agents.run_episodes`) and the learner."""
    learner = actor_critic_for(env, agent, seed=plan.rng(seed, "agent"))
    starts = plan.rng(seed, "starts").integers(0, 2**31 - 1, size=episodes)
    records = run_episodes(env, learner, starts, on_episode=on_episode, info_keys=info_keys)
    return records, learner
