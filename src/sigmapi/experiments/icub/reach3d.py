# Over 500 lines: one task read top to bottom (babbling, the states, the reach, its scores and
# one seed's run); the pooled result lives in box.py, the figures in plots3d.py.
"""Reaches in the iCub's 3-D peripersonal space, judged in centimetres.

The world is :mod:`sigmapi.envs.icub.stereo`'s (a ball hanging anywhere in a box within the
right arm's reach, seen by both eyes); the maps are
:mod:`sigmapi.experiments.icub.space3d`'s (map H head-centred, map T torso-centred).

**Babbling** (:func:`babble3d`, learning from touch): the right arm takes random postures (as
on the table: :func:`~sigmapi.experiments.icub.reaching.babble`'s joints and ranges) that
touch nothing; when the palm lies where balls are met (the ball's centre on it in
:data:`~sigmapi.envs.icub.stereo.BOX`), the experimenter presses the ball :data:`TOUCH_DEPTH`
into the palm (truth: where the experimenter puts the ball), and the posture is kept by what
the robot senses: its skin (:meth:`~sigmapi.envs.icub.ICubScene.skin`: the palm feels the
ball, no other part of the arm feels anything) and both eyes find the ball (random head
postures and eye commands, :func:`look`). A babble is the posture and both eyes' view of the
ball on its palm (its pixels and the gaze); the ball's true place is kept as the labels of the
references. That is babbling "offered"; in "swept" (``babbling``,
:data:`~sigmapi.experiments.icub.config.BABBLINGS`) the experimenter only holds a ball at a
random point of the box, the arm sweeps from :data:`START_ARM` toward a random posture until
its first touch (:func:`_sweep`), and the skin keeps the posture when the palm's middle
(:data:`PALM_PATCH`) alone feels the ball.

**The states** (:data:`ASSOCIATED`), each associated with the postures by an
:class:`~sigmapi.agents.Association` trained on the same babbles:

- ``learned``: a Gaussian bump on map T's grid, centred at map T's winner's place (the
  learned chain: both eyes' pixels and the eyes' angles through map H, the neck's through
  map T);
- ``true_position``: the same bump, centred at the true torso-centred position placed on a
  grid of map T's size (a labelled reference: the association's ceiling with a perfect map);
- ``retina``: a 3-D population code of both eyes' pixels alone (mean column, mean row,
  disparity: :func:`~sigmapi.experiments.icub.space3d.retina3`);
- ``retina_gaze``: that code beside codes of the eyes' angles and of the neck's, no map.

Beside them ``scripted_ik`` (damped least squares on the true ball position: the ball resting
on the palm, the upper bound) and ``random_posture`` (a held-out babble's posture drawn
at random: the chance rate).

**The reach** (:func:`reach3d`, palm first): the arm starts at :data:`START_ARM` (the hand
out of the box), moves to the approach posture (the posture plus :data:`BACK_OFF`: the palm
backed off against its facing) in :data:`LEG` seconds, then to the posture in
:data:`APPROACH` seconds and, untouched, on the same way past it (:data:`FOLLOW_THROUGH`);
the joint targets are ramped (each leg reaching its goal at 70 % of its time), and the arm
stops where it is at the first touch of the ball (the arm's touch: any contact of the hand
or forearm with the ball); :data:`SETTLE` seconds later it is scored:

- **end-point error**: the distance from the palm's contact point ``C`` (the palm site: the
  middle of the palm's surface) to the surface of the ball where the experimenter put it:
  ``| |C - b| - R |`` (``b`` its centre, ``R`` its radius), centimetres;
- **strict success**: the palm touched the ball (a contact of the hand whose point lies on
  the palm's side: at least :data:`PALM_SIDE` along the palm's normal from ``C``; the back
  of the hand and of the fingers lie behind it, the marker 3 cm behind) and the ball moved
  less than :data:`MOVED` (its centre at the end against where it was put).

**The reach tests** (:func:`reach_tests3d`): balls uniform in the box that the scripted IK
rests on the palm within 1 cm (the experimenter's choice, as on the table), or every ball
uniform in the box (:data:`TEST_BALLS`); the robot finds
each with both eyes (random head postures and eye commands: **eyes free**, the ball anywhere
in both views), then fixates it (:func:`~sigmapi.envs.icub.stereo.fixate`: **fixated**); each
associated method reaches from each view.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import Association
from sigmapi.codes import PopulationCode
from sigmapi.envs import bump_features
from sigmapi.envs.icub import ICubScene, arm_ik
from sigmapi.envs.icub import stereo as st
from sigmapi.envs.icub.model import BALL_RADIUS
from sigmapi.experiments.icub import space3d as s3
from sigmapi.experiments.icub.config import BABBLING, BABBLINGS, PLAN, TEST_BALL, TEST_BALLS
from sigmapi.experiments.icub.maps import unit_rows
from sigmapi.experiments.icub.reaching import _BABBLED, _WRIST, _YAW, eye_frames, film_first
from sigmapi.metrics import z_decoder

Array = NDArray[np.float64]

METHODS = ("learned", "true_position", "retina", "retina_gaze", "scripted_ik", "random_posture")
"""The reaching methods compared in 3-D, in the order of the result."""
ASSOCIATED = METHODS[:4]
"""The methods that reach through an association learned from babbling."""
CONDITIONS = ("free", "fixated")
"""The eyes when the state is read: free (the ball anywhere in both views) or fixated."""
LEG = 0.6
"""Seconds of the move from the home pose to the approach posture."""
APPROACH = 0.8
"""Seconds of the move from the approach posture to the posture."""
SETTLE = 0.05
"""Seconds the physics runs after the arm stopped, before the reach is scored."""
PALM_SIDE = -0.01
"""A contact of the hand is the palm's when its point lies at least this far along the palm's
normal from the palm's contact point (metres; negative: behind it; how far the hand reaches
either way: docs/guide/icub-3d.md)."""
MOVED = 0.01
"""Strict success: the ball's centre moved less than this, metres."""
START_ARM = (-0.52, 1.3, 0.0, 0.785, 0.0, 0.0, 0.0)
"""Where a reach starts, radians (:data:`~sigmapi.envs.icub.model.ARM`'s order): the home pose
with the shoulder rolled out to 1.3 rad, the hand right of and above the box (the home pose
holds the hand inside the box, where the first leg swept balls away)."""
BACK_OFF = (0.0, 0.0, -0.15, 0.0, 0.0, -0.35, 0.0)
"""The approach posture is the posture plus this (shoulder yaw and wrist pitch, radians): the
palm backed off from the ball, against its facing (how far: docs/guide/icub-3d.md); the last
leg moves it forward onto the ball, palm first."""
FOLLOW_THROUGH = 1.0
"""When the posture is reached untouched, the arm goes on the same way, this many
:data:`BACK_OFF` past it, in :data:`APPROACH` seconds, until the first touch (0: it stops at
the posture)."""
LEARNED_STATES = ("winner", "soft")
"""Where the ``learned`` state's bump sits on map T's grid: at its winner, or at its soft place
(moved between units by the scores,
:meth:`~sigmapi.experiments.icub.space3d.Chain3D.soft_grid_place`), which the linear
association can interpolate."""
LEARNED_STATE = "soft"
"""The ``learned`` state by default (:data:`LEARNED_STATES`)."""
TOUCH_DEPTH = 0.002
"""How far into the palm's skin the experimenter presses the ball while babbling ("offered"),
metres."""
PALM_PATCH = 0.03
"""A swept babble is kept only when the ball touches the palm within this many metres of the
palm's middle (:meth:`~sigmapi.envs.icub.ICubScene.palm_patch`: the palm's taxels, not the
fingers')."""
SWEEP_STEPS = 30
"""Steps of a babbling sweep from :data:`START_ARM` to its random posture ("swept")."""
SWEEP_HALVINGS = 5
"""Halvings of the step in which a sweep first touched, to find the posture of the touch."""
CODE_GRID = 6
"""Units per axis of the 3-D population codes that the ``retina`` and ``retina_gaze`` states
read (both eyes' pixels, the eyes' angles, the neck's) by default."""
_FAR = (1.5, -1.5, 0.7)  # where the ball waits while the robot babbles (out of reach and view)
_SEARCHES = 4  # head postures tried before a ball or a hand is given up
_SEARCH_TRIES = 60  # eye commands per head posture


