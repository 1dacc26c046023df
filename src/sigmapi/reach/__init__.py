"""From map to action: the gaze-and-reach task, map observations and an actor-critic learner.

``import sigmapi`` registers the Gymnasium environment ``sigmapi/GazeReach-v0``
(:class:`GazeReachEnv`; keyword arguments of ``gymnasium.make`` go to its constructor).

    >>> import gymnasium as gym
    >>> import sigmapi
    >>> env = gym.make("sigmapi/GazeReach-v0", dim=1, grid=9)
    >>> obs, info = env.reset(seed=0)
    >>> sorted(obs)
    ['gaze', 'retina']
"""

from __future__ import annotations

from sigmapi.reach.agent import ActorCritic
from sigmapi.reach.config import ReachConfig
from sigmapi.reach.env import GazeReachEnv, move_table
from sigmapi.reach.experiment import ReachResult, learn_map_in_env, run_reach, run_with_progress
from sigmapi.reach.views import collect_saccade_views
from sigmapi.reach.wrappers import (
    CodeObservation,
    MapObservation,
    TrueZObservation,
    make_state_env,
)

__all__ = [
    "ENV_ID",
    "ActorCritic",
    "CodeObservation",
    "GazeReachEnv",
    "MapObservation",
    "ReachConfig",
    "ReachResult",
    "TrueZObservation",
    "collect_saccade_views",
    "learn_map_in_env",
    "make_state_env",
    "move_table",
    "run_reach",
    "run_with_progress",
]

ENV_ID = "sigmapi/GazeReach-v0"
"""The environment's Gymnasium id (registered by ``import sigmapi``)."""
