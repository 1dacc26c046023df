"""Episodes of learning: one actor-critic in one Gymnasium environment, step by step.

The loop reads only Gymnasium's interface: a 1-D ``Box`` observation (the features a wrapper
of :mod:`sigmapi.envs.wrappers` gives), a ``Discrete`` action space, ``terminated`` and
``truncated`` (the time limit, Gymnasium's ``TimeLimit``) and ``info["is_success"]``. Any
environment that offers them can be learned, the gaze-and-reach world or another.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi.agents.actor_critic import ActorCritic, ActorCriticConfig
from sigmapi.errors import ConfigError

__all__ = [
    "Ending",
    "Episodes",
    "actor_critic_for",
    "discrete_actions",
    "reset_from",
    "run_episodes",
    "tally",
]

ObsT = TypeVar("ObsT")


@dataclass(frozen=True)
class Episodes:
    """What became of each episode, ``(n_episodes,)`` each.

    ``success``: ``info["is_success"]`` at the last step; ``failed``: the world ended the
    episode without success (terminated, e.g. the object left the view); the rest ran into the
    time limit. ``steps``: steps taken. ``info``: for each key asked of
    :func:`run_episodes` (``info_keys``), ``info[key]`` at the last step of each episode.
    """

    success: NDArray[np.bool_]
    failed: NDArray[np.bool_]
    steps: NDArray[np.int64]
    info: dict[str, NDArray[np.generic]] = field(default_factory=dict)


def discrete_actions(space: spaces.Space[Any]) -> tuple[int, int]:
    """``(n, start)`` of a ``Discrete`` action space; a ConfigError for any other space."""
    if not isinstance(space, spaces.Discrete):
        raise ConfigError(
            f"the actor-critic chooses among discrete actions, but the environment's action "
            f"space is {space}; give the environment a Discrete action space"
        )
    return int(space.n), int(space.start)


def actor_critic_for(
    env: gym.Env[Any, Any],
    config: ActorCriticConfig,
    seed: int | np.random.Generator | None = None,
) -> ActorCritic:
    """An :class:`ActorCritic` sized for ``env``: its features (a 1-D ``Box`` observation)
    and its actions (a ``Discrete`` space)."""
    obs = env.observation_space
    if not isinstance(obs, spaces.Box) or len(obs.shape) != 1:
        raise ConfigError(
            f"the actor-critic learns over a feature vector, a 1-D Box observation, got {obs}; "
            "wrap the environment with sigmapi.envs.make_state_env"
        )
    n_actions, _ = discrete_actions(env.action_space)
    return ActorCritic.from_config(config, int(obs.shape[0]), n_actions, seed=seed)


Start = int | np.integer[Any] | np.random.Generator
"""An episode's start: the seed of its ``reset`` (an int) or the generator the world draws
it from (:func:`reset_from`)."""


def reset_from(env: gym.Env[ObsT, Any], start: Start) -> tuple[ObsT, dict[str, Any]]:
    """``env.reset`` from ``start``: an int is the seed of the reset (Gymnasium's
    ``reset(seed=n)``, the world's generator ``default_rng(n)``); a generator becomes the
    world's ``np_random`` (the same, from a stream one was handed) before a ``reset()``."""
    if isinstance(start, np.random.Generator):
        env.np_random = start
        return env.reset()
    return env.reset(seed=int(start))


def run_episodes(
    env: gym.Env[Any, Any],
    agent: ActorCritic,
    starts: Sequence[Start] | NDArray[np.int64],
    on_episode: Callable[[], None] | None = None,
    info_keys: Sequence[str] = (),
) -> Episodes:
    """Learn over one episode per entry of ``starts`` (how its ``reset`` is seeded:
    :func:`reset_from`).

    After every step the agent learns from ``(s, a, r, s')`` (``s'`` terminal only when
    ``terminated``: a time limit is no part of the task). ``on_episode()`` is called after each
    episode (a progress bar). ``info_keys``: entries of the last step's ``info`` to keep per
    episode (:attr:`Episodes.info`), e.g. what ended it.
    """
    _, first = discrete_actions(env.action_space)

    def play(ep: int) -> Ending:
        phi, info = reset_from(env, starts[ep])
        t, terminated, truncated = 0, False, False
        while not (terminated or truncated):
            a = agent.act(phi)
            phi2, r, terminated, truncated, info = env.step(first + a)
            agent.update(phi, a, float(r), phi2, terminated)
            phi = phi2
            t += 1
        return t, terminated, info

    return tally(len(starts), play, on_episode, info_keys)


Ending = tuple[int, bool, Mapping[str, object]]
"""How an episode ended: the steps it took, whether the world terminated it (not the time
limit), the last step's ``info``."""


def tally(
    n: int,
    play: Callable[[int], Ending],
    on_episode: Callable[[], None] | None = None,
    info_keys: Sequence[str] = (),
) -> Episodes:
    """Play episodes ``0 .. n - 1`` in order (``play(ep)`` runs one) and tally their
    :class:`Episodes`: ``on_episode()`` after each; ``info_keys`` as :func:`run_episodes`."""
    success = np.zeros(n, dtype=bool)
    failed = np.zeros(n, dtype=bool)
    steps = np.zeros(n, dtype=np.int64)
    kept: dict[str, list[object]] = {k: [] for k in info_keys}
    for ep in range(n):
        steps[ep], terminated, info = play(ep)
        success[ep] = bool(info["is_success"])
        failed[ep] = terminated and not success[ep]
        for k, values in kept.items():
            values.append(info[k])
        if on_episode is not None:
            on_episode()
    return Episodes(success, failed, steps, {k: np.asarray(v) for k, v in kept.items()})