@dataclass(frozen=True)
class Babbles3D:
    """``n`` babbles: postures ``(n, 7)`` and both eyes' views of the ball the palm touched
    (the labels: the ball's true head- and torso-centred positions); ``tried``: the postures
    drawn for them (the keep rate is ``n / tried``)."""

    posture: Array
    views: s3.Views3D
    tried: int = 0


def look(
    scene: ICubScene, rng: np.random.Generator, target: str = "ball"
) -> tuple[Array, Array] | None:
    """Random head postures (:func:`~sigmapi.envs.icub.stereo.random_neck3d`) and eye
    commands until both eyes see ``target``; its detections, or None."""
    for _ in range(_SEARCHES):
        scene.set_gaze([0.0, 0.0, 0.0, *st.random_neck3d(rng)])
        seen = st.search_both(scene, rng, target, tries=_SEARCH_TRIES)
        if seen is not None:
            return seen
    return None


def _touch_point(scene: ICubScene, inset: float = 0.0) -> Array:
    """Where a ball's centre sits when it rests on the palm (the palm's contact point plus a
    radius less ``inset`` along its normal), world; truth: the experimenter's and the scores'
    reading."""
    r = scene.data.site_xmat[scene._palm].reshape(3, 3)
    return scene.palm_position() + (BALL_RADIUS - inset) * r[:, 2]


