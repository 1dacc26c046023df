"""The settings of one reach comparison, in four frozen parts (:class:`ReachConfig`): the world
(:class:`~sigmapi.envs.GazeReachConfig`), the map (:class:`MapConfig`), the learner
(:class:`~sigmapi.agents.ActorCriticConfig`) and the run (:class:`ReachRunConfig`); the seeds
are not settings (they are given to the run).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from sigmapi import _validate
from sigmapi._outputs import INPUT
from sigmapi.agents import ActorCriticConfig
from sigmapi.codes import PopulationCode
from sigmapi.config import BACKEND_NAMES, SOMConfig, list_presets
from sigmapi.envs import FEATURES, STATES, GazeReachConfig, learn_map_in_env
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.episodes import check_episode_run
from sigmapi.experiments.kit.jobs import Tick
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.parts import Parts, check_part_types, count_field
from sigmapi.experiments.kit.results import JSON
from sigmapi.experiments.kit.worlds import GAZE_REACH, World
from sigmapi.model.som import SigmaPiSOM


def default_map_shape(dim: object) -> tuple[int, ...]:
    """The map of a ``dim``-D task when none is given: 15x15 in 2-D (paper-2d), 12 units in 1-D."""
    return (15, 15) if dim == 2 else (12,)


class MapParts(Parts):
    """A config of parts whose ``env`` is a world's settings and whose ``map`` a
    :class:`MapConfig` (the reach and reward configs): each part is of its class
    (:func:`~sigmapi.experiments.kit.parts.check_part_types`), and the map has an axis per
    dimension of the world's task (a ConfigError naming the first that is not)."""

    if TYPE_CHECKING:
        env: GazeReachConfig
        map: MapConfig

    def __post_init__(self) -> None:
        check_part_types(self, self.PARTS)
        dim, shape = self.env.dim, self.map.map_shape
        if len(shape) != dim:
            axes = "1 axis" if dim == 1 else f"{dim} axes"
            raise ConfigError(
                f"map_shape must have {axes} for a task of dim {dim}, got "
                f"{'x'.join(map(str, shape))} ({len(shape)}-D); give map_shape "
                f"{'x'.join(map(str, default_map_shape(dim)))} (the dim-{dim} default), or "
                f"dim {len(shape)} for a {len(shape)}-D task"
            )

    def som_config(self, seed: int, world: World = GAZE_REACH) -> SOMConfig:
        """The config of the map of seed ``seed``, on the codes of ``world``
        (:meth:`MapConfig.in_world`)."""
        return self.map.in_world(world, self.env, seed)


@dataclass(frozen=True)
class MapConfig:
    """The Sigma-Pi map a reach learner reads: its size, how it learns, how it is read."""

    map_shape: tuple[int, ...] = field(
        default=(15, 15), metadata=_validate.bounded("ints", 1, 1024, count=2, fix="e.g. 15x15")
    )
    """Grid of the Sigma-Pi map learned in the environment (a 1-D task given without one
    gets a map of 12 units)."""
    iterations: int = field(
        default=100_000,
        metadata=_validate.bounded("int", 1, 100_000_000, fix="paper-2d runs 100000"),
    )
    """Iterations of the map, one per saccade view pair it learns from (paper-2d's length)."""
    preset: str = "paper-2d"
    """The SOM preset the map learns with: its winner rule, schedules, ordering procedure and
    kernel tolerance (the codes come from the world, the size, length and seed from here;
    "small-2d": the 7x7 map of the quick run)."""
    backend: str = "auto"
    """Kernel that learns and reads the map ("auto": the fast one when it is installed)."""
    model_path: str | None = field(default=None, metadata=INPUT)
    """A trained model file to use for every seed instead of learning a map per seed."""
    features: str = "response"
    """Map features: "response" (activations clipped at 0, L2-normalised) or "bump" (Gaussian
    around the winner on the map grid)."""
    feature_width: float = field(
        default=1.0,
        metadata=_validate.bounded("number", 0, _validate.MAX_WIDTH, lo_open=True, fix="e.g. 1.0"),
    )
    """Width of the bump features (map and true-z codes), in grid units."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "map_shape", _validate.shape("map_shape", self.map_shape))
        _validate.check_fields(self)
        _validate.choice("preset", self.preset, list_presets())
        _validate.choice("backend", self.backend, BACKEND_NAMES)
        if self.model_path is not None and not isinstance(self.model_path, str):
            raise _validate.fail("model_path", "a file name or None", self.model_path)
        _validate.choice("features", self.features, FEATURES)

    def learn(
        self,
        world: World,
        settings: object,
        seed: int,
        views: np.random.Generator,
        tick: Tick | None = None,
    ) -> SigmaPiSOM:
        """The map of seed ``seed`` learned in ``world`` as ``settings`` make it (from its
        saccade views, drawn from ``views``: :func:`~sigmapi.envs.learn_map_in_env`); the map
        is built with the seed itself, its weights' streams the seed's
        (:mod:`sigmapi.experiments.kit.seeds`); ``tick`` is told that the map learns."""
        som = self.in_world(world, settings, seed)
        told = None if tick is None else lambda model: tick(0, "learning the map")
        return learn_map_in_env(world.make_env(settings), som, seed=views, callback=told)

    def in_world(self, world: World, settings: object, seed: int) -> SOMConfig:
        """The map's config on the codes of ``world`` as ``settings`` make it
        (:meth:`som_config`)."""
        source = world.source(settings)
        return self.som_config(source.x_code, source.y_code, seed)

    def som_config(self, x_code: PopulationCode, y_code: PopulationCode, seed: int) -> SOMConfig:
        """The map's config for views coded by ``x_code`` and ``y_code`` (the world's codes):
        the ``preset`` (:class:`~sigmapi.experiments.kit.maps.MapSpec`) on them, with this
        map's shape, length (``iterations``) and backend."""
        same = ("width", "height", "normalize", "periodic")
        if any(getattr(x_code, k) != getattr(y_code, k) for k in same):
            raise ConfigError(
                f"a map's x and y codes differ only in shape, got {x_code} and {y_code}"
            )
        shapes = {"x_shape": x_code.shape, "y_shape": y_code.shape, "map_shape": self.map_shape}
        codes = {f"code_{k}": getattr(x_code, k) for k in same[:3]}  # code_width, ...
        run = {"iterations": self.iterations, "backend": self.backend, "seed": seed}
        return MapSpec(self.preset).config(**shapes, **codes, periodic=x_code.periodic, **run)


