"""The iCub's frames, measured: views of a point from random gazes, and their true directions.

A *view* of a point (the ball, or the palm) is what the robot measures of it at one gaze: the
right eye's retinal position ``(u, v)`` (pixels), the six gaze angles
(:data:`~sigmapi.envs.icub.scene.GAZE`) and, for analysis only, the point's head-centred and
torso-centred directions ``(azimuth, elevation)`` (radians;
:meth:`~sigmapi.envs.icub.scene.ICubScene.head_direction`,
:meth:`~sigmapi.envs.icub.scene.ICubScene.torso_direction`).

- :func:`random_gaze` draws a gaze that keeps a point in the right eye's view (uniform in
  :data:`GAZE_LOW`..:data:`GAZE_HIGH`, redrawn until the point lies at least ``margin`` pixels
  inside the image); ``neck=`` keeps the neck where it is (a saccade of the eyes only).
- :func:`view_pairs` records pairs of views of one still point: ``stage="eyes"`` (the head
  still: the pair shares the neck angles and thus the head-centred direction, drawn first and
  uniform in :data:`HEAD_BOX`) or ``"head"``
  (the neck turns too: the pair shares the torso-centred direction); a ``moved_share`` of the
  pairs see the ball moved between the views (a nuisance the learner must live with).
- :func:`direction_ball` draws balls on the table whose torso-centred directions are uniform
  in :data:`TORSO_BOX` (the maps' views; a ball for which no gaze gives a pair of views is
  drawn again); :func:`random_ball` uniform in a table area
  (the reaches, in :data:`REACH_REGION`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.envs.icub.scene import ICubScene
from sigmapi.errors import ConfigError

__all__ = [
    "GAZE_HIGH",
    "GAZE_LOW",
    "HEAD_BOX",
    "MOVE",
    "REACH_REGION",
    "TORSO_BOX",
    "ViewBatch",
    "direction_ball",
    "measure",
    "neck_for",
    "random_ball",
    "random_gaze",
    "random_neck",
    "view_pairs",
]

Array = NDArray[np.float64]

GAZE_LOW = np.radians([-35.0, -30.0, 0.0, -40.0, 0.0, -40.0])
"""Lower bounds of the random gazes (eye tilt, version, vergence, neck pitch, roll, yaw),
radians: within the joints' ranges; the neck's roll is held at zero."""
GAZE_HIGH = np.radians([10.0, 30.0, 20.0, 0.0, 0.0, 40.0])
"""Upper bounds of the random gazes, radians."""
TORSO_BOX = np.radians([[-50.0, 20.0], [-82.0, -48.0]])
"""The torso-centred directions (azimuth, elevation rows; radians) the balls of the maps'
views are drawn from, uniformly: a part of the table around the arm's reach (in these
coordinates a near rectangle on the table: 0.1-0.4 m ahead, 0.45 m right to 0.15 m left)."""
HEAD_BOX = np.radians([[-30.0, 30.0], [-50.0, -15.0]])
"""The head-centred directions (azimuth, elevation rows) the views' necks put the ball at,
uniformly (:func:`neck_for`): the head turns so that the ball lies anywhere in this part of
its field; a neck outside the neck's range is drawn again."""
MOVE = 0.06
"""How far a moved ball moves between two views (uniform in +-MOVE along x and y, metres)."""
REACH_REGION = ((0.14, 0.31), (-0.36, 0.08))
"""The table area (world x and y) the reaching tests draw balls from (the scripted inverse
kinematics' reach, measured on a grid: ``docs/guide/icub.md``)."""


def random_ball(rng: np.random.Generator, n: int, region: tuple = REACH_REGION) -> Array:
    """``n`` ball positions ``(n, 2)`` (world x, y), uniform in ``region``."""
    (x0, x1), (y0, y1) = region
    return np.column_stack([rng.uniform(x0, x1, n), rng.uniform(y0, y1, n)])


def direction_ball(scene: ICubScene, rng: np.random.Generator, n: int) -> Array:
    """``n`` ball positions ``(n, 2)`` (world x, y) whose torso-centred directions are
    uniform in :data:`TORSO_BOX`."""
    d = rng.uniform(TORSO_BOX[:, 0], TORSO_BOX[:, 1], (n, 2))
    return scene.table_point(d)[:, :2]


def random_gaze(
    scene: ICubScene,
    point: ArrayLike,
    rng: np.random.Generator,
    *,
    neck: ArrayLike | None = None,
    head_box: NDArray[np.float64] | None = None,
    margin: float = 4.0,
    tries: int = 2000,
) -> Array:
    """A random gaze (set on ``scene``) that keeps world ``point`` in the right eye's image,
    at least ``margin`` pixels inside; ``neck`` (3 angles) holds the neck there, else a neck
    is drawn (until the point's head-centred direction lies in ``head_box``, when given)."""
    lo, hi = GAZE_LOW.copy(), GAZE_HIGH.copy()
    p = np.asarray(point, dtype=np.float64)
    size = scene.eye_size
    for _ in range(tries):
        g = rng.uniform(lo, hi)
        if neck is not None:
            g[3:] = neck
        elif head_box is not None:
            scene.set_gaze(g)
            h = scene.head_direction(p)
            if np.any(h < head_box[:, 0]) or np.any(h > head_box[:, 1]):
                continue
        scene.set_gaze(g)
        u, v = scene.project(p)[0]
        if margin <= u <= size - margin and margin <= v <= size - margin:
            return g
    raise ConfigError(
        f"no gaze within {tries} tries keeps the point {np.round(p, 3).tolist()} in view; "
        "draw points on the table (sigmapi.envs.icub.frames.direction_ball)"
    )