def _labels(scene: ICubScene, p: Array) -> tuple[Array, Array]:
    return st.head_position(scene, p), st.torso_position(scene, p)


def babble3d(
    scene: ICubScene,
    n: int,
    rng: np.random.Generator,
    *,
    yaw: float,
    wrist: tuple[float, float],
    how: str = BABBLING,
) -> Babbles3D:
    """``n`` babbles (the module's account), the shoulder's yaw drawn from ``yaw`` to its
    upper limit and the wrist's pitch from ``wrist``, ``how`` as
    :data:`~sigmapi.experiments.icub.config.BABBLINGS` says; the scene's arm goes back to
    rest."""
    s3._check_choice("babbling", how, BABBLINGS)
    lo, hi = scene.arm_range.T.copy()
    lo[_YAW] = max(lo[_YAW], yaw)
    lo[_WRIST], hi[_WRIST] = wrist
    idx = list(_BABBLED)
    scene.reset()
    postures: list[Array] = []
    rows: list[tuple[Array, ...]] = []
    tried = 0
    while len(postures) < n:
        tried += 1
        q = np.zeros(7)
        q[idx] = rng.uniform(lo[idx], hi[idx])
        if how == "offered":
            st.place_ball(scene, _FAR)
            scene.set_arm(q)
            if scene.arm_touches():
                continue
            with scene.truth():  # the experimenter presses the ball against the palm
                p = _touch_point(scene, TOUCH_DEPTH)
            if np.any((p < st.BOX[:, 0]) | (p > st.BOX[:, 1])):  # where balls are met only
                continue
            st.place_ball(scene, p)
        else:  # the experimenter holds a ball anywhere in the box; the arm sweeps into it
            p = st.random_point(rng, 1)[0]
            st.place_ball(scene, p)
            touch = _sweep(scene, np.asarray(START_ARM), q)
            if touch is None:
                continue
            q = touch
        # kept by the skin: the palm alone feels the ball (swept: the palm's middle)
        palm, other = scene.skin(PALM_SIDE, None if how == "offered" else PALM_PATCH)
        if not palm or other:
            continue
        seen = look(scene, rng, "ball")
        if seen is None:
            continue
        postures.append(q)
        rows.append((seen[0], seen[1], scene.gaze(), *_labels(scene, p)))
    scene.reset()
    cols = [np.array(c, dtype=np.float64) for c in zip(*rows, strict=True)]
    return Babbles3D(np.array(postures), s3.Views3D(*cols), tried)


