"""The settings of one iCub run: the frames check, the two maps, babbling and the reaches.

One flat frozen dataclass (:class:`ICubConfig`), a docstring under each field, so that the
command-line options of ``sigmapi icub`` are its fields.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from sigmapi import _validate
from sigmapi._outputs import OUTPUT
from sigmapi.codes import _WIDTH_FIX, MIN_WIDTH
from sigmapi.config import BACKEND_NAMES
from sigmapi.envs.icub import ENV_ID, EYE_SIZE, ICubViews
from sigmapi.envs.icub.frames import BALLS, PAIRS_PER_BALL
from sigmapi.envs.icub.views import GRID
from sigmapi.experiments.icub.maps import HEAD_WIDTH, MAP
from sigmapi.experiments.icub.reaching import BABBLE_WRIST, BABBLE_YAW
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.kit.worlds import World, register_world

PLAN = SeedPlan({"views": 5, "babbling": 6, "reaches": 7, "servo": 8})
"""The random streams of one seed, on the table and in the box (children of
``SeedSequence(seed)``, :mod:`sigmapi.experiments.kit.seeds`); the maps are built with the
seed itself, their streams the seed's own."""

SPACES = ("table", "box")
"""Where the balls are: on the table, seen by the right eye (the 2-D task), or hanging
anywhere in a box within the arm's reach, seen by both eyes (the 3-D task,
:mod:`~sigmapi.experiments.icub.reach3d`)."""

TEST_BALLS = ("reachable", "box")
"""Where the experimenter puts the 3-D reach tests' balls (:attr:`ICubConfig.box_balls`):
"reachable" (uniform in the box, kept when the scripted IK rests the ball on the palm within
1 cm, :data:`~sigmapi.experiments.icub.reach3d.REACHABLE`) or "box" (uniform in the box,
every one, the far corners beyond the arm included)."""
TEST_BALL = "reachable"
"""Where the 3-D reach tests' balls are put by default (:data:`TEST_BALLS`)."""

BABBLINGS = ("offered", "swept")
"""How a 3-D babble meets its ball (:attr:`ICubConfig.box_babbling`,
:func:`~sigmapi.experiments.icub.reach3d.babble3d`): "offered" (the arm takes a random
posture; where its palm lies where balls are met, the experimenter presses a ball onto it, a
choice that reads the palm's true place) or "swept" (the experimenter holds a ball at a random
point of the box; the arm moves from the reach's start toward a random posture and stops at
its first touch: no truth read but the ball's place). Either way the skin and both eyes keep
it."""
BABBLING = "offered"
"""How 3-D babbles meet their balls by default (:data:`BABBLINGS`)."""

HEAD_CODES = ("winner", "centroid", "response")
"""What map 1 can hand to map 2 (:meth:`~sigmapi.experiments.icub.maps.ChainMaps.head`)."""
READOUTS = ("centroid", "winner")
"""What of map 2 can key the learned chain's association (:attr:`ICubConfig.readout`)."""

_WRIST_FIX = "the joint's range is -1.396 to 0.436 rad; e.g. --babble-wrist=-0.6,-0.3"


