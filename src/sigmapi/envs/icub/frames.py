"""The iCub's frames, measured: views of a point from random gazes, and their true directions.

A *view* of a point (the ball, or the palm) is what the robot measures of it at one gaze: the
right eye's retinal position ``(u, v)`` (pixels), the six gaze angles
(:data:`~sigmapi.envs.icub.scene.GAZE`) and, for analysis only, the point's head-centred and
torso-centred directions ``(azimuth, elevation)`` (radians;
:meth:`~sigmapi.envs.icub.scene.ICubScene.head_direction`,
:meth:`~sigmapi.envs.icub.scene.ICubScene.torso_direction`).

The robot's own looking (the image and the joint angles only; :func:`sensed_view` reads
the truth only for a view's labels, within ``scene.truth()``):

- :func:`search`: random gaze commands until the right eye detects the target(s);
- :func:`saccade`: the eyes move by the angles of the retinal error, to put a seen target at
  a given place on the retina; :func:`look`: a random command of the eyes, accepted when the
  target would stay in view (predicted from the retinal position and the angles' change);
- :func:`orient`: the head turns so that a seen target lies at a chosen head-centred
  direction, estimated from the eye angles and the retinal offset; :func:`head_goal` draws
  that direction uniformly in :data:`HEAD_BOX` among those the neck reaches (by the same
  estimate);
- :func:`view_pairs` records pairs of views of one ball: ``stage="eyes"`` (the head still:
  the pair shares the head-centred direction; the head turns before each pair, then the eyes
  look twice) or ``"head"`` (the head turns between the views: the pair shares the
  torso-centred direction); a ``moved_share`` of the pairs see the ball moved between the
  views (a nuisance the learner must live with). :data:`PAIRS_PER_BALL` pairs per ball, the
  balls put by the experimenter (:func:`place_ball`).

The experimenter's and the references' tools (they read the truth):
:func:`place_ball` puts the maps' balls uniformly on the table (:data:`MAP_REGION`) or, by
:func:`direction_ball`, with their torso-centred directions uniform in :data:`TORSO_BOX`;
:func:`random_ball` uniform in a table area (the reaches, in :data:`REACH_REGION`);
:func:`random_gaze` draws a gaze that keeps a point in view (from its projection),
:func:`neck_for` / :func:`random_neck` a neck that puts it at a head-centred direction;
:func:`measure` one view from the projection.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.envs.icub.detect import detect
from sigmapi.envs.icub.scene import ICubScene
from sigmapi.errors import ConfigError

__all__ = [
    "BALLS",
    "GAZE_HIGH",
    "GAZE_LOW",
    "HEAD_BOX",
    "MAP_REGION",
    "MOVE",
    "REACH_REGION",
    "TORSO_BOX",
    "ViewBatch",
    "direction_ball",
    "look",
    "measure",
    "neck_for",
    "orient",
    "place_ball",
    "random_ball",
    "random_gaze",
    "random_neck",
    "reaches",
    "saccade",
    "search",
    "sensed_view",
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
"""The head-centred directions (azimuth, elevation rows) the head turns the ball to, uniformly,
in the views of :func:`view_pairs` (:func:`orient`, from the robot's own estimate: the true
directions spill a few degrees over the edges, and a neck at its limit stops short); for
:func:`random_neck` and :func:`random_gaze` (``head_box``) the box the true direction is
drawn in."""
MOVE = 0.06
"""How far a moved ball moves between two views (uniform in +-MOVE along x and y, metres)."""
SEARCH_TRIES = 200
"""Random gazes :func:`search` tries before it gives up."""
GOAL_MARGIN = 8.0
"""How far inside the image a saccade's goal lies (:func:`look`), pixels."""
GOAL_BALLS = 50
"""Balls :func:`view_pairs` waits for one that its neck can turn to map 1's next head-centred
direction before it draws another direction."""
LOOK_TRIES = 200
"""Random eye commands :func:`look` tries before it gives up."""
PAIRS_PER_BALL = 2
"""Pairs of views :func:`view_pairs` records of one ball before the experimenter puts down
the next (each ball costs a search by random gazes; chosen on the tuning seeds:
``docs/guide/icub.md``)."""
MAP_REGION = ((0.12, 0.40), (-0.45, 0.15))
"""The table area (world x and y, metres) the experimenter puts the maps' balls on, uniformly
(:data:`BALLS` ``"table"``): the part of the table around the arm's reach that
:data:`TORSO_BOX` covers (0.12-0.41 m ahead, 0.47 m right to 0.15 m left), as a rectangle."""
BALLS = ("table", "directions")
"""Where the experimenter puts the maps' balls (:func:`place_ball`): uniform on the table in
:data:`MAP_REGION` ("table"), or uniform in the torso-centred directions of :data:`TORSO_BOX`,
the coordinates map 2 is scored in ("directions")."""
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
    with scene.truth():  # the experimenter puts the ball
        return scene.table_point(d)[:, :2]


