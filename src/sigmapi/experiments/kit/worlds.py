"""The worlds an embodied experiment learns its map in and acts in, by name (:data:`WORLDS`).

A new world (a humanoid) is one :func:`register_world` call; its callables are module-level
functions, so that a job carrying the world runs in another process. The gaze-and-reach world
is registered here (:data:`GAZE_REACH`), the simulated robot's in
:mod:`sigmapi.experiments.robot.config`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from sigmapi import _validate
from sigmapi.envs import ENV_ID, GazeReachConfig, GazeReachEnv
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.maps import MapSpec


@dataclass(frozen=True)
class World:
    """What an experiment needs of a world: its Gymnasium id, its settings (the ``env`` part of
    the reach and robot configs) and how they give ``gymnasium.make``'s arguments, the world as
    a view source, the map spec its map starts from and its default seeds."""

    name: str
    """Its name in :data:`WORLDS`."""
    env_id: str
    """Its Gymnasium id (registered with ``gymnasium.register``)."""
    settings: type
    """The frozen dataclass of its settings."""
    kwargs: Callable[[Any], dict[str, Any]]
    """``kwargs(settings)``: ``gymnasium.make``'s keyword arguments, time limit included."""
    source: Callable[[Any], Any]
    """``source(settings)``: the world as a view source, unwrapped (its codes, its saccade
    view pairs: how a map's data are recorded; the goal of a reach world)."""
    map: MapSpec
    """The map's preset (the run sets its codes, size, length, seed and backend)."""
    seeds: tuple[int, ...]
    """The default seeds of an experiment in this world."""

    def make_env(self, settings: object, **kwargs: Any) -> gym.Env[Any, Any]:
        """The environment of ``settings`` through ``gymnasium.make`` (its time limit
        included, without Gymnasium's checker); ``kwargs`` go to it too (``render_mode``)."""
        if not isinstance(settings, self.settings):
            raise _validate.fail(
                f"settings of world {self.name!r}", f"a {self.settings.__name__}", settings
            )
        return gym.make(self.env_id, **self.kwargs(settings), disable_env_checker=True, **kwargs)


WORLDS: dict[str, World] = {}
"""Every registered world by name."""


def register_world(world: World) -> World:
    """Add ``world`` to :data:`WORLDS` (its id must be registered with Gymnasium); returns it."""
    if world.env_id not in gym.registry:
        raise ConfigError(
            f"world {world.name!r}: Gymnasium id {world.env_id!r} is not "
            "registered; gymnasium.register it first"
        )
    if WORLDS.get(world.name, world) != world:
        raise ConfigError(f"world name {world.name!r} is taken; choose another")
    WORLDS[world.name] = world
    return world


def get_world(name: str) -> World:
    """The world ``name`` (a ConfigError naming the registered ones)."""
    if name not in WORLDS:
        raise ConfigError(f"unknown world {name!r}; registered: {', '.join(sorted(WORLDS))}")
    return WORLDS[name]


def _gaze_kwargs(settings: GazeReachConfig) -> dict[str, object]:
    return {**settings.env_kwargs(), "max_episode_steps": settings.max_episode_steps}


def _gaze_source(settings: GazeReachConfig) -> GazeReachEnv:
    return GazeReachEnv(**settings.env_kwargs())


GAZE_REACH = register_world(
    World(
        name="gaze-reach",
        env_id=ENV_ID,
        settings=GazeReachConfig,
        kwargs=_gaze_kwargs,
        source=_gaze_source,
        map=MapSpec("paper-2d"),
        seeds=(0, 1, 2, 3, 4),
    )
)
"""The gaze-and-reach world (:class:`~sigmapi.envs.GazeReachEnv`), the reach and reward
experiments' default."""