@dataclass(frozen=True)
class ICubEnvConfig:
    """The iCub's world in the experiment kit (:data:`ICUB_WORLD`): the Gym id's settings and
    how map 1's view pairs are recorded (:class:`~sigmapi.envs.icub.ICubViews`). The fields
    it shares with :class:`ICubConfig` are declared here once."""

    grid: int = field(default=GRID, metadata=_validate.bounded("int", 3, 64, fix="e.g. 16"))
    """Units per axis of map 1's codes (the retina's and the eye angles')."""
    code_width: float = field(
        default=1.0, metadata=_validate.bounded("width", MIN_WIDTH, fix=_WIDTH_FIX)
    )
    """Width of the codes' hills, grid units."""
    moved_share: float = field(default=0.1, metadata=_validate.bounded("number", 0, 1))
    """Share of the view pairs in which the experimenter moved the ball between the views."""
    balls: str = field(default="table", metadata=_validate.bounded("choice", options=BALLS))
    """Where the experimenter puts the balls (:data:`~sigmapi.envs.icub.frames.BALLS`)."""
    pairs_per_ball: int = field(
        default=PAIRS_PER_BALL, metadata=_validate.bounded("int", 1, 100, fix="e.g. 2")
    )
    """Pairs of views the robot records of one ball before the next is put down."""
    eye_size: int = field(
        default=EYE_SIZE, metadata=_validate.bounded("int", 8, 240, fix=f"e.g. {EYE_SIZE}")
    )
    """Side of each eye's square image, pixels."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)

    def env_kwargs(self) -> dict[str, object]:
        """``gymnasium.make``'s keyword arguments for ``sigmapi/ICubReach-v0`` (its episodes
        are one reach long: no time limit)."""
        return {"eye_size": self.eye_size}

    def views(self) -> ICubViews:
        """Map 1's view source with these settings (its scene built at first use)."""
        return ICubViews(
            self.grid,
            self.code_width,
            self.moved_share,
            self.balls,
            self.pairs_per_ball,
            self.eye_size,
        )


def _env_field(name: str) -> Any:
    """A field of :class:`ICubConfig` that is :class:`ICubEnvConfig`'s ``name``: its default
    and bounds."""
    f = ICubEnvConfig.__dataclass_fields__[name]
    return field(default=f.default, metadata=f.metadata)


SEEDS = (123, 124, 125, 126, 127)
"""The seeds of the 2-D acceptance run (``sigmapi icub``'s and the iCub world's default): none
of them was tuned on (the tuning seeds are 0-2; the seeds earlier versions were checked on:
docs/results/icub-history.md)."""

ICUB_WORLD = register_world(
    World(
        name="icub",
        env_id=ENV_ID,
        settings=ICubEnvConfig,
        kwargs=ICubEnvConfig.env_kwargs,
        source=ICubEnvConfig.views,
        map=MAP,
        seeds=SEEDS,
    )
)
"""The iCub on the table (``sigmapi/ICubReach-v0``): its view source is map 1's, the right
eye's retina and eye angles from saccades with the head still
(:class:`~sigmapi.envs.icub.ICubViews`), its map the ``icub-2d`` preset, its seeds the 2-D
acceptance run's. Map 2 (the neck), the chain and the 3-D box are the ``icub`` experiment's
own: a kit world has one view source and one map."""


