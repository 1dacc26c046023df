"""The iCub's 3-D peripersonal space: a ball in the air, seen by both eyes, fixated by its own gaze.

The experimenter puts the ball anywhere in :data:`BOX` (world metres, uniform: 20 cm deep,
24 cm wide, 20 cm high, within the right arm's reach above the table) and turns its gravity
off (:func:`float_ball`: MuJoCo's gravity compensation of the ball's body), so that it hangs
where it was put until the hand pushes it.

What the robot senses of it (only pixels and joint angles, as in
:mod:`~sigmapi.envs.icub.frames`):

- **both eyes' detections** (:func:`see_both`): the ball's ``(u, v)`` in the left and the
  right eye's rendered frames (:func:`~sigmapi.envs.icub.detect.detect`), or None when either
  eye misses it;
- **its own gaze**: random eye commands (:data:`EYE_LOW`.. :data:`EYE_HIGH`, the neck held)
  until both eyes see the ball (:func:`search_both`), and a fixation (:func:`fixate`) that
  servos each eye's pan on its own horizontal retinal error and the common tilt on the mean
  vertical error (version and vergence follow: ``(l + r) / 2`` and ``l - r``), through the
  cameras' focal length (the neck pitches by what the tilt's range leaves over), until each
  eye holds the ball within ``tol`` pixels of its centre horizontally and the eyes' mean row
  is within ``tol`` of the centre's (the shared tilt cannot null the vertical disparity of a
  near ball off to the side).

Depth from the eyes (:func:`triangulate`): each eye's ray through the detected pixel, from the
eye's rotation centre (on the tilt axis, :data:`EYE_HALF` either side of the midline), turned
by the eye's tilt and pan; the point nearest both rays, in the head-centred frame of
:mod:`~sigmapi.envs.icub.scene` (the right eye's centre, x forward, y left, z up with the eyes
at zero). Fixated, it is the vergence's distance; free, the disparity's. It reads the
kinematic constants of the body (the baseline, the focal length) and the joint angles, never
the simulator's state; the maps (:mod:`sigmapi.experiments.icub.space3d`) do without it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.envs.icub.detect import detect
from sigmapi.envs.icub.scene import ICubScene

__all__ = [
    "BOX",
    "EYE_HALF",
    "EYE_HIGH",
    "EYE_LOW",
    "FUSION",
    "NECK_HIGH",
    "NECK_LOW",
    "fixate",
    "float_ball",
    "head_position",
    "place_ball",
    "random_neck3d",
    "random_point",
    "search_both",
    "see_both",
    "torso_position",
    "torso_to_world",
    "triangulate",
]

Array = NDArray[np.float64]

BOX = np.array([[0.16, 0.36], [-0.28, -0.04], [0.61, 0.81]])
"""Where the experimenter puts the ball's centre: world ``x`` (ahead of the root), ``y``
(left) and ``z`` (up; the table's top is at 0.56 m), metres, ``(3, 2)`` low and high."""
EYE_HALF = 0.034
"""Half the distance between the eyes' rotation centres, metres (the model's, after iKin)."""
EYE_LOW = np.radians([-35.0, -30.0, 4.0])
"""Low ends of the eyes' random commands: tilt, version, vergence (radians; the vergence
spans the box's distances, with a margin of the disparities' :data:`FUSION` range: the
vergences of fixations are in docs/guide/icub-3d.md)."""
EYE_HIGH = np.radians([10.0, 30.0, 20.0])
"""High ends of the eyes' random commands."""
NECK_LOW = np.radians([-40.0, -8.0, -40.0])
"""Low ends of the neck's random postures in the 3-D task: pitch, roll, yaw (radians)."""
NECK_HIGH = np.radians([-15.0, 8.0, 0.0])
"""High ends of the neck's random postures (the box lies below and to the right)."""
FIX_LIMIT = np.radians([[-35.0, 15.0], [-50.0, 50.0]])
"""The fixation's clip: tilt and each eye's pan (the joints' ranges, radians)."""
NECK_PITCH = np.radians([-40.0, 22.0])
"""The neck pitch's range (radians): the fixation turns the neck by what the tilt cannot."""
FUSION = 12.0
"""The widest horizontal disparity ``|u_left - u_right|`` (pixels) at which :func:`search_both`
takes the two detections as one ball (about 10 degrees; wider, the eyes look again)."""
SEARCH_TRIES = 300
"""Random eye commands before :func:`search_both` gives up."""


def float_ball(scene: ICubScene) -> None:
    """Turn the ball's gravity off in ``scene``'s model: it stays where it is put (in the
    air) until something pushes it."""
    scene.model.body_gravcomp[scene.model.body("ball").id] = 1.0


def place_ball(scene: ICubScene, p: ArrayLike) -> None:
    """The ball's centre at world point ``p`` ``(3,)``, at rest (the experimenter's hand)."""
    a = scene._ball_q
    scene.data.qpos[a : a + 7] = [*np.asarray(p, dtype=np.float64), 1.0, 0.0, 0.0, 0.0]
    dof = scene.model.jnt_dofadr[scene.model.joint("ball").id]
    scene.data.qvel[dof : dof + 6] = 0.0
    scene._forward()


def random_point(rng: np.random.Generator, n: int, box: ArrayLike = BOX) -> Array:
    """``n`` points ``(n, 3)`` uniform in ``box`` (world metres): the experimenter's
    distribution."""
    b = np.asarray(box, dtype=np.float64)
    return rng.uniform(b[:, 0], b[:, 1], (n, 3))


def random_neck3d(rng: np.random.Generator) -> Array:
    """A random neck posture ``(3,)`` (pitch, roll, yaw) in :data:`NECK_LOW`..:data:`NECK_HIGH`."""
    return rng.uniform(NECK_LOW, NECK_HIGH)


def see_both(scene: ICubScene, target: str = "ball") -> tuple[Array, Array] | None:
    """``target``'s ``(u, v)`` in the left and the right eye's frames, or None when either
    eye misses it (the right eye is looked at first)."""
    r = detect(scene.render("r_eye"), target)
    if r is None:
        return None
    left = detect(scene.render("l_eye"), target)
    return None if left is None else (left, r)


def search_both(
    scene: ICubScene,
    rng: np.random.Generator,
    target: str = "ball",
    tries: int = SEARCH_TRIES,
    fusion: float | None = FUSION,
) -> tuple[Array, Array] | None:
    """Random eye commands (uniform in :data:`EYE_LOW`..:data:`EYE_HIGH`, the neck held) until
    both eyes see ``target`` with a horizontal disparity within ``fusion`` pixels (None: any);
    its detections, or None after ``tries``."""
    neck = scene.gaze()[3:]
    for _ in range(tries):
        scene.set_gaze([*rng.uniform(EYE_LOW, EYE_HIGH), *neck])
        seen = see_both(scene, target)
        if seen is not None and (fusion is None or abs(seen[0][0] - seen[1][0]) <= fusion):
            return seen
    return None


def _pans(gaze: Array) -> tuple[float, float]:
    """The left and right eye's pans from version and vergence."""
    return gaze[1] + 0.5 * gaze[2], gaze[1] - 0.5 * gaze[2]


def fixate(
    scene: ICubScene, target: str = "ball", *, steps: int = 12, tol: float = 0.5
) -> tuple[tuple[Array, Array], int] | None:
    """Fixate ``target`` with both eyes (the module's account): the last detections and the
    number of servo steps made, or None when an eye lost it (or it was not fixated within
    ``steps``)."""
    c, f = 0.5 * scene.eye_size, scene.focal
    seen = see_both(scene, target)
    for k in range(steps + 1):
        if seen is None:
            return None
        (ul, vl), (ur, vr) = seen
        if max(abs(ul - c), abs(ur - c), abs(0.5 * (vl + vr) - c)) <= tol:
            return seen, k
        if k == steps:
            return None
        g = scene.gaze()
        pl, pr = _pans(g)
        pl = np.clip(pl + np.arctan((ul - c) / f), *FIX_LIMIT[1])
        pr = np.clip(pr + np.arctan((ur - c) / f), *FIX_LIMIT[1])
        tilt = g[0] - np.arctan((0.5 * (vl + vr) - c) / f)
        g[0] = np.clip(tilt, *FIX_LIMIT[0])
        g[3] = np.clip(g[3] + tilt - g[0], *NECK_PITCH)  # what the eyes cannot, the neck does
        g[1], g[2] = 0.5 * (pl + pr), pl - pr
        scene.set_gaze(g)
        seen = see_both(scene, target)
    return None


def _ray(tilt: float, pan: float, uv: Array, c: float, f: float) -> Array:
    """Unit ray ``(3,)`` in the head-centred frame through pixel ``uv`` of an eye at
    ``tilt``, ``pan`` (tilt outside, pan inside)."""
    u, v = uv
    d = np.array([1.0, -(u - c) / f, -(v - c) / f])  # the eye's frame: forward, left, up
    cp, sp = np.cos(pan), np.sin(pan)
    d = np.array([cp * d[0] + sp * d[1], -sp * d[0] + cp * d[1], d[2]])  # pan right: -y
    ct, st = np.cos(tilt), np.sin(tilt)
    d = np.array([ct * d[0] - st * d[2], d[1], st * d[0] + ct * d[2]])  # tilt up: +z
    return d / np.linalg.norm(d)


def triangulate(
    gaze: ArrayLike, left: ArrayLike, right: ArrayLike, eye_size: int, focal: float
) -> Array:
    """The head-centred point ``(3,)`` (metres, from the right eye's centre) nearest both eyes'
    rays through pixels ``left`` and ``right`` at ``gaze`` (the module's account)."""
    g = np.asarray(gaze, dtype=np.float64)
    pl, pr = _pans(g)
    c = 0.5 * eye_size
    a = np.array([0.0, 2.0 * EYE_HALF, 0.0])  # the left eye's centre; the right's is 0
    dl = _ray(g[0], pl, np.asarray(left, dtype=np.float64), c, focal)
    dr = _ray(g[0], pr, np.asarray(right, dtype=np.float64), c, focal)
    # nearest points a + s dl and t dr: least squares in (s, t)
    m = np.array([[dl @ dl, -dl @ dr], [dl @ dr, -dr @ dr]])
    s, t = np.linalg.solve(m, [-(a @ dl), -(a @ dr)])
    return 0.5 * (a + s * dl + t * dr)


def head_position(scene: ICubScene, p: ArrayLike) -> Array:
    """The true head-centred position ``(..., 3)`` (metres, from the right eye's centre) of
    world points ``p``: scoring and references only (read within ``scene.truth()``)."""
    with scene.truth():
        c, r = scene.head_frame()
        return (np.asarray(p, dtype=np.float64) - c) @ r


def torso_position(scene: ICubScene, p: ArrayLike) -> Array:
    """The true torso-centred position ``(..., 3)`` (metres, the chest's frame from the point
    between the eyes at neck zero) of world points ``p``: scoring and references only."""
    with scene.truth():
        c, r = scene.torso_frame()
        return (np.asarray(p, dtype=np.float64) - c) @ r - scene._torso_origin


def torso_to_world(scene: ICubScene, z: ArrayLike) -> Array:
    """World points ``(..., 3)`` of torso-centred positions ``z`` (the inverse of
    :func:`torso_position`): references only (read within ``scene.truth()``)."""
    with scene.truth():
        c, r = scene.torso_frame()
        return c + (np.asarray(z, dtype=np.float64) + scene._torso_origin) @ r.T