def _sweep(scene: ICubScene, start: Array, goal: Array) -> Array | None:
    """The arm moved from ``start`` toward ``goal`` (joint space, a straight line) until its
    first touch (:meth:`~sigmapi.envs.icub.ICubScene.skin`: anything the arm feels), in
    :data:`SWEEP_STEPS` steps and then halved :data:`SWEEP_HALVINGS` times between the last
    step untouched and the first touched: the posture of the first touch, the arm left there;
    None if nothing was touched or the start already touches."""

    def touches(s: float) -> bool:
        scene.set_arm(start + s * (goal - start))
        return any(scene.skin(PALM_SIDE))

    if touches(0.0):
        return None
    for k in range(1, SWEEP_STEPS + 1):
        if touches(k / SWEEP_STEPS):
            a, b = (k - 1) / SWEEP_STEPS, k / SWEEP_STEPS
            for _ in range(SWEEP_HALVINGS):
                mid = 0.5 * (a + b)
                a, b = (a, mid) if touches(mid) else (mid, b)
            touches(b)  # the arm at the first touch
            return start + b * (goal - start)
    return None


@dataclass
class Features3D:
    """The states of views for each associated method (the module's account)."""

    chain: s3.Chain3D
    grid: int
    width: float
    feature_width: float
    torso_box: Array
    """``(3, 2)`` the torso-centred range the ``true_position`` grid spans (metres)."""
    state: str = LEARNED_STATE
    """Where ``learned``'s bump sits (:data:`LEARNED_STATES`): map T's winner or its soft
    place."""

    def __call__(self, method: str, v: s3.Views3D) -> Array:
        """The state ``(n, n_features)`` of views ``v`` for ``method``."""
        m_t = self.chain.model("torso")  # map T, whatever its design
        if method == "learned":
            if self.state == "soft":
                centres = self.chain.soft_grid_place("torso", v)
            else:
                centres = m_t.map_coords[m_t.winner(*self.chain.inputs("torso", v), hard=True)]
            return bump_features(centres, m_t.map_coords, self.feature_width)
        if method == "true_position":
            lo, hi = self.torso_box.T
            pos = np.clip((v.torso - lo) / (hi - lo), 0.0, 1.0)
            centres = pos * (np.asarray(m_t.map_shape, dtype=np.float64) - 1.0)
            return bump_features(centres, m_t.map_coords, self.feature_width)
        code = PopulationCode((self.grid,) * 3, self.width)
        retina = unit_rows(code.encode(s3.retina3(v, self.chain.eye_size)))
        if method == "retina":
            return retina
        if method == "retina_gaze":
            parts = [retina, *(unit_rows(code.encode(f(v))) for f in (s3.eyes3, s3.neck3))]
            return np.hstack(parts) / np.sqrt(3.0)
        raise ValueError(f"no features for method {method!r}")


def features3d(
    scene: ICubScene,
    chain: s3.Chain3D,
    grid: int,
    width: float,
    feature_width: float,
    state: str = LEARNED_STATE,
) -> Features3D:
    """The states of the associated methods; ``true_position``'s grid spans the box's
    torso-centred range (its corners, read as the reference's labels)."""
    s3._check_choice("learned_state", state, LEARNED_STATES)
    corners = np.array(np.meshgrid(*st.BOX)).reshape(3, -1).T
    t = st.torso_position(scene, corners)
    box = np.column_stack([t.min(axis=0), t.max(axis=0)])
    return Features3D(chain, grid, width, feature_width, box, state)