@dataclass(frozen=True)
class ICubConfig:
    """Everything one iCub run depends on but its seeds (the CLI's options are its fields)."""

    space: str = field(default="table", metadata=_validate.bounded("choice", options=SPACES))
    """Where the balls are: "table" (the 2-D task: on the table, the right eye) or "box"
    (the 3-D task: in the air, both eyes; it reads the ``box_*`` fields, ``babble_yaw``,
    ``babble_wrist``, ``epochs``, ``reaches`` and ``backend``)."""
    grid: int = _env_field("grid")
    """Units per axis of the population codes (retina, eye angles, neck angles)."""
    code_width: float = _env_field("code_width")
    """Width of the codes' hills, grid units."""
    map_shape: tuple[int, ...] = field(
        default=(8, 8),
        metadata=_validate.bounded("ints", 1, 64, count=2, exact=True, fix="e.g. 8x8"),
    )
    """Grid of each Sigma-Pi map (map 1 and map 2)."""
    train_pairs: int = field(
        default=6000, metadata=_validate.bounded("int", 1, 1_000_000, fix="e.g. 6000")
    )
    """View pairs per map (saccades of the eyes for map 1, turns of the head for map 2)."""
    iterations: int = field(
        default=40_000, metadata=_validate.bounded("int", 1, 100_000_000, fix="e.g. 40000")
    )
    """Learning iterations of each map."""
    balls: str = _env_field("balls")
    """Where the experimenter puts the balls of the maps' views (training and scoring):
    "table" (uniform on a rectangle of the table, as the robot would meet them) or
    "directions" (uniform in the torso-centred directions map 2 is scored in)."""
    pairs_per_ball: int = _env_field("pairs_per_ball")
    """Pairs of views the robot records of one ball (each after its own head turn) before the
    experimenter puts down the next."""
    moved_share: float = _env_field("moved_share")
    """Share of the view pairs in which the ball moved between the two views."""
    head_code: str = field(
        default="winner", metadata=_validate.bounded("choice", options=HEAD_CODES)
    )
    """What map 1 hands to map 2: "winner" (a code of its winner's place), "centroid" (of its
    response's centre of mass near the winner) or "response"."""
    head_width: float = field(
        default=HEAD_WIDTH,
        metadata=_validate.bounded("width", MIN_WIDTH, fix=f"map-1 units; e.g. {HEAD_WIDTH}"),
    )
    """Width of the hill, map-1 units, of the code of map 1's place that map 2 reads
    (``head_code`` "winner" or "centroid":
    :data:`~sigmapi.experiments.icub.maps.HEAD_WIDTH`)."""
    eval_pairs: int = field(
        default=1000, metadata=_validate.bounded("int", 1, 100_000, fix="e.g. 1000")
    )
    """Calibration and test pairs (each, per map) that score the maps against the true
    directions."""
    frame_scenes: int = field(
        default=1000,
        metadata=_validate.bounded("int", 1, 20_000, fix="e.g. 1000"),
    )
    """Random scenes in which the rendered retina is compared with the exact projection."""
    babble_yaw: float = field(
        default=BABBLE_YAW,
        metadata=_validate.bounded("number", -0.65, 1.3, fix="the joint's range is -0.65 to 1.40"),
    )
    """The lowest shoulder yaw babbling draws, radians (the joint's range is -0.65 to 1.40:
    :data:`~sigmapi.experiments.icub.reaching.BABBLE_YAW`)."""
    babble_wrist: tuple[float, ...] = field(
        default=BABBLE_WRIST,
        metadata=_validate.bounded("numbers", -1.39, 0.43, count=2, exact=True, fix=_WRIST_FIX),
    )
    """The range (low, high) of the wrist's pitch that babbling draws from, radians (the
    joint's range is -1.396 to 0.436: :data:`~sigmapi.experiments.icub.reaching.BABBLE_WRIST`;
    on the command line ``--babble-wrist=-0.6,-0.3``)."""
    babbles: int = field(
        default=2000, metadata=_validate.bounded("int", 50, 1_000_000, fix="e.g. 2000")
    )
    """Babbles (random arm postures, the eyes on the hand) the associations learn from."""
    epochs: int = field(default=8, metadata=_validate.bounded("int", 1, 10_000, fix="e.g. 8"))
    """Passes of the associations' delta rule over the babbles."""
    readout: str = field(default="centroid", metadata=_validate.bounded("choice", options=READOUTS))
    """Where on map 2 the learned chain's bump is centred: "centroid" (the centre of mass of
    map 2's rectified response within 2 units of its winner) or "winner" (the winner's place
    on the grid)."""
    feature_width: float = field(default=2.5, metadata=_validate.bounded("width", 0, lo_open=True))
    """Width of the bump a map's winner gives the association, map units."""
    reaches: int = field(default=60, metadata=_validate.bounded("int", 1, 100_000, fix="e.g. 60"))
    """Reaches per seed and method (random reachable balls, random gazes)."""
    servo_steps: int = field(default=3, metadata=_validate.bounded("int", 0, 100, fix="e.g. 3"))
    """Glances of the learned servo that correct each associated method's posture, reached
    again beside the posture of the first view alone (0: no servo)."""
    box_pairs: int = field(
        default=1500, metadata=_validate.bounded("int", 1, 1_000_000, fix="e.g. 1500")
    )
    """View pairs per 3-D map (``space`` "box": eye movements for map H, head turns for map
    T)."""
    box_iterations: int = field(
        default=30_000, metadata=_validate.bounded("int", 1, 100_000_000, fix="e.g. 30000")
    )
    """Learning iterations of each 3-D map (``space`` "box")."""
    box_eval_pairs: int = field(
        default=300, metadata=_validate.bounded("int", 1, 100_000, fix="e.g. 300")
    )
    """Calibration and test pairs (each, per map) that score the 3-D maps (``space``
    "box")."""
    box_babbles: int = field(
        default=1500, metadata=_validate.bounded("int", 50, 1_000_000, fix="e.g. 1500")
    )
    """Babbles (random arm postures whose palm felt a ball in the box, both eyes on the ball)
    of the 3-D task (``space`` "box")."""
    box_feature_width: float = field(
        default=1.0, metadata=_validate.bounded("width", 0, lo_open=True)
    )
    """Width of the bump map T's winner (or the true position) gives the 3-D task's
    association, map units (``space`` "box")."""
    box_restarts: int = field(
        default=3, metadata=_validate.bounded("int", 1, 10, fix="e.g. 1 (one fit) or 3")
    )
    """Fits of each part of map T, each kept by its own fold score on the robot's view pairs
    (``space`` "box"; :func:`~sigmapi.experiments.icub.space3d.learn_chain3d`'s
    ``restarts``; 1: one fit)."""
    box_babbling: str = field(
        default=BABBLING, metadata=_validate.bounded("choice", options=BABBLINGS)
    )
    """How the 3-D task's babbles meet their balls (``space`` "box"): "offered" (the
    experimenter presses a ball onto the palm where the palm lies in the box) or "swept" (the
    arm sweeps toward a random posture into a ball held at a random point of the box, kept at
    the palm's first touch)."""
    box_balls: str = field(
        default=TEST_BALL, metadata=_validate.bounded("choice", options=TEST_BALLS)
    )
    """Where the experimenter puts the 3-D reach tests' balls (``space`` "box"): "reachable"
    (uniform in the box, kept when the scripted IK rests the ball on the palm within 1 cm) or
    "box" (uniform in the box, every one); the JSON's ``balls`` pools the reaches over the
    reachable ones apart."""
    backend: str = field(
        default="auto", metadata=_validate.bounded("choice", options=BACKEND_NAMES)
    )
    """Kernel that learns and reads the maps ("auto": the fast one when it is installed)."""
    render: str | None = field(default=None, metadata=OUTPUT)
    """Also write an animated GIF of the first seed's first learned reach to this file: a
    name ending in .gif (e.g. reach.gif)."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)  # the bounds declared beside the fields
        object.__setattr__(self, "babble_wrist", _wrist_range(self.babble_wrist))
        if self.render is not None and not str(self.render).lower().endswith(".gif"):
            raise _validate.fail("render", "a file name ending in .gif", self.render)

    @property
    def env(self) -> ICubEnvConfig:
        """The settings it shares with the iCub's kit world (:data:`ICUB_WORLD`)."""
        shared = (f.name for f in dataclasses.fields(ICubEnvConfig) if f.name != "eye_size")
        return ICubEnvConfig(**{k: getattr(self, k) for k in shared})

    def replace(self, **changes: Any) -> ICubConfig:
        """A copy with ``changes``."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, object]:
        """JSON-able (tuples as lists)."""
        return {
            k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()
        }


def _wrist_range(value: Any) -> tuple[float, float]:
    """``babble_wrist`` checked: two numbers, low <= high, within the wrist pitch's range."""
    fix = _WRIST_FIX
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise _validate.fail("babble_wrist", "two numbers (low, high)", value, fix)
    lo, hi = (_validate.number("babble_wrist", w, -1.39, 0.43, fix=fix) for w in value)
    if lo > hi:
        raise _validate.fail("babble_wrist", "(low, high) with low <= high", value, fix)
    return lo, hi


QUICK = ICubConfig(
    train_pairs=2500,
    iterations=15_000,
    eval_pairs=500,
    frame_scenes=200,
    babbles=800,
    epochs=6,
    reaches=30,
    box_pairs=300,
    box_eval_pairs=100,
    box_babbles=400,
)
"""``sigmapi icub --quick``: smaller maps' data, fewer babbles and reaches (minutes)."""
