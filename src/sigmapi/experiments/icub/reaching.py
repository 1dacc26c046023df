"""Reaching learned from motor babbling, and the reaches of every method side by side.

**Babbling** (:func:`babble`): the right arm takes random postures (shoulder pitch, roll and
yaw and elbow uniform in their ranges, the wrist straight); a posture is kept when it puts the
palm at the height a reach aims at (:data:`~sigmapi.envs.icub.reach.AIM` above a ball's
centre, within 1 cm) above the table, and the eyes and neck then look at the hand (a gaze as
in the maps' views, the palm in view). Each babble gives a view of the palm (retina from the
projection, gaze) and the posture.

**The states** (:data:`METHODS`) a posture is associated with, each through an
:class:`~sigmapi.agents.Association` trained on the same babbles:

- ``learned``: a Gaussian bump on map 2 around the chain's winner (map 1 -> map 2);
- ``true_direction``: the same bump, centred at the true torso-centred direction placed on a
  grid of the same size (the association's ceiling with a perfect map);
- ``retina``: the retina's population code alone;
- ``retina_gaze``: the retina's, eye angles' and neck angles' codes side by side, without a map
  (a linear layer cannot form their products).

**The reaches** (:func:`reach_tests`): balls uniform in the table area the scripted inverse
kinematics reaches (:data:`~sigmapi.envs.icub.REACH_REGION`, kept when it reaches them within
1 cm), each seen from a random gaze; every method's posture goes to the physics
(:func:`~sigmapi.envs.icub.physical_reach`), beside ``scripted_ik`` (damped least squares on
the true ball position: the upper bound). Success: the hand touched the ball.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sigmapi.agents import Association
from sigmapi.codes import PopulationCode
from sigmapi.envs import bump_features
from sigmapi.envs.icub import (
    BALL_RADIUS,
    REACH_REGION,
    TABLE_HEIGHT,
    TORSO_BOX,
    ICubScene,
    ViewBatch,
    arm_ik,
    measure,
    physical_reach,
    random_ball,
    random_gaze,
    random_neck,
)
from sigmapi.envs.icub.reach import AIM
from sigmapi.experiments.icub.maps import ChainMaps, eye_position, neck_position, retina_position

__all__ = [
    "ASSOCIATED",
    "METHODS",
    "Babbles",
    "ReachTests",
    "babble",
    "features",
    "learn_reaching",
    "reach_tests",
    "reachable_balls",
]

Array = NDArray[np.float64]

METHODS = ("learned", "true_direction", "retina", "retina_gaze", "scripted_ik")
"""The reaching methods compared, in the order of the result."""
ASSOCIATED = METHODS[:4]
"""The methods that reach through an association learned from babbling."""
_BABBLED = (0, 1, 2, 3)  # shoulder pitch, roll, yaw, elbow; the wrist stays straight


@dataclass(frozen=True)
class Babbles:
    """``n`` babbles: postures ``(n, 7)``, palm positions ``(n, 3)`` and the views of the palm."""

    posture: Array
    palm: Array
    views: ViewBatch


def babble(scene: ICubScene, n: int, rng: np.random.Generator, tolerance: float = 0.01) -> Babbles:
    """``n`` babbles (see the module's account); the scene's arm goes back to rest."""
    aim = TABLE_HEIGHT + BALL_RADIUS + AIM
    lo, hi = scene.arm_range.T
    postures: list[Array] = []
    palms: list[Array] = []
    rows: list[tuple[Array, Array, Array, Array]] = []
    scene.reset()
    while len(postures) < n:
        q = np.zeros(7)
        q[list(_BABBLED)] = rng.uniform(lo[list(_BABBLED)], hi[list(_BABBLED)])
        scene.set_arm(q)
        p = scene.palm_position()
        if abs(p[2] - aim) > tolerance or not 0.09 < p[0] < 0.45 or not -0.48 < p[1] < 0.2:
            continue
        neck = random_neck(scene, p, rng)
        if neck is None:
            continue
        random_gaze(scene, p, rng, neck=neck)
        postures.append(q)
        palms.append(p)
        rows.append(measure(scene, p))
    scene.reset()
    cols = [np.array(c) for c in zip(*rows, strict=True)]
    return Babbles(np.array(postures), np.array(palms), ViewBatch(*cols))


def _neck(scene: ICubScene, p: Array, rng: np.random.Generator) -> Array | None:

    return random_neck(scene, p, rng)


def features(
    method: str, v: ViewBatch, chain: ChainMaps, grid: int, width: float, feature_width: float
) -> Array:
    """The state ``(B, n_features)`` of views ``v`` for an associated ``method``."""
    code = PopulationCode((grid, grid), width)
    if method == "learned":
        k = chain.winner(v, 2)
        return bump_features(chain.map2.map_coords[k], chain.map2.map_coords, feature_width)
    if method == "true_direction":
        shape = np.asarray(chain.map2.map_shape, dtype=np.float64)
        pos = (v.torso - TORSO_BOX[:, 0]) / (TORSO_BOX[:, 1] - TORSO_BOX[:, 0])
        centres = np.clip(pos, 0.0, 1.0) * (shape - 1.0)
        return bump_features(centres, chain.map2.map_coords, feature_width)
    retina = _unit(code.encode(retina_position(v, chain.eye_size)))
    if method == "retina":
        return retina
    if method == "retina_gaze":
        parts = [retina, _unit(code.encode(eye_position(v))), _unit(code.encode(neck_position(v)))]
        return np.hstack(parts) / np.sqrt(3.0)
    raise ValueError(f"no features for method {method!r}")


def _unit(a: Array) -> Array:
    n = np.linalg.norm(a, axis=1, keepdims=True)
    return a / np.where(n > 0, n, 1.0)


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
        errs.append(np.linalg.norm(scene.palm_position() - p))
    return float(np.median(errs))


@dataclass
class ReachTests:
    """Every reach of one seed: balls ``(n, 2)``, gazes ``(n, 6)``, success per method."""

    ball: Array
    gaze: Array
    success: dict[str, NDArray[np.bool_]] = field(default_factory=dict)
    distance: dict[str, Array] = field(default_factory=dict)


def reachable_balls(scene: ICubScene, n: int, rng: np.random.Generator) -> Array:
    """``n`` balls ``(n, 2)`` uniform in :data:`REACH_REGION` that the scripted inverse
    kinematics reaches within 1 cm (others are drawn again)."""
    out: list[Array] = []
    while len(out) < n:
        b = random_ball(rng, 1, REACH_REGION)[0]
        scene.set_ball(b)
        if arm_ik(scene, scene.ball_position() + np.array([0.0, 0.0, AIM]))[1] < 0.01:
            out.append(b)
    return np.array(out)


def reach_tests(
    scene: ICubScene,
    layers: dict[str, Association],
    feats: Callable[[str, ViewBatch], Array],
    n: int,
    rng: np.random.Generator,
    film: Callable[[int, str], int] | None = None,
) -> tuple[ReachTests, list[NDArray[np.uint8]]]:
    """``n`` reaches per method (see the module's account); ``film(i, method)`` > 0 films that
    many frames per leg of reach ``i`` by ``method``; the frames filmed, in order."""
    balls = reachable_balls(scene, n, rng)
    gazes, views = [], []
    for b in balls:
        scene.reset()
        scene.set_ball(b)
        p = scene.ball_position()
        random_gaze(scene, p, rng, neck=random_neck(scene, p, rng))
        gazes.append(scene.gaze())
        views.append(measure(scene, p))
    cols = [np.array(c) for c in zip(*views, strict=True)]
    vb = ViewBatch(*cols)
    postures = {m: layers[m].predict(feats(m, vb)) for m in ASSOCIATED}
    res = ReachTests(balls, np.array(gazes))
    frames: list[NDArray[np.uint8]] = []
    for method in METHODS:
        ok, dist = np.zeros(n, dtype=bool), np.zeros(n)
        for i, b in enumerate(balls):
            scene.reset()
            scene.set_ball(b)
            scene.set_gaze(gazes[i])
            if method == "scripted_ik":
                q = arm_ik(scene, scene.ball_position() + np.array([0.0, 0.0, AIM]))[0]
            else:
                q = postures[method][i]
            k = film(i, method) if film is not None else 0
            out = physical_reach(scene, q, film=k)
            ok[i], dist[i] = out.touched, out.distance
            frames.extend(out.frames)
        res.success[method], res.distance[method] = ok, dist
    scene.reset()
    return res, frames
