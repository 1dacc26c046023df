"""Reaching learned from motor babbling, and the reaches of every method side by side.

**Babbling** (:func:`babble`): the right arm takes random postures (shoulder pitch and roll
and elbow uniform in their ranges, the shoulder's yaw uniform from :data:`BABBLE_YAW` to its
upper limit, the wrist's pitch uniform in the narrow range :data:`BABBLE_WRIST`, which bends the
hand down, the wrist's other joints straight); a posture is kept by what the robot senses: the
hand touches the table lightly (:meth:`~sigmapi.envs.icub.scene.ICubScene.hand_on_table`) and
the eyes find its marker (:func:`~sigmapi.envs.icub.frames.search`, then a random command of
the eyes that keeps it in view, :func:`~sigmapi.envs.icub.frames.look`). Each babble gives a
view of the hand (the detected marker, the gaze) and the posture; the palm's true position is
kept for scoring only.

**The states** (:data:`METHODS`) a posture is associated with, each through an
:class:`~sigmapi.agents.Association` trained on the same babbles:

- ``learned``: a Gaussian bump on map 2 (map 1 -> map 2) centred at the centre of mass of
  its response near the winner (:meth:`~sigmapi.experiments.icub.maps.ChainMaps.place`), or
  at the winner's place (``readout="winner"``);
- ``true_direction``: the same bump, centred at the true torso-centred direction placed on a
  grid of the same size (the association's ceiling with a perfect map);
- ``retina``: the retina's population code alone;
- ``retina_gaze``: the retina's, eye angles' and neck angles' codes side by side, without a map
  (a linear layer cannot form their products).

**The reaches** (:func:`reach_tests`): balls uniform in the table area the scripted inverse
kinematics reaches (:data:`~sigmapi.envs.icub.REACH_REGION`, kept when it reaches them within
1 cm: the experimenter's choice), each found by the eyes (random gazes, then a random command
of the eyes that keeps it in view; a ball they cannot find is replaced); every method's posture
goes to the physics (:func:`~sigmapi.envs.icub.physical_reach`), beside ``scripted_ik`` (damped
least squares on the true ball position: the upper bound) and ``random_posture`` (a babbled
posture drawn at random: the chance rate). Success: the hand touched the ball.

**The learned servo** (:func:`servo`, every associated method alike): before the physical
reach the arm holds the posture its association gave, the eyes and neck look where they see
both the hand and the ball in one glance (:func:`glance`), and the posture moves by
``A(ball) - A(hand)`` (the association's postures for the two views, from the same gaze); a
few such glances. It uses only what was learned (the maps, the association) and the sensed
views, never the true
kinematics: seen in the same glance, the two views share the gaze, so errors the method makes
alike for both (a map's unit off by some degrees, a posture that misses its place) cancel in
the difference. ``success`` holds the reaches to the posture of the first view alone (the
method as such); ``servo`` those after the servo's glances.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import Association
from sigmapi.codes import PopulationCode
from sigmapi.envs import bump_features
from sigmapi.envs.icub import (
    REACH_REGION,
    TORSO_BOX,
    ICubScene,
    ViewBatch,
    arm_ik,
    physical_reach,
    random_ball,
)
from sigmapi.envs.icub.detect import TARGETS, detect
from sigmapi.envs.icub.frames import GOAL_MARGIN, look, saccade, search, sensed_view
from sigmapi.envs.icub.reach import AIM
from sigmapi.envs.icub.views import eye_position, neck_position, retina_position
from sigmapi.errors import ConfigError
from sigmapi.experiments.icub.maps import ChainMaps, unit_rows

Array = NDArray[np.float64]

METHODS = ("learned", "true_direction", "retina", "retina_gaze", "scripted_ik", "random_posture")
"""The reaching methods compared, in the order of the result (``random_posture``: a babbled
posture drawn at random, the chance rate)."""
ASSOCIATED = METHODS[:4]
"""The methods that reach through an association learned from babbling."""
_BABBLED = (0, 1, 2, 3, 5)  # shoulder pitch, roll, yaw, elbow, wrist pitch
_YAW = 2
_WRIST = 5
BABBLE_YAW = 0.8
"""The lowest shoulder yaw babbling draws, radians (the joint's range is -0.65 to 1.40). The
arm reaches most places on the table in postures of several families (four joints for three
coordinates of the palm), and an association averages the postures it saw at a place: two
families average to a posture that reaches neither. Keeping the yaw high keeps one family
(chosen on the tuning seeds: ``docs/guide/icub.md``, where the settings come from)."""
BABBLE_WRIST = (-0.6, -0.3)
"""The range of the wrist's pitch that babbling draws from, radians (the joint's range is -1.396
to 0.436). With the wrist straight, the hand of a posture of the high-yaw family
(:data:`BABBLE_YAW`) meets the table in the nearest, rightmost corner of the table, and the
physics stops it short of where the posture puts it; bent a little, it stays off the table
(chosen on the tuning seeds: ``docs/guide/icub.md``)."""


@dataclass(frozen=True)
class Babbles:
    """``n`` babbles: postures ``(n, 7)``, palm positions ``(n, 3)`` and the views of the palm."""

    posture: Array
    palm: Array
    views: ViewBatch


def babble(
    scene: ICubScene,
    n: int,
    rng: np.random.Generator,
    tolerance: float = 0.01,
    *,
    yaw: float = BABBLE_YAW,
    wrist: tuple[float, float] = BABBLE_WRIST,
) -> Babbles:
    """``n`` babbles (see the module's account), the shoulder's yaw drawn from ``yaw`` (or
    its lower limit, if higher) to its upper limit and the wrist's pitch from ``wrist`` (low,
    high; within the joint's range), the touch no deeper than ``tolerance`` metres; the
    scene's arm goes back to rest."""
    lo, hi = scene.arm_range.T.copy()
    lo[_YAW] = max(lo[_YAW], yaw)
    if lo[_YAW] >= hi[_YAW]:
        raise ConfigError(
            f"yaw must be below the shoulder yaw's upper limit {hi[_YAW]:.2f} rad, got {yaw!r}"
        )
    w_lo, w_hi = (float(w) for w in wrist)
    if not lo[_WRIST] <= w_lo <= w_hi <= hi[_WRIST]:
        raise ConfigError(
            f"wrist must be (low, high) with {lo[_WRIST]:.2f} <= low <= high <= "
            f"{hi[_WRIST]:.2f} rad (the wrist pitch's range), got {wrist!r}"
        )
    lo[_WRIST], hi[_WRIST] = w_lo, w_hi
    postures: list[Array] = []
    palms: list[Array] = []
    rows: list[tuple[Array, Array, Array, Array]] = []
    scene.reset()
    while len(postures) < n:
        q = np.zeros(7)
        q[list(_BABBLED)] = rng.uniform(lo[list(_BABBLED)], hi[list(_BABBLED)])
        scene.set_arm(q)
        if not scene.hand_on_table(tolerance):
            continue
        found = search(scene, rng, ("hand",))
        if found is None:
            continue
        uv = look(scene, rng, "hand", found[0])
        if uv is None:
            continue
        postures.append(q)
        rows.append(sensed_view(scene, uv, scene.palm_position))
        with scene.truth():  # for the babbling curve's score only
            palms.append(scene.palm_position())
    scene.reset()
    cols = [np.array(c) for c in zip(*rows, strict=True)]
    return Babbles(np.array(postures), np.array(palms), ViewBatch(*cols))


def features(
    method: str,
    v: ViewBatch,
    chain: ChainMaps,
    grid: int,
    width: float,
    feature_width: float,
    readout: str = "centroid",
) -> Array:
    """The state ``(B, n_features)`` of views ``v`` for an associated ``method``; ``readout``
    says where the learned chain's bump is centred on map 2 (:attr:`ICubConfig.readout
    <sigmapi.experiments.icub.config.ICubConfig.readout>`)."""
    code = PopulationCode((grid, grid), width)
    if method == "learned":
        if readout == "centroid":
            centres = chain.place(v)
        else:
            centres = chain.map2.map_coords[chain.winner(v, 2)]
        return bump_features(centres, chain.map2.map_coords, feature_width)
    if method == "true_direction":
        shape = np.asarray(chain.map2.map_shape, dtype=np.float64)
        pos = (v.torso - TORSO_BOX[:, 0]) / (TORSO_BOX[:, 1] - TORSO_BOX[:, 0])
        centres = np.clip(pos, 0.0, 1.0) * (shape - 1.0)
        return bump_features(centres, chain.map2.map_coords, feature_width)
    retina = unit_rows(code.encode(retina_position(v, chain.eye_size)))
    if method == "retina":
        return retina
    if method == "retina_gaze":
        parts = [retina, *(unit_rows(code.encode(f(v))) for f in (eye_position, neck_position))]
        return np.hstack(parts) / np.sqrt(3.0)
    raise ValueError(f"no features for method {method!r}")


def learn_reaching(
    scene: ICubScene,
    train: Babbles,
    held_out: Babbles,
    feats: Callable[[str, ViewBatch], Array],
    *,
    epochs: int,
    points: int = 6,
) -> tuple[dict[str, Association], dict[str, list[tuple[int, float]]]]:
    """An association per method on ``train``, and its babbling curve: fitted on the first
    ``n`` babbles for ``points`` values of ``n`` (geometric, up to all), the median distance
    (metres) between the palm at the predicted posture and the palm of ``held_out``'s
    babbles."""
    n = train.posture.shape[0]
    cuts = np.unique(np.geomspace(min(50, n), n, points).astype(int))
    layers, curves = {}, {}
    for method in ASSOCIATED:
        phi = feats(method, train.views)
        test_phi = feats(method, held_out.views)
        curve = []
        for cut in cuts:
            layer = Association(phi.shape[1], 7, epochs=epochs).fit(phi[:cut], train.posture[:cut])
            curve.append((int(cut), _palm_error(scene, layer.predict(test_phi), held_out.palm)))
        layers[method], curves[method] = layer, curve
    scene.reset()
    return layers, curves


def _palm_error(scene: ICubScene, postures: Array, palms: Array) -> float:
    errs = []
    for q, p in zip(postures, palms, strict=True):
        scene.set_arm(q)
        with scene.truth():  # the babbling curve's score
            errs.append(np.linalg.norm(scene.palm_position() - p))
    return float(np.median(errs))


@dataclass
class ReachTests:
    """Every reach of one seed: balls ``(n, 2)``, gazes ``(n, 6)``, success per method."""

    ball: Array
    gaze: Array
    success: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    distance: dict[str, Array] = field(default_factory=dict)
    servo: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    """Per associated method, success after the learned servo (:func:`servo`; empty without)."""


def reachable_balls(scene: ICubScene, n: int, rng: np.random.Generator) -> Array:
    """``n`` balls ``(n, 2)`` uniform in :data:`REACH_REGION` that the scripted inverse
    kinematics reaches within 1 cm (others are drawn again)."""
    out: list[Array] = []
    while len(out) < n:
        b = random_ball(rng, 1, REACH_REGION)[0]
        scene.set_ball(b)
        with scene.truth():  # the experimenter's choice of balls
            if arm_ik(scene, scene.ball_position() + np.array([0.0, 0.0, AIM]))[1] < 0.01:
                out.append(b)
    return np.array(out)


def glance(
    scene: ICubScene, rng: np.random.Generator, tries: int = 10
) -> tuple[Array, Array] | None:
    """Where the right eye sees both the ball and the hand in one glance: the eyes look for the
    ball (:func:`~sigmapi.envs.icub.frames.search`), then move it to random places on the
    retina (:func:`~sigmapi.envs.icub.frames.saccade`) until the hand is seen too, at most
    ``tries`` times; None when they do not (the gaze is then the last one)."""
    found = search(scene, rng)
    if found is None:
        return None
    at = found[0]
    for k in range(tries + 1):
        if k:
            saccade(scene, at, rng.uniform(GOAL_MARGIN, scene.eye_size - GOAL_MARGIN, 2))
        img = scene.render("r_eye")
        ball, hand = detect(img, "ball"), detect(img, "hand")
        if ball is None:
            return None
        if hand is not None:
            return ball, hand
        at = ball
    return None


def servo(
    scene: ICubScene,
    layer: Association,
    feats: Callable[[ViewBatch], Array],
    q: Array,
    rng: np.random.Generator,
    steps: int,
) -> Array:
    """The posture after ``steps`` glances of the learned servo (the module's account), from
    posture ``q``; the scene's arm and gaze are left where the last glance put them."""
    q = np.array(q, dtype=np.float64)
    for _ in range(steps):
        scene.set_arm(q)
        seen = glance(scene, rng)
        if seen is None:
            break
        rows = [
            sensed_view(scene, seen[0], scene.ball_position),
            sensed_view(scene, seen[1], scene.palm_position),
        ]
        a_ball, a_palm = layer.predict(
            feats(ViewBatch(*(np.array(c) for c in zip(*rows, strict=True))))
        )
        q = np.clip(q + a_ball - a_palm, *scene.arm_range.T)
    return q


def reach_tests(
    scene: ICubScene,
    layers: dict[str, Association],
    feats: Callable[[str, ViewBatch], Array],
    n: int,
    rng: np.random.Generator,
    film: Callable[[int, str], int] | None = None,
    *,
    servo_steps: int = 0,
    servo_rng: np.random.Generator | None = None,
    babbled: Array | None = None,
) -> tuple[ReachTests, list[NDArray[np.uint8]]]:
    """``n`` reaches per method (see the module's account), each associated method's also
    after ``servo_steps`` glances of :func:`servo` (gazes from ``servo_rng``) when > 0;
    ``random_posture`` reaches with a posture drawn from ``babbled`` (``(m, 7)``; None: that
    method is left out);
    ``film(i, method)`` > 0 films that many frames per leg of reach ``i`` by ``method``; the
    frames filmed, in order."""
    balls = reachable_balls(scene, n, rng)
    gazes, views = [], []
    for i in range(n):
        while True:  # the eyes look for the ball; one they cannot find is put elsewhere
            scene.reset()
            scene.set_ball(balls[i])
            found = search(scene, rng)
            uv = None if found is None else look(scene, rng, "ball", found[0])
            if uv is not None:
                break
            balls[i] = reachable_balls(scene, 1, rng)[0]
        gazes.append(scene.gaze())
        views.append(sensed_view(scene, uv, scene.ball_position))
    cols = [np.array(c) for c in zip(*views, strict=True)]
    vb = ViewBatch(*cols)
    postures = {m: layers[m].predict(feats(m, vb)) for m in ASSOCIATED}
    res = ReachTests(balls, np.array(gazes))
    frames: list[NDArray[np.uint8]] = []
    s_rng = servo_rng if servo_rng is not None else np.random.default_rng(0)

    def touch(i: int, q: Array, k: int = 0) -> tuple[bool, float]:
        scene.reset()
        scene.set_ball(balls[i])
        scene.set_gaze(gazes[i])
        out = physical_reach(scene, q, film=k)
        frames.extend(out.frames)
        return out.touched, out.distance

    chance = None if babbled is None else babbled[rng.integers(0, len(babbled), n)]
    for method in METHODS:
        if method == "random_posture" and chance is None:
            continue
        ok, dist = np.zeros(n, dtype=bool), np.zeros(n)
        served = np.zeros(n, dtype=bool)
        serve = servo_steps > 0 and method in ASSOCIATED

        def key(v: ViewBatch, m: str = method) -> Array:
            return feats(m, v)

        for i, b in enumerate(balls):
            if method == "scripted_ik":
                scene.reset()
                scene.set_ball(b)
                with scene.truth():  # the reference: scripted inverse kinematics
                    q = arm_ik(scene, scene.ball_position() + np.array([0.0, 0.0, AIM]))[0]
            elif method == "random_posture":
                q = chance[i]  # type: ignore[index]
            else:
                q = postures[method][i]
            ok[i], dist[i] = touch(i, q, film(i, method) if film is not None else 0)
            if serve:
                scene.reset()
                scene.set_ball(b)
                q = servo(scene, layers[method], key, q, s_rng, servo_steps)
                served[i] = touch(i, q)[0]
        res.success[method], res.distance[method] = ok, dist
        if serve:
            res.servo[method] = served
    scene.reset()
    return res, frames


EYES = ("l_eye", "r_eye")
"""The eyes' cameras, left then right."""
FILM = 8
"""Frames filmed per leg of the one reach a run films (:func:`film_first`)."""


def film_first(i: int, method: str) -> int:
    """What a run films (a ``film`` of :func:`reach_tests` and of the 3-D task's reach tests):
    :data:`FILM` frames per leg of the learned method's first reach, none of the others."""
    return FILM if i == 0 and method == "learned" else 0


def eye_frames(scene: ICubScene) -> dict[str, Any]:
    """Both eyes' frames of the scene as it is set (``"l_eye"``, ``"r_eye"``), where the
    detector finds each target in each (``"<eye>_<target>_seen"``, pixels or None) and, as
    the figure's labels (truth), where the ball's centre and the palm project
    (``"<eye>_ball"``, ``"<eye>_palm"``): what
    :func:`~sigmapi.experiments.icub.plots.plot_eyes` draws."""
    out: dict[str, Any] = {}
    for eye in EYES:
        out[eye] = img = scene.render(eye)
        with scene.truth():  # the figure's labels
            out[f"{eye}_ball"] = scene.project(scene.ball_position(), eye)[0]
            out[f"{eye}_palm"] = scene.project(scene.palm_position(), eye)[0]
        for target in TARGETS:
            out[f"{eye}_{target}_seen"] = detect(img, target)
    return out