def place_ball(scene: ICubScene, rng: np.random.Generator, balls: str = "table") -> Array:
    """Where the experimenter puts the next ball of the maps' views (world x, y;
    :data:`BALLS`)."""
    if balls not in BALLS:
        raise ConfigError(f"balls must be one of {BALLS}, got {balls!r}")
    if balls == "table":
        return random_ball(rng, 1, MAP_REGION)[0]
    return direction_ball(scene, rng, 1)[0]


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


def sensed_view(
    scene: ICubScene, uv: ArrayLike, point: Callable[[], Array]
) -> tuple[Array, Array, Array, Array]:
    """One view as the robot senses it: the detected retinal position ``uv`` and the gaze
    joints now; beside them the labels (head- and torso-centred directions of the true point
    ``point()``, read within :meth:`~sigmapi.envs.icub.scene.ICubScene.truth`: analysis and
    references only)."""
    with scene.truth():
        p = point()
        labels = scene.head_direction(p), scene.torso_direction(p)
    return np.array(uv, dtype=np.float64), scene.gaze(), *labels


def saccade(scene: ICubScene, uv: ArrayLike, goal: ArrayLike) -> None:
    """Move the eyes (the neck still) so that what the right eye sees at ``uv`` lands near
    pixel ``goal``: one proportional step on the retinal error, each axis's angle from the
    camera's focal length (a pan for ``u``, a tilt for ``v``), clipped to the random gazes'
    range; the image and the joint angles only."""
    c, f = 0.5 * scene.eye_size, scene.focal
    (u, v), (gu, gv) = np.asarray(uv, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    g = scene.gaze()
    g[0] -= np.arctan((v - c) / f) - np.arctan((gv - c) / f)
    g[1] += np.arctan((u - c) / f) - np.arctan((gu - c) / f)
    g[:3] = np.clip(g[:3], GAZE_LOW[:3], GAZE_HIGH[:3])
    scene.set_gaze(g)


def _turned(scene: ICubScene, uv: ArrayLike, goal: ArrayLike) -> Array:
    """The gaze (not clipped) of :func:`orient`."""
    c, f = 0.5 * scene.eye_size, scene.focal
    u, v = np.asarray(uv, dtype=np.float64)
    g = scene.gaze()
    pan = g[1] - 0.5 * g[2]
    now = np.array([-(pan + np.arctan((u - c) / f)), g[0] - np.arctan((v - c) / f)])
    az, el = np.asarray(goal, dtype=np.float64)
    g[3] += now[1] - el
    g[5] += now[0] - az
    g[0], g[1] = el, -az + 0.5 * g[2]
    return g


def orient(scene: ICubScene, uv: ArrayLike, goal: ArrayLike) -> None:
    """Turn the head so that what the right eye sees at ``uv`` lies at head-centred direction
    ``goal`` (azimuth, elevation), and the eyes to it: the direction now is estimated from
    the image and the joints alone (the eye's tilt and pan plus the retinal offset's angles;
    the eyes' offset from the neck's axes is ignored), the neck turns by the difference and
    the eyes point at ``goal`` (each clipped to the random gazes' range)."""
    scene.set_gaze(np.clip(_turned(scene, uv, goal), GAZE_LOW, GAZE_HIGH))


def reaches(scene: ICubScene, uv: ArrayLike, goal: ArrayLike) -> bool:
    """Whether the neck can turn what the right eye sees at ``uv`` to head-centred direction
    ``goal`` (:func:`orient`'s estimate; the neck within the random gazes' range)."""
    neck = _turned(scene, uv, goal)[3:]
    return bool(np.all(neck >= GAZE_LOW[3:]) and np.all(neck <= GAZE_HIGH[3:]))


def head_goal(
    scene: ICubScene, rng: np.random.Generator, uv: ArrayLike, tries: int = SEARCH_TRIES
) -> Array:
    """A head-centred direction uniform in :data:`HEAD_BOX` that the neck can turn what the
    right eye sees at ``uv`` to (:func:`reaches`): directions it cannot reach are drawn again
    (after ``tries``, the last one)."""
    goal = rng.uniform(HEAD_BOX[:, 0], HEAD_BOX[:, 1])
    for _ in range(tries):
        if reaches(scene, uv, goal):
            break
        goal = rng.uniform(HEAD_BOX[:, 0], HEAD_BOX[:, 1])
    return goal


def search(
    scene: ICubScene,
    rng: np.random.Generator,
    targets: tuple[str, ...] = ("ball",),
    *,
    neck: ArrayLike | None = None,
    tries: int = SEARCH_TRIES,
) -> list[Array] | None:
    """Random gaze commands (uniform in :data:`GAZE_LOW`..:data:`GAZE_HIGH`; ``neck`` holds the
    neck) until the right eye detects every one of ``targets``; their retinal positions, or
    None after ``tries`` (the gaze is then the last one tried)."""
    for _ in range(tries):
        g = rng.uniform(GAZE_LOW, GAZE_HIGH)
        if neck is not None:
            g[3:] = neck
        scene.set_gaze(g)
        img = scene.render("r_eye")
        seen = [detect(img, t) for t in targets]
        if all(x is not None for x in seen):
            return seen  # type: ignore[return-value]
    return None


def look(scene: ICubScene, rng: np.random.Generator, target: str, uv: ArrayLike) -> Array | None:
    """A random command of the eyes (tilt, version and vergence uniform in the random gazes'
    range, the neck held), accepted when ``target``, seen at ``uv``, would land at least
    :data:`GOAL_MARGIN` pixels inside the image (predicted from the retinal position and the
    commanded change of the angles, through the camera's focal length: the image and the
    joint angles only); where it is seen after, or None when no command of :data:`LOOK_TRIES`
    is accepted or the eyes lost it."""
    c, f, m, size = 0.5 * scene.eye_size, scene.focal, GOAL_MARGIN, scene.eye_size
    u, v = np.asarray(uv, dtype=np.float64)
    now = scene.gaze()
    at_u, at_v = np.arctan((u - c) / f), np.arctan((v - c) / f)
    for _ in range(LOOK_TRIES):
        g = now.copy()
        g[:3] = rng.uniform(GAZE_LOW[:3], GAZE_HIGH[:3])
        to_u = at_u - ((g[1] - 0.5 * g[2]) - (now[1] - 0.5 * now[2]))  # the right eye's pan
        to_v = at_v + (g[0] - now[0])
        if max(abs(to_u), abs(to_v)) >= 0.5 * np.pi - 0.1:
            continue
        pu, pv = c + f * np.tan(to_u), c + f * np.tan(to_v)
        if m <= pu <= size - m and m <= pv <= size - m:
            scene.set_gaze(g)
            return scene.see(target)
    return None


def _find(
    scene: ICubScene, rng: np.random.Generator, uv: Array | None, goal: Array | None
) -> Array | None:
    """After the head turned to head-centred direction ``goal`` (:func:`orient`, from where
    the ball was seen, ``uv``; None: the head still) or the ball moved: where the right eye
    sees the ball after the eyes :func:`look`; the eyes look for it (the neck held) when it
    is out of view."""
    if goal is not None and uv is not None:
        orient(scene, uv, goal)
    seen = scene.see("ball")
    if seen is None:
        found = search(scene, rng, neck=scene.gaze()[3:])
        if found is None:
            return None
        seen = found[0]
    return look(scene, rng, "ball", seen)


def view_pairs(
    scene: ICubScene,
    n: int,
    rng: np.random.Generator,
    *,
    stage: str = "eyes",
    moved_share: float = 0.0,
    balls: str = "table",
    per_ball: int = PAIRS_PER_BALL,
) -> tuple[ViewBatch, ViewBatch]:
    """``n`` pairs of views of a ball on the table, as the robot senses them (see the
    module's account); the experimenter puts the balls as ``balls`` says
    (:func:`place_ball`), at most ``per_ball`` pairs each. For map 1's pairs the robot draws
    the head-centred direction first, uniformly in :data:`HEAD_BOX`, and keeps it until a
    ball comes that its neck can turn there (:func:`reaches`; after :data:`GOAL_BALLS` balls
    it draws another): their directions are uniform in the box, not skewed to those most
    balls reach."""
    if stage not in ("eyes", "head"):
        raise ConfigError(f"stage must be 'eyes' or 'head', got {stage!r}")
    first: list[tuple[Array, Array, Array, Array]] = []
    second: list[tuple[Array, Array, Array, Array]] = []
    goal, waited = None, 0
    while len(first) < n:
        xy = place_ball(scene, rng, balls)
        scene.set_ball(xy)
        found = search(scene, rng)
        uv = None if found is None else found[0]
        waited += 1
        for k in range(per_ball):
            if stage == "eyes":  # the head turns before each of the eyes' pairs
                if goal is None or waited > GOAL_BALLS:
                    goal, waited = rng.uniform(HEAD_BOX[:, 0], HEAD_BOX[:, 1]), 0
                if uv is None or not reaches(scene, uv, goal):
                    break  # the next ball
                uv, goal = _find(scene, rng, uv, goal), None
            elif k == 0:
                uv = _find(scene, rng, uv, None if uv is None else head_goal(scene, rng, uv))
            if uv is None or len(first) >= n:
                break
            view = sensed_view(scene, uv, scene.ball_position)
            moved = rng.random() < moved_share
            if moved:
                xy = xy + rng.uniform(-MOVE, MOVE, 2)
                scene.set_ball(xy)
            if stage == "head":
                uv = _find(scene, rng, uv, head_goal(scene, rng, uv))
            elif moved:
                uv = _find(scene, rng, uv, None)
            else:  # the ball still, the eyes still: where it was seen, moved to a new place
                uv = look(scene, rng, "ball", uv)
            if uv is not None:
                first.append(view)
                second.append(sensed_view(scene, uv, scene.ball_position))
    return _batch(first), _batch(second)