@dataclass(frozen=True)
class Reach3D:
    """What one physical reach did (the module's account)."""

    touched: bool
    """The arm touched the ball (any contact of the hand or forearm)."""
    palm: bool
    """The palm touched it (a contact on the palm's side, :data:`PALM_SIDE`)."""
    moved: float
    """How far the ball's centre moved, metres."""
    end_point: float
    """The end-point error, metres: the palm's contact point to the ball's surface."""
    aim: float
    """The aim's error, metres: where a ball resting on the palm would be centred at the
    posture (kinematics, before the reach) to the ball's centre."""
    frames: tuple[NDArray[np.uint8], ...] = ()

    @property
    def strict(self) -> bool:
        """Strict success: the palm touched it and it moved less than :data:`MOVED`."""
        return self.palm and self.moved < MOVED


def _contacts(scene: ICubScene) -> tuple[bool, bool]:
    """(the arm touches the ball, a touch is on the palm's side) from the physics' contacts
    now; the palm's side as the skin reads it
    (:meth:`~sigmapi.envs.icub.ICubScene.palm_side`), the score's test."""
    d = scene.data
    n = d.ncon
    if n == 0:
        return False, False
    g1, g2 = d.contact.geom1[:n], d.contact.geom2[:n]
    b = scene._ball_geom
    arm = scene.model.geom_contype == 2
    hit = ((g1 == b) & arm[g2]) | ((g2 == b) & arm[g1])
    if not np.any(hit):
        return False, False
    hand = ((g1 == b) & scene._hand[g2]) | ((g2 == b) & scene._hand[g1])
    return True, bool(np.any(scene.palm_side(d.contact.pos[:n][hand], PALM_SIDE)))


