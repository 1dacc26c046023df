"""Learners that act on a state: the actor-critic of the authors' docking model."""

from __future__ import annotations

from sigmapi.agents.actor_critic import ActorCritic

__all__ = ["ActorCritic"]