@dataclass(frozen=True)
class ReachRunConfig:
    """What is compared and for how long: the states, the episodes, the curves' blocks."""

    states: tuple[str, ...] = STATES
    """State representations to compare."""
    episodes: int = count_field(600)
    """Episodes of reinforcement learning per seed and state."""
    block: int = count_field(50)
    """Episodes per point of the learning curves."""
    final_episodes: int = count_field(200)
    """The final success rate is measured over this many last episodes."""
    plateau_rise: float = field(
        default=0.05,
        metadata=_validate.bounded(
            "number", 0, 1, lo_open=True, fix="a share of success rate, e.g. 0.05"
        ),
    )
    """A learner has levelled off when its success rate rises by less than this over the last
    final_episodes episodes (a line fitted to each seed's episodes there, mean over seeds);
    the figure and the table name every learner that has not."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        check_episode_run(self)


@dataclass(frozen=True)
class ReachConfig(MapParts):
    """Everything one reach comparison depends on, but its seeds. Defaults: the 2-D task, a
    saccade on every step, the paper-2d map, the authors' actor-critic, 600 episodes."""

    env: GazeReachConfig = field(default_factory=GazeReachConfig)
    """The world and its time limit."""
    map: MapConfig = field(default_factory=MapConfig)
    """The map learned in the world."""
    agent: ActorCriticConfig = field(default_factory=ActorCriticConfig)
    """The learner."""
    run: ReachRunConfig = field(default_factory=ReachRunConfig)
    """The states, episodes and curves."""

    def replace(self, **changes: object) -> ReachConfig:
        """A copy with ``changes``, fields of any part by name (``grid=7, episodes=150``)."""
        if "dim" in changes and "map_shape" not in changes:  # the default map follows the task
            changes = {**changes, "map_shape": default_map_shape(changes["dim"])}
        return super().replace(**changes)


SMALL_PRESET = "small-2d"
"""The preset of the 7x7 setting: 7x7 codes of width 0.5, a 7x7 map on 10,000 views with the
small-map schedule (:func:`preset_setting`)."""


def preset_setting(name: str) -> JSON:
    """The fields of a reach config that the 2-D preset ``name`` fixes: the world's grid and
    code width (the preset's square ``x_shape`` and ``code_width``), the map's shape and
    length, and the preset itself. ``ReachConfig().replace(**preset_setting("small-2d"))``
    is ``sigmapi reach --grid 7 --code-width 0.5 --map-shape 7x7 --iterations 10000 --preset
    small-2d``."""
    cfg = MapSpec(name).config()
    if len(cfg.x_shape) != 2 or cfg.x_shape[0] != cfg.x_shape[1] or cfg.x_shape != cfg.y_shape:
        raise ConfigError(
            f"preset {name!r} has x_shape {cfg.x_shape} and y_shape {cfg.y_shape}; a reach "
            "setting needs square 2-D codes of one grid, e.g. small-2d"
        )
    return {
        "grid": cfg.x_shape[0],
        "code_width": cfg.code_width,
        "map_shape": cfg.map_shape,
        "iterations": cfg.iterations,
        "preset": name,
    }


SMALL = ReachConfig().replace(**preset_setting(SMALL_PRESET))
"""The 7x7 setting (:data:`SMALL_PRESET`): the world and map of the quick run and of reward."""
