"""The settings of one reach comparison: :class:`ReachConfig`, the one typed source of defaults.

The ``sigmapi reach`` options are generated from its fields (:mod:`sigmapi.cli.reach`), so a
field added here is a command-line option too.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from gymnasium.wrappers import TimeLimit

from sigmapi import _memory, _validate
from sigmapi.agents.actor_critic import ActorCritic
from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.envs.gaze_reach import GazeReachEnv
from sigmapi.envs.wrappers import FEATURES, STATES
from sigmapi.errors import ConfigError
from sigmapi.kernels import BACKENDS
from sigmapi.som import SigmaPiSOM

__all__ = ["SMALL_MAP", "ReachConfig"]

SMALL_MAP: dict[str, Any] = {
    "grid": 7, "code_width": 0.5, "map_shape": (7, 7), "map_pairs": 10_000, "map_preset": "none",
}  # fmt: skip
"""The 7x7 setting, the experiment's default before the paper-scale map: 7x7 codes of width
0.5, a 7x7 map on 10,000 views with the small-map schedule (``ReachConfig(**SMALL_MAP)``;
``sigmapi reach --grid 7 --code-width 0.5 --map-shape 7x7 --map-pairs 10000 --map-preset none``)."""


@dataclass(frozen=True)
class ReachConfig:
    """Everything one reach comparison depends on. Defaults: the 2-D task, saccade every step."""

    dim: int = 2
    """1 or 2: dimensions of the task."""
    grid: int = 15
    """Units per axis of the retina and gaze codes (15x15 in 2-D, the paper's Fig. 8 network)."""
    code_width: float = 1.0
    """Width of the input hills in grid units (1.0: the paper-2d preset; the 1-D paper: 0.5)."""
    step_size: float = 0.05
    """How far one move shifts z along an axis."""
    goal_radius: float = 0.1
    """Half-width of the goal box around z = 0.5 (straight ahead, within grasp range)."""
    saccade_rate: float = 1.0
    """Probability of a saccade per step (1: on every step, the hardest case)."""
    max_steps: int = 50
    """Time limit per episode (truncation): 3x the longest shortest path (16 moves in 2-D)."""
    map_shape: tuple[int, ...] = (15, 15)
    """Grid of the Sigma-Pi map learned in the environment (``sigmapi reach``: 12 in 1-D)."""
    map_pairs: int = 100_000
    """Saccade view pairs the map learns from (one SOM iteration each; paper-2d: 100,000)."""
    map_preset: str = "paper-2d"
    """The SOM preset the map learns with: its winner rule, schedules, ordering procedure and
    kernel tolerance (shapes, code width, length and seed come from this config). "none": the
    small-map schedule of :meth:`som_config` (the 7x7 setting: soft winner, random start)."""
    backend: str = "auto"
    """Kernel that learns and reads the map ("auto": the fast one when it is installed)."""
    model_path: str | None = None
    """A trained model file to use for every seed instead of learning a map per seed."""
    features: str = "response"
    """Map features: "response" (activations clipped at 0, L2-normalised; measured best) or
    "bump" (Gaussian around the winner on the map grid). 2-D, 5 seeds, 600 episodes: final
    success 0.971 with "response", 0.949 with "bump" (true z: 0.977), in the 7x7 setting."""
    feature_width: float = 1.0
    """Width of the bump features (map and true-z codes), in grid units."""
    episodes: int = 600
    """Episodes of reinforcement learning per seed and state."""
    seeds: int = 5
    """Number of independent seeds (maps, start states, action choices)."""
    seed: int = 0
    """Root seed; seed i of the run uses SeedSequence(seed).spawn child i."""
    block: int = 50
    """Episodes per point of the learning curves."""
    final_episodes: int = 200
    """The final success rate is measured over this many last episodes."""
    gamma: float = 0.9
    """Discount of the actor-critic (the authors: 0.9)."""
    critic_lr: float = 0.1
    """Learning rate of the critic (the authors: 0.1)."""
    actor_lr: float = 0.1
    """Learning rate of the actor (the authors: 0.1)."""
    beta: float = 2.0
    """Inverse temperature of the softmax policy (the authors: 2)."""
    states: tuple[str, ...] = STATES
    """State representations to compare."""

    def __post_init__(self) -> None:
        for name in ("episodes", "seeds", "block", "final_episodes", "map_pairs"):
            object.__setattr__(self, name, _validate.integer(name, getattr(self, name), 1))
        if self.final_episodes > self.episodes:
            raise ConfigError(
                f"final_episodes must be <= episodes ({self.episodes}), got {self.final_episodes}"
            )
        object.__setattr__(self, "seed", _validate.integer("seed", self.seed, 0))
        states = tuple(self.states)
        bad = [s for s in states if s not in STATES]
        if not states or bad or len(set(states)) != len(states):
            raise ConfigError(f"states must be distinct names from {STATES}, got {states!r}")
        object.__setattr__(self, "states", states)
        _validate.choice("features", self.features, FEATURES)
        _validate.choice("backend", self.backend, ("auto", *BACKENDS))
        _validate.choice("map_preset", self.map_preset, ("none", *list_presets()))
        object.__setattr__(self, "map_shape", tuple(int(n) for n in self.map_shape))
        self.make_env()  # validates the task's parameters
        _validate.integer("max_steps", self.max_steps, 1)
        ActorCritic(1, 1, self.gamma, self.critic_lr, self.actor_lr, self.beta)
        if self.model_path is None:  # the map is learned here: its weights and its views
            som = SigmaPiSOM(self.som_config(self.seed))
            n_in = self.grid**self.dim
            _memory.check(
                som.memory_estimate() + self.map_pairs * 4 * n_in * 8,
                f"the reach experiment's map ({'x'.join(map(str, self.map_shape))} units on "
                f"{n_in} x {n_in} inputs, {self.map_pairs} views)",
                "use a smaller --grid, --map-shape or --map-pairs",
            )

    def env_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :class:`GazeReachEnv` (also of ``gymnasium.make``)."""
        return {
            "dim": self.dim, "grid": self.grid, "code_width": self.code_width,
            "step_size": self.step_size, "goal_radius": self.goal_radius,
            "saccade_rate": self.saccade_rate,
        }  # fmt: skip

    def make_env(self) -> TimeLimit[Any, Any]:
        """The environment under its time limit (``max_steps``)."""
        return TimeLimit(GazeReachEnv(**self.env_kwargs()), max_episode_steps=self.max_steps)

    def som_config(self, seed: int) -> SOMConfig:
        """The map's config for ``map_pairs`` saccade views.

        With a ``map_preset`` (default ``paper-2d``): that preset, on this task's grids, code
        width, map, length (``map_pairs`` iterations) and backend. Its ordering procedure
        (``crossview``) orders a 15x15 map on every seed measured (README).

        ``map_preset="none"``, the small-map schedule: the neighbourhood shrinks from the map's
        size to 30 % of it over the first 30 % of the run, then to 0.7 units at 80 %: a longer
        ordering phase and a wider final
        neighbourhood than the paper's 300,000-iteration 1-D schedule, because a 2-D map
        trained on only ~10^4 views twists under the paper's schedule shape (measured: order
        R^2 0.1 vs 0.5 on a 7x7 map, 10,000 views).
        """
        inputs = (self.grid,) * self.dim
        if self.map_preset != "none":
            return load_preset(self.map_preset).replace(
                map_shape=self.map_shape, x_shape=inputs, y_shape=inputs,
                code_width=self.code_width, iterations=self.map_pairs, backend=self.backend,
                seed=seed,
            )  # fmt: skip
        m = float(max(self.map_shape))
        return SOMConfig(
            map_shape=self.map_shape, x_shape=inputs, y_shape=inputs, code_width=self.code_width,
            iterations=self.map_pairs, backend=self.backend, seed=seed,
            sigma=((0.0, m), (0.3, max(m / 3.5, 1.0)), (0.8, 0.7)),
        )  # fmt: skip

    def replace(self, **changes: Any) -> ReachConfig:
        names = {f.name for f in dataclasses.fields(self)}
        bad = sorted(set(changes) - names)
        if bad:
            raise ConfigError(
                f"unknown ReachConfig field {bad[0]!r}; valid: {', '.join(sorted(names))}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return {
            k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()
        }