def neck_for(
    scene: ICubScene, point: ArrayLike, head: ArrayLike, iterations: int = 10
) -> Array | None:
    """Neck angles (pitch, roll 0, yaw) that put world ``point`` at head-centred direction
    ``head`` (azimuth, elevation), by Newton steps on a finite-difference Jacobian (the eyes
    as they are); None when they fall outside the neck's random range or miss ``head`` by
    more than 1e-4 rad."""
    p, goal = np.asarray(point, dtype=np.float64), np.asarray(head, dtype=np.float64)
    g = scene.gaze()
    g[3], g[4], g[5] = 0.0, 0.0, 0.0
    scene.set_gaze(g)
    t = scene.torso_direction(p)
    g[3], g[5] = t[1] - goal[1], t[0] - goal[0]  # first guess: head = torso - neck
    for _ in range(iterations):
        scene.set_gaze(g)
        err = scene.head_direction(p) - goal
        if np.max(np.abs(err)) < 1e-6:
            break
        jac = np.zeros((2, 2))
        for k, idx in enumerate((3, 5)):
            h = g.copy()
            h[idx] += 1e-4
            scene.set_gaze(h)
            jac[:, k] = (scene.head_direction(p) - goal - err) / 1e-4
        step = np.linalg.solve(jac, err)
        g[3] -= step[0]
        g[5] -= step[1]
    scene.set_gaze(g)
    neck = g[3:]
    if np.any(neck < GAZE_LOW[3:] - 1e-9) or np.any(neck > GAZE_HIGH[3:] + 1e-9):
        return None
    if np.max(np.abs(scene.head_direction(p) - goal)) > 1e-4:
        return None
    return np.array(neck)


def random_neck(
    scene: ICubScene, point: Array, rng: np.random.Generator, tries: int = 200
) -> Array | None:
    """A neck that puts ``point`` at a head-centred direction uniform in :data:`HEAD_BOX`
    (head directions no neck in range reaches are drawn again), or None."""
    for _ in range(tries):
        neck = neck_for(scene, point, rng.uniform(HEAD_BOX[:, 0], HEAD_BOX[:, 1]))
        if neck is not None:
            return neck
    return None


@dataclass(frozen=True)
class ViewBatch:
    """Views of ``n`` points: retina ``(n, 2)`` pixels, gaze ``(n, 6)`` radians, head and
    torso directions ``(n, 2)`` radians (analysis only)."""

    retina: Array
    gaze: Array
    head: Array
    torso: Array


def measure(scene: ICubScene, point: ArrayLike) -> tuple[Array, Array, Array, Array]:
    """One view of world ``point`` at the scene's gaze: retina, gaze, head and torso
    directions."""
    return (
        scene.project(point)[0],
        scene.gaze(),
        scene.head_direction(point),
        scene.torso_direction(point),
    )


def _batch(rows: list[tuple[Array, Array, Array, Array]]) -> ViewBatch:
    cols = [np.array(c) for c in zip(*rows, strict=True)]
    return ViewBatch(*cols)


def view_pairs(
    scene: ICubScene,
    n: int,
    rng: np.random.Generator,
    *,
    stage: str = "eyes",
    moved_share: float = 0.0,
) -> tuple[ViewBatch, ViewBatch]:
    """``n`` pairs of views of a ball on the table (see the module's account)."""
    if stage not in ("eyes", "head"):
        raise ConfigError(f"stage must be 'eyes' or 'head', got {stage!r}")
    first: list[tuple[Array, Array, Array, Array]] = []
    second: list[tuple[Array, Array, Array, Array]] = []
    balls = direction_ball(scene, rng, n)
    moved = rng.random(n) < moved_share
    for i in range(n):
        # the eyes' pairs draw the head-centred direction first, then balls until a neck in
        # range puts one there: their head-centred directions are uniform in HEAD_BOX
        head = rng.uniform(HEAD_BOX[:, 0], HEAD_BOX[:, 1]) if stage == "eyes" else None
        for attempt in range(500):  # no gaze sees both views: draw again (a new ball)
            if attempt and (head is not None or attempt % 50 == 0):
                balls[i] = direction_ball(scene, rng, 1)[0]
            scene.set_ball(balls[i])
            ball = scene.ball_position()
            try:
                neck = (
                    random_neck(scene, ball, rng) if head is None else neck_for(scene, ball, head)
                )
                if neck is None:
                    continue
                random_gaze(scene, ball, rng, neck=neck)
                view = measure(scene, ball)
                if moved[i]:
                    scene.set_ball(balls[i] + rng.uniform(-MOVE, MOVE, 2))
                    ball = scene.ball_position()
                if stage == "head":
                    neck = random_neck(scene, ball, rng)
                    if neck is None:
                        continue
                random_gaze(scene, ball, rng, neck=neck)
            except ConfigError:
                continue
            first.append(view)
            second.append(measure(scene, ball))
            break
        else:
            raise ConfigError(f"no pair of views of the ball at {balls[i].tolist()} found")
    return _batch(first), _batch(second)
