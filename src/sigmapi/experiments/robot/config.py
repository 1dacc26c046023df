"""The settings of one robot run, in four frozen parts as the reach experiment's
(:class:`RobotConfig`): the docking world and how the map's view pairs are recorded in it
(:class:`RobotEnvConfig`, the settings of :data:`ROBOT_WORLD`), the map (:class:`RobotMapConfig`),
the learner and the run (:class:`RobotRunConfig`). Its JSON form is flat (one table of every
part's fields, as the robot's results have always been written).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym

from sigmapi import _validate
from sigmapi._outputs import OUTPUT
from sigmapi.agents import ActorCriticConfig
from sigmapi.config import BACKEND_NAMES
from sigmapi.envs import FEATURES, STATES, Features, TrueZObservation, make_state_env
from sigmapi.envs.robot.env import ENV_ID
from sigmapi.envs.robot.frames import RETINA_SOURCES
from sigmapi.envs.robot.views import RobotViews
from sigmapi.errors import ConfigError
from sigmapi.experiments.kit.episodes import check_episode_run
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.parts import Parts, check_part_types, count_field, parts_dict
from sigmapi.experiments.kit.results import as_object, tuples
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import World, register_world
from sigmapi.model.som import SigmaPiSOM

PLAN = SeedPlan({"views": 5, "starts": 6, "agent": 7, "film": 8})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): children of
``SeedSequence(seed)``, apart from the map's own (the map is built with the seed)."""


@dataclass(frozen=True)
class RobotEnvConfig:
    """The docking world (:class:`~sigmapi.envs.robot.RobotDockEnv`) and how the map's view
    pairs are recorded in it."""

    grid: int = field(
        default=12,
        metadata=_validate.bounded(
            "int", 2, 1024, fix="units per axis of the codes (grid**2 a view); e.g. 12"
        ),
    )
    """Units per axis of the retina and gaze codes."""
    code_width: float = field(default=1.0, metadata=_validate.bounded("width", 0, lo_open=True))
    """Width of the codes' hills, grid units."""
    moved_share: float = field(default=0.0, metadata=_validate.bounded("number", 0, 1))
    """Share of recorded pairs in which the ball moved between the two views (a nuisance)."""
    retina: str = "projection"
    """Retinal position in the docking episodes: "projection" or "pixels" (rendered, slower)."""
    saccade_rate: float = field(default=1.0, metadata=_validate.bounded("number", 0, 1))
    """Probability of a saccade per docking step (1: the head looks around every step)."""
    max_steps: int = field(default=100, metadata=_validate.bounded("int", 1, 100_000))
    """Time limit of a docking episode (Gymnasium's TimeLimit)."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        _validate.choice("retina", self.retina, RETINA_SOURCES)

    def env_kwargs(self) -> dict[str, object]:
        """The docking world's keyword arguments (``gymnasium.make``'s, time limit included)."""
        world = ("grid", "code_width", "retina", "saccade_rate")  # moved_share: views only
        return {**{k: getattr(self, k) for k in world}, "max_episode_steps": self.max_steps}


@dataclass(frozen=True)
class RobotMapConfig:
    """The map learned from the recorded view pairs, its scoring and how the learner reads it."""

    map_shape: tuple[int, ...] = field(
        default=(8, 8), metadata=_validate.bounded("ints", 1, 1024, count=2, fix="e.g. 8x8")
    )
    """Grid of the Sigma-Pi map."""
    train_pairs: int = field(default=10_000, metadata=_validate.bounded("int", 1, 10_000_000))
    """View pairs recorded from saccades for the map (body and ball still)."""
    iterations: int = field(default=40_000, metadata=_validate.bounded("int", 1, 100_000_000))
    """Learning iterations of the map (the recorded pairs are used in passes)."""
    eval_pairs: int = count_field(3000)
    """Calibration and test pairs (each) that score the map against the true z."""
    backend: str = "auto"
    """Kernel that learns and reads the map ("auto": the fast one when it is installed)."""
    features: str = "response"
    """Map features: "response" (activations clipped at 0, L2-normalised) or "bump"."""
    feature_width: float = field(
        default=1.0, metadata=_validate.bounded("number", 0, _validate.MAX_WIDTH, lo_open=True)
    )
    """Width of the bump features (map and true-z codes), in grid units."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "map_shape", _validate.shape("map_shape", self.map_shape))
        _validate.check_fields(self)
        if len(self.map_shape) != 2:
            raise _validate.fail("map_shape", "2 axes (z is 2-D)", self.map_shape, "e.g. 8x8")
        _validate.choice("backend", self.backend, BACKEND_NAMES)
        _validate.choice("features", self.features, FEATURES)


