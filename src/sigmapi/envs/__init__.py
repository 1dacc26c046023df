"""Worlds to learn in, behind a view-source protocol: the gaze-and-reach task, the observation
wrappers (which read observation spaces, not classes) and the saccade views a map learns from.

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

from sigmapi.envs.gaze_reach import ENV_ID, GazeReachConfig, GazeReachEnv, move_table
from sigmapi.envs.protocols import (
    OBS_KEYS,
    Obs,
    PlacedViewSource,
    Views,
    ViewSource,
    check_view_space,
    view_space,
)
from sigmapi.envs.views import collect_saccade_views, collect_stream, learn_map_in_env, view_source
from sigmapi.envs.wrappers import (
    FEATURES,
    STATE_WRAPPERS,
    STATES,
    CodeObservation,
    Features,
    MapObservation,
    TrueZObservation,
    bump_features,
    make_state_env,
)

__all__ = [
    "ENV_ID",
    "FEATURES",
    "OBS_KEYS",
    "STATES",
    "STATE_WRAPPERS",
    "CodeObservation",
    "Features",
    "GazeReachConfig",
    "GazeReachEnv",
    "MapObservation",
    "Obs",
    "PlacedViewSource",
    "TrueZObservation",
    "ViewSource",
    "Views",
    "bump_features",
    "check_view_space",
    "collect_saccade_views",
    "collect_stream",
    "learn_map_in_env",
    "make_state_env",
    "move_table",
    "view_source",
    "view_space",
]
