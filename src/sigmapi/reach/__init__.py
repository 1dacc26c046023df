"""From map to action: the reach experiment (the environment and wrappers are in
:mod:`sigmapi.envs`, the learner in :mod:`sigmapi.agents`; re-exported here)."""

from __future__ import annotations

from sigmapi.agents import ActorCritic
from sigmapi.envs import (
    ENV_ID,
    CodeObservation,
    GazeReachEnv,
    MapObservation,
    TrueZObservation,
    collect_saccade_views,
    learn_map_in_env,
    make_state_env,
    move_table,
)
from sigmapi.reach.config import ReachConfig
from sigmapi.reach.experiment import ReachResult, run_reach, run_with_progress

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