@dataclass(frozen=True)
class RobotRunConfig:
    """What is compared and for how long: the states, the episodes, the curves' blocks."""

    episodes: int = count_field(400)
    """Docking episodes per seed and state."""
    final_episodes: int = count_field(100)
    """Final success is measured over this many last episodes."""
    block: int = count_field(50)
    """Episodes per point of the learning curves."""
    states: tuple[str, ...] = STATES
    """States compared: map, retina, retina_gaze, true_z."""
    render: str | None = field(default=None, metadata=OUTPUT)
    """Also write an animated GIF of one episode of the first seed's map learner (third-person
    and head cameras) to this file."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        check_episode_run(self)
        if self.render is not None and not str(self.render).lower().endswith(".gif"):
            raise _validate.fail("render", "a file name ending in .gif", self.render)
        if self.render is not None and "map" not in self.states:
            raise ConfigError(
                f"render films the map learner, but states {self.states!r} has no "
                "'map'; add map to --states, or drop --render"
            )


@dataclass(frozen=True)
class RobotConfig(Parts):
    """Everything one robot run depends on but its seeds (the CLI's options are its parts'
    fields)."""

    env: RobotEnvConfig = field(default_factory=RobotEnvConfig)
    """The docking world, its time limit and how view pairs are recorded."""
    map: RobotMapConfig = field(default_factory=RobotMapConfig)
    """The map learned from the recorded pairs."""
    agent: ActorCriticConfig = field(default_factory=ActorCriticConfig)
    """The learner (the authors' docking: gamma 0.9, learning rates 0.1, beta 2)."""
    run: RobotRunConfig = field(default_factory=RobotRunConfig)
    """The states, episodes and curves."""

    def __post_init__(self) -> None:
        check_part_types(self, self.PARTS)

    def state_env(
        self,
        state: str,
        model: SigmaPiSOM | None = None,
        world: World | None = None,
        **kwargs: object,
    ) -> gym.Env[Features, Any]:
        """The docking world through ``gymnasium.make`` (``world``, default
        :data:`ROBOT_WORLD`; its TimeLimit included; ``kwargs`` go to it too, e.g.
        ``render_mode="rgb_array"``) as ``state`` sees it (:mod:`sigmapi.envs.wrappers`);
        ``"true_z"`` codes z on the map's grid (like for like), ``"map"`` needs ``model``."""
        env, m = (world or ROBOT_WORLD).make_env(self.env, **kwargs), self.map
        if state == "true_z":
            return TrueZObservation(env, shape=m.map_shape, width=m.feature_width)
        return make_state_env(env, state, model, m.features, m.feature_width)

    def to_dict(self) -> dict[str, object]:
        """JSON-able and flat: every part's fields in one table (tuples as lists)."""
        return {k: v for table in parts_dict(self, self.PARTS).values() for k, v in table.items()}

    @classmethod
    def from_dict(cls, data: object) -> RobotConfig:
        """The config a :meth:`to_dict` wrote (an unknown field is a ConfigError naming the
        valid ones)."""
        return cls().replace(**tuples(as_object(data, "robot config")))


QUICK = RobotConfig().replace(
    train_pairs=3000, iterations=12_000, eval_pairs=1000, episodes=150, final_episodes=50, block=25
)
"""``sigmapi robot --quick``: a smaller map run and fewer episodes (minutes, not tens)."""


def _robot_source(settings: RobotEnvConfig) -> RobotViews:
    return RobotViews(settings.grid, settings.code_width, moved_share=settings.moved_share)


ROBOT_WORLD = register_world(
    World(
        name="robot",
        env_id=ENV_ID,
        settings=RobotEnvConfig,
        kwargs=RobotEnvConfig.env_kwargs,
        source=_robot_source,
        map=MapSpec("robot-2d"),
        seeds=(100, 101, 102, 103, 104),
    )
)
"""The simulated robot (:class:`~sigmapi.envs.robot.RobotDockEnv`, MuJoCo): its view pairs
are recorded from the still robot's saccades (``moved_share`` of them spoiled); its map is
the ``robot-2d`` preset; its default seeds are those of the acceptance run (none of them was
tuned on: tuning used 0-2)."""
