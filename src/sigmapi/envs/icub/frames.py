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
  still: the pair shares the neck angles and thus the head-centred direction) or ``"head"``
  (the neck turns too: the pair shares the torso-centred direction); a ``moved_share`` of the
  pairs see the ball moved between the views (a nuisance the learner must live with).
- :data:`REGION` is the table area the balls are drawn from (:func:`random_ball`).
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
    "MOVE",
    "REACH_REGION",
    "REGION",
    "ViewBatch",
    "measure",
    "random_ball",
    "random_gaze",
    "view_pairs",
]

Array = NDArray[np.float64]

GAZE_LOW = np.radians([-35.0, -30.0, 0.0, -40.0, 0.0, -40.0])
"""Lower bounds of the random gazes (eye tilt, version, vergence, neck pitch, roll, yaw),
radians: within the joints' ranges; the neck's roll is held at zero."""
GAZE_HIGH = np.radians([10.0, 30.0, 20.0, 0.0, 0.0, 40.0])
"""Upper bounds of the random gazes, radians."""
REGION = ((0.12, 0.36), (-0.44, 0.14))
"""The table area (world x and y, metres) the balls of the maps' views are drawn from: the
arm's reach and a margin around it."""
MOVE = 0.06
"""How far a moved ball moves between two views (uniform in +-MOVE along x and y, metres)."""
REACH_REGION = ((0.14, 0.31), (-0.36, 0.08))
"""The table area (world x and y) the reaching tests draw balls from (the scripted inverse
kinematics' reach, measured on a grid: ``docs/guide/icub.md``)."""


def random_ball(rng: np.random.Generator, n: int, region: tuple = REGION) -> Array:
    """``n`` ball positions ``(n, 2)`` (world x, y), uniform in ``region``."""
    (x0, x1), (y0, y1) = region
    return np.column_stack([rng.uniform(x0, x1, n), rng.uniform(y0, y1, n)])


def random_gaze(
    scene: ICubScene,
    point: ArrayLike,
    rng: np.random.Generator,
    *,
    neck: ArrayLike | None = None,
    margin: float = 4.0,
    tries: int = 2000,
) -> Array:
    """A random gaze (set on ``scene``) that keeps world ``point`` in the right eye's image,
    at least ``margin`` pixels inside; ``neck`` (3 angles) holds the neck there."""
    lo, hi = GAZE_LOW.copy(), GAZE_HIGH.copy()
    if neck is not None:
        lo[3:] = hi[3:] = np.asarray(neck, dtype=np.float64)
    p = np.asarray(point, dtype=np.float64)
    size = scene.eye_size
    for _ in range(tries):
        g = rng.uniform(lo, hi)
        scene.set_gaze(g)
        u, v = scene.project(p)[0]
        if margin <= u <= size - margin and margin <= v <= size - margin:
            return g
    raise ConfigError(
        f"no gaze within {tries} tries keeps the point {np.round(p, 3).tolist()} in view; "
        "draw points from the table region (sigmapi.envs.icub.frames.REGION)"
    )


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
    return (scene.project(point)[0], scene.gaze(), scene.head_direction(point),
            scene.torso_direction(point))  # fmt: skip


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
    region: tuple = REGION,
) -> tuple[ViewBatch, ViewBatch]:
    """``n`` pairs of views of a ball on the table (see the module's account)."""
    if stage not in ("eyes", "head"):
        raise ConfigError(f"stage must be 'eyes' or 'head', got {stage!r}")
    first: list[tuple[Array, Array, Array, Array]] = []
    second: list[tuple[Array, Array, Array, Array]] = []
    balls = random_ball(rng, n, region)
    moved = rng.random(n) < moved_share
    (x0, x1), (y0, y1) = region
    others = np.clip(balls + rng.uniform(-MOVE, MOVE, (n, 2)), [x0, y0], [x1, y1])
    for i in range(n):
        for _ in range(50):  # a neck from which the eyes alone cannot see both: draw again
            scene.set_ball(balls[i])
            ball = scene.ball_position()
            g = random_gaze(scene, ball, rng)
            view = measure(scene, ball)
            if moved[i]:
                scene.set_ball(others[i])
                ball = scene.ball_position()
            try:
                random_gaze(scene, ball, rng, neck=g[3:] if stage == "eyes" else None,
                            tries=200)  # fmt: skip
            except ConfigError:
                continue
            first.append(view)
            second.append(measure(scene, ball))
            break
        else:
            raise ConfigError(f"no pair of views of the ball at {balls[i].tolist()} found")
    return _batch(first), _batch(second)
