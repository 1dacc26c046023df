"""Worlds to learn in: the gaze-and-reach task, its observation wrappers and its saccade views.

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

from sigmapi.envs.gaze_reach import GazeReachEnv, move_table
from sigmapi.envs.views import collect_saccade_views, learn_map_in_env
from sigmapi.envs.wrappers import (
    FEATURES,
    STATES,
    CodeObservation,
    MapObservation,
    TrueZObservation,
    bump_features,
    make_state_env,
)

__all__ = [
    "ENV_ID",
    "FEATURES",
    "STATES",
    "CodeObservation",
    "GazeReachEnv",
    "MapObservation",
    "TrueZObservation",
    "bump_features",
    "collect_saccade_views",
    "learn_map_in_env",
    "make_state_env",
    "move_table",
]

ENV_ID = "sigmapi/GazeReach-v0"
"""The gaze-and-reach environment's Gymnasium id (registered by ``import sigmapi``)."""
