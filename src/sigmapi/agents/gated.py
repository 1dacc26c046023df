"""Episodes in which the map keeps learning, its plasticity gated by reward
(docs/algorithm.md, "Reward-gated plasticity").

The loop of :func:`~sigmapi.agents.run_episodes`, with one addition after every step: the
map learns the step's view pair, each unit ``k`` with the gate ``g_k = f(delta) b_k``
(:func:`sigmapi.rules.gating.reward_gate`: the critic's TD error ``delta`` of the step and
the chosen action's actor weights, after the step's update). The pair is the view the step
led to (``view="next"``, the default: on the rewarded step, the goal's own view) or the view it
started from (``view="start"``), which finds the winner, and a second fixation of the same
object while the body is still, which is learned: the two-view rule of the map's unsupervised
training. The world shows the second fixation
(:meth:`~sigmapi.envs.PlacedViewSource.views_of` of that object); the learner never reads
``z``. The state the actor-critic sees is the map's reading at each step
(:class:`~sigmapi.envs.MapObservation`), so it reads the map as it changes.

``surprises``: a sequence of global factors to use instead of the step's own ``f(delta)``
(step ``t`` of the run takes ``surprises[t % len]``): the shuffled-reward control, the same
factors in another order, uncoupled from what happens.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, cast

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.agents.actor_critic import ActorCritic
from sigmapi.agents.episodes import Ending, Episodes, Start, discrete_actions, reset_from, tally
from sigmapi.envs import MapObservation, PlacedViewSource
from sigmapi.envs.protocols import Obs
from sigmapi.errors import ConfigError
from sigmapi.rules.gating import FEEDBACK, SURPRISE, action_feedback, surprise

__all__ = ["VIEWS", "GatedEpisodes", "Gating", "run_gated_episodes"]

VIEWS = ("start", "next")
"""Which state of a step the map learns (:attr:`Gating.view`)."""


@dataclass(frozen=True)
class Gating:
    """How the map learns during the episodes: the gate's parts and the update's size."""

    surprise: str = "positive"
    """Global factor of the TD error (:data:`sigmapi.rules.gating.SURPRISE`)."""
    feedback: str = "action"
    """Per-unit feedback (:data:`sigmapi.rules.gating.FEEDBACK`)."""
    scale: float = 0.5
    """TD error that opens the gate fully."""
    eps: float = 0.3
    """Learning rate of the gated update."""
    sigma: float = 1.0
    """Neighbourhood width of the gated update, in map units."""
    view: str = "next"
    """The view that learns: "next" (the state the step led to: the goal's own view on the
    rewarded step; an object that left the workspace is not learned) or "start" (the state
    the step started from)."""

    def __post_init__(self) -> None:
        _validate.choice("view", self.view, VIEWS)
        _validate.choice("surprise", self.surprise, SURPRISE)
        _validate.choice("feedback", self.feedback, FEEDBACK)
        object.__setattr__(
            self,
            "scale",
            _validate.positive("scale", self.scale, fix="a TD error of this size opens the gate"),
        )
        object.__setattr__(self, "eps", _validate.number("eps", self.eps, 0.0, 1.0))
        object.__setattr__(self, "sigma", _validate.width("sigma", self.sigma, 0.0, lo_open=True))


@dataclass(frozen=True)
class GatedEpisodes:
    """:class:`~sigmapi.agents.Episodes` of the run and the global factor ``f(delta)`` of
    each of its steps, in order (``surprises``), and how many steps changed the map."""

    episodes: Episodes
    surprises: NDArray[np.float64]
    updates: int


def run_gated_episodes(
    env: MapObservation,
    agent: ActorCritic,
    starts: Sequence[Start] | NDArray[np.int64],
    gating: Gating,
    rng: np.random.Generator,
    surprises: NDArray[np.float64] | None = None,
    on_episode: Callable[[], None] | None = None,
) -> GatedEpisodes:
    """Learn over one episode per entry of ``starts`` (:func:`~sigmapi.agents.reset_from`),
    the map learning as it is gated.

    ``env``: the world read through its map (:class:`~sigmapi.envs.MapObservation`; its
    ``model`` is changed in place). ``rng``: the second fixations. ``surprises``: the
    shuffled-reward control's factors (see the module's text), else None.
    """
    if not isinstance(env, MapObservation):
        raise ConfigError(f"the gated map learns under a MapObservation, got {type(env).__name__}")
    world = env.unwrapped
    if not isinstance(world, PlacedViewSource):
        raise ConfigError(
            f"the gated map needs a world that shows an object from a second fixation "
            f"(views_of), got {type(world).__name__}"
        )
    if surprises is not None and len(surprises) == 0:
        raise ConfigError("surprises must hold at least one factor, got none")
    model = env.model
    inner = cast(gym.Env[Obs, Any], env.env)
    _, first = discrete_actions(env.action_space)
    seen: list[float] = []
    updates = 0

    def play(ep: int) -> Ending:
        nonlocal updates
        obs, info = reset_from(inner, starts[ep])
        phi = env.observation(obs)
        t, terminated, truncated = 0, False, False
        while not (terminated or truncated):
            a = agent.act(phi)
            obs2, r, terminated, truncated, info2 = inner.step(first + a)
            phi2 = env.observation(obs2)
            delta = agent.update(phi, a, float(r), phi2, terminated)
            f = float(surprise(delta, gating.surprise, gating.scale))
            seen.append(f)
            if surprises is not None:
                f = float(surprises[(len(seen) - 1) % len(surprises)])
            gate = f * action_feedback(agent.w_[a], gating.feedback)
            seen_obs, seen_z = (obs, info["z"]) if gating.view == "start" else (obs2, info2["z"])
            z = np.asarray(seen_z, dtype=np.float64)[None, :]
            if gate.max(initial=0.0) > 0.0 and np.all((z >= 0.0) & (z <= 1.0)):
                x1, y1 = world.views_of(z, rng)
                x0 = np.asarray(seen_obs["retina"], dtype=np.float64)[None, :]
                y0 = np.asarray(seen_obs["gaze"], dtype=np.float64)[None, :]
                model.learn_gated(
                    (x0, y0, x1, y1), gate[None, :], sigma=gating.sigma, eps=gating.eps
                )
                phi2 = env.observation(obs2)  # the next state as the changed map reads it
                updates += 1
            phi, obs, info = phi2, obs2, info2
            t += 1
        return t, terminated, info

    episodes = tally(len(starts), play, on_episode)
    return GatedEpisodes(episodes, np.asarray(seen), updates)
