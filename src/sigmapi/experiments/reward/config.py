"""The settings of one reward-gating comparison, in five frozen parts (:class:`RewardConfig`):
the world, the map learned before the episodes (the reach experiment's
:class:`~sigmapi.experiments.reach.config.MapConfig`), the learner, the gate
(:class:`GateConfig`) and the run (:class:`RewardRunConfig`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from sigmapi import _validate
from sigmapi.agents import ActorCriticConfig, Gating
from sigmapi.agents.gated import VIEWS
from sigmapi.envs import GazeReachConfig
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.episodes import check_episode_run
from sigmapi.experiments.kit.parts import count_field
from sigmapi.experiments.reach.config import SMALL, MapConfig, MapParts
from sigmapi.rules.gating import FEEDBACK, SURPRISE

METHODS = ("frozen", "gated", "shuffled")
"""The compared maps: frozen after unsupervised learning; learning on, gated by the step's
TD error and the chosen action; learning on with the gated run's factors shuffled in time."""


@dataclass(frozen=True)
class GateConfig:
    """How the map keeps learning during the episodes (docs/algorithm.md, "Reward-gated
    plasticity")."""

    surprise: str = Gating.surprise
    """Global factor of the TD error: "positive" (max(delta, 0)), "absolute" (|delta|) or
    "constant" (1: the action's feedback alone)."""
    feedback: str = Gating.feedback
    """Per-unit feedback: "action" (the chosen action's actor weights, positive part, over
    their largest) or "none" (every unit 1)."""
    gate_scale: float = field(
        default=Gating.scale,
        metadata=_validate.bounded("number", 0, 1e6, lo_open=True, fix="e.g. 0.5"),
    )
    """TD error that opens the gate fully (the factor is clipped to [0, 1])."""
    gate_eps: float = field(
        default=Gating.eps, metadata=_validate.bounded("number", 0, 1, lo_open=True, fix="e.g. 0.3")
    )
    """Learning rate of the gated update."""
    gate_sigma: float = field(
        default=Gating.sigma,
        metadata=_validate.bounded(
            "number", 0, 1e3, lo_open=True, fix="e.g. 1.0; 1e-5 moves the winner alone"
        ),
    )
    """Neighbourhood width of the gated update, in map units."""
    gate_view: str = Gating.view
    """The view that learns: "next" (the state the step led to, the goal's own view on the
    rewarded step) or "start" (the state the step started from)."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)  # the bounds declared beside the fields
        _validate.choice("surprise", self.surprise, SURPRISE)
        _validate.choice("feedback", self.feedback, FEEDBACK)
        _validate.choice("gate_view", self.gate_view, VIEWS)

    def gating(self) -> Gating:
        """The loop's settings (:class:`~sigmapi.agents.gated.Gating`: the same fields, in
        order, without their ``gate_`` prefix)."""
        return Gating(*dataclasses.astuple(self))


@dataclass(frozen=True)
class RewardRunConfig:
    """What is compared, for how long, and how the maps are scored."""

    methods: tuple[str, ...] = METHODS
    """Maps to compare ("frozen", "gated", "shuffled"; "shuffled" needs "gated")."""
    episodes: int = count_field(300)
    """Episodes of reinforcement learning per seed and method."""
    block: int = count_field(20)
    """Episodes per point of the learning curves (and the window of the 80 % criterion)."""
    final_episodes: int = count_field(100)
    """The final success rate is measured over this many last episodes."""
    target: float = field(
        default=0.8, metadata=_validate.bounded("number", 0, 1, lo_open=True, fix="e.g. 0.8")
    )
    """Success rate over a block that counts as learned (episodes to reach it)."""
    near_radius: float = field(
        default=0.2, metadata=_validate.bounded("number", 0, 0.5, lo_open=True, fix="e.g. 0.2")
    )
    """Chebyshev radius around the goal of the region "near the goal" (the magnification)."""
    n_test: int = count_field(4000)
    """Test objects (views at random z) that score the maps."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        check_episode_run(self, "methods", METHODS)
        if "shuffled" in self.methods and "gated" not in self.methods:
            raise ConfigError(
                "methods: 'shuffled' replays the gated run's factors in another order, so it "
                f"needs 'gated' too, got {self.methods!r}; add 'gated'"
            )


@dataclass(frozen=True)
class RewardConfig(MapParts):
    """Everything one reward-gating comparison depends on, but its seeds. Defaults: the 7x7
    world and map of the reach experiment's small setting, the authors' actor-critic."""

    env: GazeReachConfig = field(default_factory=lambda: SMALL.env)
    """The world and its time limit."""
    map: MapConfig = field(default_factory=lambda: SMALL.map)
    """The map learned without a teacher before the episodes."""
    agent: ActorCriticConfig = field(default_factory=ActorCriticConfig)
    """The learner."""
    gate: GateConfig = field(default_factory=GateConfig)
    """The gated learning during the episodes."""
    run: RewardRunConfig = field(default_factory=RewardRunConfig)
    """The methods, episodes and scores."""

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.map.model_path is not None:
            raise ConfigError(
                "model_path must be None for the reward experiment: each seed learns its own "
                f"map, the one the methods start from, got {self.map.model_path!r}"
            )