def reach3d(scene: ICubScene, q: Array, *, film: int = 0) -> Reach3D:
    """Reach posture ``q`` from the home pose with the ball where it is (the module's
    account); ``film`` > 0 keeps that many third-person frames per leg."""
    lo, hi = scene.arm_range.T
    goal = np.clip(q, lo, hi)
    scene.set_arm(goal)
    with scene.truth():  # the score's references: where the ball was put, the aim
        b0 = scene.ball_position()
        aim = float(np.linalg.norm(_touch_point(scene) - b0))
    scene.set_arm(START_ARM)
    back = np.asarray(BACK_OFF)
    legs = [(np.clip(goal + back, lo, hi), LEG), (goal, APPROACH)]
    if FOLLOW_THROUGH:
        legs.append((np.clip(goal - FOLLOW_THROUGH * back, lo, hi), APPROACH))
    touched = palm = False
    frames: list[NDArray[np.uint8]] = []
    dt = scene.model.opt.timestep
    for target, seconds in legs:
        steps = max(1, round(seconds / dt))
        start = scene.arm()
        for i in range(steps):
            scene.set_arm_targets(start + (target - start) * min(1.0, (i + 1) / (0.7 * steps)))
            scene._mj.mj_step(scene.model, scene.data)
            t, p = _contacts(scene)
            touched, palm = touched or t, palm or p
            if film and i % max(1, steps // film) == 0:
                frames.append(scene.render("third"))
            if touched:
                scene.set_arm_targets(scene.arm())  # the touch stops the arm
                break
        if touched:
            break
    scene.step(SETTLE)
    with scene.truth():  # the score
        b1, c = scene.ball_position(), scene.palm_position()
    err = abs(float(np.linalg.norm(c - b0)) - BALL_RADIUS)
    return Reach3D(touched, palm, float(np.linalg.norm(b1 - b0)), err, aim, tuple(frames))


def scripted_ik(scene: ICubScene, p: Array, rounds: int = 4) -> tuple[Array, float]:
    """The reference: a posture that rests a ball centred at world point ``p`` on the palm
    (damped least squares on the palm, :func:`~sigmapi.envs.icub.arm_ik`, aimed at ``p``
    less a radius along the palm's normal at the posture so far), and the palm's touch point
    (:func:`_touch_point`) distance left to ``p``."""
    with scene.truth():
        saved = scene.arm()
        q, _ = arm_ik(scene, p)
        for _ in range(rounds):
            scene.set_arm(q)
            off = _touch_point(scene) - scene.palm_position()
            q, _ = arm_ik(scene, p - off, q0=q)
        scene.set_arm(q)
        err = float(np.linalg.norm(_touch_point(scene) - p))
        scene.set_arm(saved)
    return q, err


REACHABLE = 0.01
"""The scripted IK's error (metres) under which a ball counts as reachable."""


def _reachable(scene: ICubScene, rng: np.random.Generator) -> Array:
    """A ball centre uniform in the box that the scripted IK rests on the palm within
    :data:`REACHABLE`."""
    while True:
        p = st.random_point(rng, 1)[0]
        if scripted_ik(scene, p)[1] < REACHABLE:
            return p


def _test_ball(scene: ICubScene, rng: np.random.Generator, balls: str) -> Array:
    """One test ball's centre (world metres) drawn as :data:`TEST_BALLS` ``balls`` says."""
    s3._check_choice("balls", balls, TEST_BALLS)
    return _reachable(scene, rng) if balls == "reachable" else st.random_point(rng, 1)[0]


@dataclass
class ReachTests3D:
    """Every reach of one seed: balls ``(n, 3)`` (world), per condition and method the reaches'
    end-point errors (metres), strict successes, touches and the ball's moves."""

    ball: Array
    fixated: NDArray[np.bool_]
    """Per ball, whether the fixation converged (else the fixated state is the free one)."""
    ik_error: Array = field(default_factory=lambda: np.zeros(0))
    """Per ball, the distance (metres) from its centre to where the scripted IK's posture
    would rest a ball on the palm (the kinematics); under :data:`REACHABLE`: reachable."""
    end_point: dict[str, dict[str, Array]] = field(default_factory=dict)
    strict: dict[str, dict[str, NDArray[np.bool_]]] = field(default_factory=dict)
    touched: dict[str, dict[str, NDArray[np.bool_]]] = field(default_factory=dict)
    moved: dict[str, dict[str, Array]] = field(default_factory=dict)
    aim: dict[str, dict[str, Array]] = field(default_factory=dict)


def _view_row(scene: ICubScene, seen: tuple[Array, Array], p: Array) -> tuple[Array, ...]:
    return (seen[0], seen[1], scene.gaze(), *_labels(scene, p))


def _views(rows: list[tuple[Array, ...]]) -> s3.Views3D:
    return s3.Views3D(*(np.array(c, dtype=np.float64) for c in zip(*rows, strict=True)))


def reach_tests3d(
    scene: ICubScene,
    layers: dict[str, Association],
    feats: Callable[[str, s3.Views3D], Array],
    n: int,
    rng: np.random.Generator,
    babbled: Array,
    film: Callable[[int, str], int] | None = None,
    balls: str = TEST_BALL,
) -> tuple[ReachTests3D, list[NDArray[np.uint8]]]:
    """``n`` reaches per condition and method (the module's account); ``random_posture``
    draws from ``babbled`` ``(m, 7)``; ``film(i, method)`` frames per leg of reach ``i``
    (eyes free); ``balls``: where the experimenter puts them (:data:`TEST_BALLS`); the
    frames filmed, in order."""
    placed: list[Array] = []
    free: list[tuple[Array, ...]] = []
    fixed: list[tuple[Array, ...]] = []
    converged: list[bool] = []
    while len(placed) < n:
        scene.reset()
        p = _test_ball(scene, rng, balls)
        st.place_ball(scene, p)
        seen = look(scene, rng)
        if seen is None:  # the eyes cannot find it: the experimenter puts another
            continue
        placed.append(p)
        free.append(_view_row(scene, seen, p))
        fix = st.fixate(scene)
        converged.append(fix is not None)
        fixed.append(free[-1] if fix is None else _view_row(scene, fix[0], p))
    ball = np.array(placed)
    views = {"free": _views(free), "fixated": _views(fixed)}
    frames: list[NDArray[np.uint8]] = []
    chance = babbled[rng.integers(0, len(babbled), n)]
    solved = [scripted_ik(scene, p) for p in ball]
    ik = np.array([q for q, _ in solved])
    res = ReachTests3D(ball, np.array(converged), np.array([e for _, e in solved]))

    def run(postures: Array, method: str, cond: str) -> None:
        out = []
        for i, q in enumerate(postures):
            scene.reset()
            st.place_ball(scene, ball[i])
            k = film(i, method) if film is not None and cond == "free" else 0
            r = reach3d(scene, q, film=k)
            frames.extend(r.frames)
            out.append(r)
        res.end_point.setdefault(cond, {})[method] = np.array([r.end_point for r in out])
        res.strict.setdefault(cond, {})[method] = np.array([r.strict for r in out])
        res.touched.setdefault(cond, {})[method] = np.array([r.touched for r in out])
        res.moved.setdefault(cond, {})[method] = np.array([r.moved for r in out])
        res.aim.setdefault(cond, {})[method] = np.array([r.aim for r in out])

    for cond in CONDITIONS:
        for method in METHODS:
            if method in ASSOCIATED:
                run(layers[method].predict(feats(method, views[cond])), method, cond)
            elif cond == "free":
                run(ik if method == "scripted_ik" else chance, method, cond)
            else:  # the same postures whatever the eyes did
                for f in (res.end_point, res.moved, res.aim):
                    f[cond][method] = f["free"][method]
                for b in (res.strict, res.touched):
                    b[cond][method] = b["free"][method]
    scene.reset()
    return res, frames


def summarise(tests: ReachTests3D) -> dict[str, dict[str, dict[str, Any]]]:
    """Per condition and method: ``end_point_cm`` (``median``, ``p90``), ``strict_success``,
    ``success`` (touched), the ball's median move and the aim's median error (cm)."""
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for cond, per in tests.end_point.items():
        out[cond] = {}
        for method, e in per.items():
            out[cond][method] = {
                "end_point_cm": {
                    "median": float(np.median(e) * 100.0),
                    "p90": float(np.percentile(e, 90) * 100.0),
                },
                "strict_success": float(np.mean(tests.strict[cond][method])),
                "success": float(np.mean(tests.touched[cond][method])),
                "ball_moved_cm_median": float(np.median(tests.moved[cond][method]) * 100.0),
                "aim_cm_median": float(np.median(tests.aim[cond][method]) * 100.0),
            }
    return out


def run_seed3d(
    seed: int,
    *,
    pairs: int,
    eval_pairs: int,
    iterations: int,
    babbles: int,
    epochs: int,
    reaches: int,
    feature_width: float,
    yaw: float,
    wrist: tuple[float, float],
    grid: int = CODE_GRID,
    width: float = 1.0,
    map_shape: tuple[int, int, int] = s3.TORSO_SHAPE,
    backend: str = "auto",
    keep: bool = False,
    learned_state: str = LEARNED_STATE,
    film: bool = False,
    restarts: int = s3.RESTARTS,
    balls: str = TEST_BALL,
    babbling: str = BABBLING,
) -> dict[str, Any]:
    """One seed of the 3-D task: the maps recorded, learned and scored; babbling; the
    associations; the reaches eyes free and fixated, summarised; ``keep``: also the raw
    reaches (``tests``) for the figures; ``film``: also the frames of the learned chain's
    first reach, eyes free (``"film"``,
    :func:`~sigmapi.experiments.icub.reaching.film_first`), and both eyes' frames of a
    view of its ball with the arm at the posture the chain reads from it (``"eyes"``,
    :func:`shown_eyes`). ``grid``: units per axis of the retina's and the gaze's codes that
    the associated methods read (:data:`CODE_GRID`); ``map_shape``: map T's
    (:data:`~sigmapi.experiments.icub.space3d.TORSO_SHAPE`; the maps' other settings
    :func:`~sigmapi.experiments.icub.space3d.learn_chain3d`'s defaults, the measured
    design); ``learned_state``: where the ``learned`` state's bump sits
    (:data:`LEARNED_STATES`); ``restarts``: fits of each part of map T (its ``restarts``);
    ``balls``: where the reach tests' balls are put (:data:`TEST_BALLS`); ``babbling``: how
    babbles meet their balls (:data:`BABBLINGS`)."""
    t0 = time.perf_counter()
    r_views, r_babble, r_reach = (PLAN.rng(seed, s) for s in ("views", "babbling", "reaches"))
    scene, train, ev = s3.record_box(r_views, pairs, eval_pairs)
    chain = s3.learn_chain3d(
        train["eyes"],
        train["head"],
        width=width,
        map_shape=map_shape,
        iterations=iterations,
        seed=seed,
        eye_size=scene.eye_size,
        backend=backend,
        restarts=restarts,
    )
    maps = s3.score_chain(chain, train, ev, iterations, seed)
    units = unit_positions(chain, ev) if film else None
    t_maps = time.perf_counter() - t0
    bab = babble3d(scene, babbles, r_babble, yaw=yaw, wrist=wrist, how=babbling)
    held = babble3d(scene, max(50, babbles // 10), r_babble, yaw=yaw, wrist=wrist, how=babbling)
    feats = features3d(scene, chain, grid, width, feature_width, learned_state)
    layers = {}
    for method in ASSOCIATED:
        phi = feats(method, bab.views)
        layers[method] = Association(phi.shape[1], 7, epochs=epochs).fit(phi, bab.posture)
    t_babble = time.perf_counter() - t0 - t_maps
    shot = film_first if film else None
    tests, frames = reach_tests3d(
        scene, layers, feats, reaches, r_reach, held.posture, shot, balls=balls
    )
    eyes = shown_eyes(scene, layers["learned"], feats, tests.ball[0], r_reach) if film else None
    scene.close()
    out: dict[str, Any] = {
        "seed": seed,
        "maps": maps,
        "reaches": summarise(tests),
        "fixation_converged": float(np.mean(tests.fixated)),
        "babbles_kept": bab.posture.shape[0] / bab.tried,
        "seconds": {
            "maps": t_maps,
            "babbling": t_babble,
            "total": time.perf_counter() - t0,
        },
    }
    if keep:
        out["tests"] = tests
    if film:
        out["film"], out["units"] = frames, units
        if eyes is not None:
            out["eyes"] = eyes
    return out


def unit_positions(
    chain: s3.Chain3D, ev: dict[str, tuple[tuple[s3.Views3D, s3.Views3D], Any]]
) -> dict[str, tuple[Array, tuple[int, ...]]]:
    """Per map (``"map_head"``, ``"map_torso"``): each unit's mean true position over the
    calibration views it wins (head- or torso-centred metres; a unit that wins none at the
    affine fit's place, :func:`~sigmapi.metrics.z_decoder`) and the map's shape: the figure's
    labelled reference."""
    out = {}
    for name, stage, data in (("map_head", "head", "eyes"), ("map_torso", "torso", "head")):
        c0 = ev[data][0][0]
        model = chain.model(stage)
        z = c0.head if stage == "head" else c0.torso
        table = z_decoder(chain.winners(stage, c0), z, model.map_coords)
        out[name] = (table, tuple(int(n) for n in model.map_shape))
    return out


def shown_eyes(
    scene: ICubScene,
    layer: Association,
    feats: Callable[[str, s3.Views3D], Array],
    ball: Array,
    rng: np.random.Generator,
) -> dict[str, Any] | None:
    """Both eyes' frames (:func:`~sigmapi.experiments.icub.reaching.eye_frames`) of a view of
    ``ball`` (world; the eyes find it, :func:`look`), the arm set at the posture the learned
    ``layer`` reads from that view (kinematics, the ball where it was put); None when the eyes
    cannot find it."""
    scene.reset()
    st.place_ball(scene, ball)
    seen = look(scene, rng)
    if seen is None:
        return None
    with scene.truth():
        row = _view_row(scene, seen, ball)
    scene.set_arm(layer.predict(feats("learned", _views([row])))[0])
    out = eye_frames(scene)
    scene.reset()
    return out
