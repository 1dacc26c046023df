"""Learners that act on a state: the actor-critic of the authors' docking model, and the
episode loop that trains it in any Gymnasium environment with a feature observation and
discrete actions, the loop in which the map keeps learning, gated by reward, and the
associative layer that learns arm postures from motor babbling."""

from __future__ import annotations

from sigmapi.agents.actor_critic import ActorCritic, ActorCriticConfig
from sigmapi.agents.association import Association
from sigmapi.agents.episodes import (
    Episodes,
    actor_critic_for,
    discrete_actions,
    reset_from,
    run_episodes,
)
from sigmapi.agents.gated import GatedEpisodes, Gating, run_gated_episodes

__all__ = [
    "ActorCritic",
    "ActorCriticConfig",
    "Association",
    "Episodes",
    "GatedEpisodes",
    "Gating",
    "actor_critic_for",
    "discrete_actions",
    "reset_from",
    "run_episodes",
    "run_gated_episodes",
]
