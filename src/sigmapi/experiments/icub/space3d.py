"""The iCub's 3-D peripersonal space seen by both eyes: a chain of two 3-D Sigma-Pi maps, scored.

The world is :mod:`sigmapi.envs.icub.stereo`'s: a ball anywhere in a box 20 cm deep and 20 cm
high within the right arm's reach, in the air, seen by both eyes.

- **Map H** (head-centred, eyes first): a 3-D Sigma-Pi map (``map_shape``, e.g. 6x6x6) on a
  3-D population code of what both eyes see (:func:`retina3`: the eyes' mean column and row
  and the horizontal disparity ``u_left - u_right``) and a 3-D code of the eyes' angles
  (:func:`eyes3`: version, tilt, vergence). Its view pairs come from two random eye commands
  (the neck still) that both see the ball: the pair shares the ball's head-centred position.
  Per axis the relation is close to the paper's sum: the head-centred azimuth is the version
  plus the column's angle, the elevation the tilt plus the row's, and the distance a
  function of the vergence plus the disparity's angle.
- **Map T** (torso-centred, then the head): a 3-D Sigma-Pi map on a code of map H's winner's
  place on its grid (hills :data:`HEAD_WIDTH` wide) and a 3-D code of the neck's pitch, roll
  and yaw (:func:`neck3`). Its pairs: the head turns to a new random posture between the
  two views, and the eyes find the ball again: the pair shares the torso-centred position.

Every learning input is read from the pixels (:func:`~sigmapi.envs.icub.stereo.see_both`)
and the joint angles, on a sealed scene; the simulator's truth gives only the labels
(:class:`Views3D`'s ``head`` and ``torso``, analysis and references).

Each map is scored on unmoved pairs from the fixed evaluation seed against the true 3-D
position it should code (head-centred for map H, torso-centred for map T, metres): the
winner metrics of :func:`sigmapi.metrics.winner_metrics` (``order_r2``, the affine fit from
the map's grid to the three coordinates), ``order_r2_per_axis`` (the same fit scored per
coordinate), the fold detector (:func:`sigmapi.metrics.fold_indicators`) and ``error_cm``
(RMS distance between a test view's true position and the mean true position of the
calibration views its winner won; ``error_cm_median`` the median). Beside each: a same-size
Kohonen map trained on the true positions (``true_position``) and k-means with as many
centres on the true positions (``kmeans``), each scored the same way.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.baselines import KohonenSOM
from sigmapi.codes import PopulationCode
from sigmapi.envs.icub import ICubScene
from sigmapi.envs.icub import stereo as st
from sigmapi.experiments.icub.maps import som_config
from sigmapi.metrics import (
    EVAL_SEED,
    FOLD_THRESHOLD,
    ORDERED_R2,
    affine_fit,
    fold_indicators,
    hard_scores,
    winner_metrics,
    z_decoder,
)
from sigmapi.model.som import SigmaPiSOM
from sigmapi.tasks import Batch

__all__ = [
    "DISPARITY",
    "HEAD_WIDTH",
    "PAIRS_PER_BALL",
    "Chain3D",
    "Views3D",
    "eyes3",
    "kmeans_reference",
    "learn_chain3d",
    "neck3",
    "record_pairs",
    "retina3",
    "score_map",
    "true_position_map",
]

Array = NDArray[np.float64]

DISPARITY = st.FUSION
"""Half the range of horizontal disparities the retina's code spans, pixels (``u_left -
u_right`` within the fusion range, :data:`~sigmapi.envs.icub.stereo.FUSION`)."""
HEAD_WIDTH = 0.85
"""Width (map-H units) of the hill of map H's place code that map T reads."""
PAIRS_PER_BALL = 2
"""View pairs recorded per placed ball (each from a new head posture)."""
_SEARCHES = 4  # head postures tried before a ball is given up
_SEARCH_TRIES = 100  # eye commands per head posture


@dataclass(frozen=True)
class Views3D:
    """Views of balls by both eyes: detections (pixels), gaze (radians) and, for analysis
    only, the true head- and torso-centred positions (metres)."""

    left: Array
    """``(n, 2)`` the ball's ``(u, v)`` in the left eye."""
    right: Array
    """``(n, 2)`` in the right eye."""
    gaze: Array
    """``(n, 6)`` the gaze joints (:data:`~sigmapi.envs.icub.GAZE`)."""
    head: Array
    """``(n, 3)`` true head-centred position (labels: scoring and references only)."""
    torso: Array
    """``(n, 3)`` true torso-centred position (labels)."""

    @property
    def n(self) -> int:
        """The number of views."""
        return int(self.gaze.shape[0])


def _stack(rows: list[tuple[Array, ...]]) -> Views3D:
    return Views3D(*(np.array(c, dtype=np.float64) for c in zip(*rows, strict=True)))


def _view(scene: ICubScene, seen: tuple[Array, Array], p: Array) -> tuple[Array, ...]:
    """One sensed view and its labels (the truth read only for them)."""
    return (
        seen[0],
        seen[1],
        scene.gaze(),
        st.head_position(scene, p),
        st.torso_position(scene, p),
    )


def _look(scene: ICubScene, rng: np.random.Generator) -> tuple[Array, Array] | None:
    """New random head postures and eye commands until both eyes see the ball."""
    for _ in range(_SEARCHES):
        scene.set_gaze([0.0, 0.0, 0.0, *st.random_neck3d(rng)])
        seen = st.search_both(scene, rng, tries=_SEARCH_TRIES)
        if seen is not None:
            return seen
    return None


def record_pairs(
    scene: ICubScene, n: int, rng: np.random.Generator, stage: str
) -> tuple[Views3D, Views3D]:
    """``n`` view pairs of balls put uniformly in :data:`~sigmapi.envs.icub.stereo.BOX`:
    ``stage="eyes"`` two random eye commands with the neck still (map H), ``"head"`` a new
    random head posture between the two views (map T)."""
    first: list[tuple[Array, ...]] = []
    second: list[tuple[Array, ...]] = []
    while len(first) < n:
        p = st.random_point(rng, 1)[0]
        st.place_ball(scene, p)
        for _ in range(PAIRS_PER_BALL):
            a = _look(scene, rng)
            if a is None or len(first) >= n:
                break
            va = _view(scene, a, p)
            if stage == "head":
                b = _look(scene, rng)
            else:
                b = st.search_both(scene, rng, tries=_SEARCH_TRIES)
            if b is not None:
                first.append(va)
                second.append(_view(scene, b, p))
    return _stack(first), _stack(second)


def retina3(v: Views3D, eye_size: int) -> Array:
    """Both eyes' retina as positions in [0, 1]^3: mean column, mean row (upward) and the
    horizontal disparity over +-:data:`DISPARITY` pixels."""
    u = 0.5 * (v.left[:, 0] + v.right[:, 0]) / eye_size
    up = 1.0 - 0.5 * (v.left[:, 1] + v.right[:, 1]) / eye_size
    d = 0.5 + 0.5 * (v.left[:, 0] - v.right[:, 0]) / DISPARITY
    return np.clip(np.column_stack([u, up, d]), 0.0, 1.0)


def eyes3(v: Views3D) -> Array:
    """The eyes' version, tilt and vergence scaled to [0, 1] over the random commands'
    range (:data:`~sigmapi.envs.icub.stereo.EYE_LOW`..``EYE_HIGH``)."""
    lo, hi = st.EYE_LOW[[1, 0, 2]], st.EYE_HIGH[[1, 0, 2]]
    g = v.gaze[:, [1, 0, 2]]
    return np.clip((g - lo) / (hi - lo), 0.0, 1.0)


def neck3(v: Views3D) -> Array:
    """The neck's yaw (to the right), pitch and roll scaled to [0, 1] over the random
    postures' range (:data:`~sigmapi.envs.icub.stereo.NECK_LOW`..``NECK_HIGH``; the
    fixation's extra pitch clipped)."""
    lo, hi = st.NECK_LOW[[2, 0, 1]], st.NECK_HIGH[[2, 0, 1]]
    g = v.gaze[:, [5, 3, 4]]
    pos = (g - lo) / (hi - lo)
    pos[:, 0] = 1.0 - pos[:, 0]
    return np.clip(pos, 0.0, 1.0)


class Chain3D:
    """Map H and map T of one seed, and the codes that feed them."""

    def __init__(self, map_h: SigmaPiSOM, map_t: SigmaPiSOM, eye_size: int) -> None:
        self.map_h, self.map_t, self.eye_size = map_h, map_t, eye_size

    def inputs_h(self, v: Views3D) -> tuple[Array, Array]:
        """Map H's codes of views ``v``: both retinas, the eyes' angles."""
        m = self.map_h
        return m.x_code.encode(retina3(v, self.eye_size)), m.y_code.encode(eyes3(v))

    def place_h(self, v: Views3D) -> Array:
        """Map H's winner's place ``(n, 3)`` in [0, 1] per axis."""
        m = self.map_h
        w = m.winner(*self.inputs_h(v), hard=True)
        return m.map_coords[w] / (np.asarray(m.map_shape) - 1.0)

    def inputs_t(self, v: Views3D) -> tuple[Array, Array]:
        """Map T's codes of views ``v``: map H's place, the neck's angles."""
        code = PopulationCode(self.map_h.map_shape, HEAD_WIDTH).encode(self.place_h(v))
        return code, self.map_t.y_code.encode(neck3(v))

    def inputs(self, stage: str, v: Views3D) -> tuple[Array, Array]:
        """The codes of map ``stage`` (``"head"`` for H, ``"torso"`` for T)."""
        return self.inputs_h(v) if stage == "head" else self.inputs_t(v)

    def model(self, stage: str) -> SigmaPiSOM:
        """Map H (``"head"``) or map T (``"torso"``)."""
        return self.map_h if stage == "head" else self.map_t


def learn_chain3d(
    eyes: tuple[Views3D, Views3D],
    head: tuple[Views3D, Views3D],
    *,
    grid: int,
    width: float,
    map_shape: tuple[int, int, int],
    iterations: int,
    seed: int,
    eye_size: int,
    backend: str = "auto",
) -> Chain3D:
    """Map H on the eyes' pairs, then map T on map H's code of the head's pairs (codes of
    ``grid`` units per axis, hills ``width`` wide; both maps ``map_shape``)."""
    g = (grid,) * 3
    s1, s2 = (int(s) for s in np.random.default_rng(seed).integers(0, 2**31 - 1, 2))
    map_h = SigmaPiSOM(som_config(g, g, map_shape, width, iterations, s1, backend))
    chain = Chain3D(map_h, map_h, eye_size)
    a, b = eyes
    map_h.fit((*chain.inputs_h(a), *chain.inputs_h(b)))
    cfg = som_config(map_h.map_shape, g, map_shape, width, iterations, s2, backend)
    chain.map_t = SigmaPiSOM(cfg)
    a, b = head
    chain.map_t.fit((*chain.inputs_t(a), *chain.inputs_t(b)))
    return chain


def _truth(stage: str, v: Views3D) -> Array:
    return v.head if stage == "head" else v.torso


def _origin(stage: str) -> Array:
    """Where :func:`spherical` sees from: between the eyes (head-centred; the right eye's
    centre is the frame's origin) or the torso-centred origin."""
    return np.array([0.0, st.EYE_HALF, 0.0]) if stage == "head" else np.zeros(3)


def spherical(z: Array, origin: Array) -> Array:
    """``(azimuth, elevation, distance)`` ``(n, 3)`` of positions ``z`` ``(n, 3)`` (x forward,
    y left, z up) seen from ``origin``: ``asin(y / r)``, ``atan2(z, x)`` (radians, the
    gimbals' angles of :func:`~sigmapi.envs.icub.direction_angles`) and ``r`` (metres)."""
    v = z - origin
    r = np.linalg.norm(v, axis=1)
    return np.column_stack(
        [np.arcsin(np.clip(v[:, 1] / r, -1, 1)), np.arctan2(v[:, 2], v[:, 0]), r]
    )


def _per_axis(cc: Array, zc: Array, ct: Array, zt: Array) -> list[float]:
    """R^2 per coordinate of the affine fit from map coordinates ``cc`` to ``zc`` (the
    calibration views), scored on ``ct``, ``zt`` (the test views)."""
    beta = affine_fit(cc, zc)
    pred = np.column_stack([ct, np.ones(ct.shape[0])]) @ beta
    sst = np.sum((zt - zt.mean(axis=0)) ** 2, axis=0)
    return [float(r) for r in 1.0 - np.sum((pred - zt) ** 2, axis=0) / sst]


def _position_scores(
    wc: NDArray[np.int64],
    zc: Array,
    w0: NDArray[np.int64],
    w1: NDArray[np.int64],
    zt: Array,
    coords: Array,
    origin: Array | None = None,
) -> dict[str, Any]:
    """Order (overall, per axis of ``x, y, z`` and per axis of :func:`spherical` from
    ``origin``), view consistency, usage and the error in cm of a quantiser whose
    calibration winners are ``wc`` (true positions ``zc``) and test winners ``w0``, ``w1``
    (true positions ``zt``), units at ``coords``; ``origin`` None: zero."""
    origin = np.zeros(3) if origin is None else origin
    m: dict[str, Any] = dict(winner_metrics(wc, zc, w0, w1, zt, coords, 1.0))
    m.pop("z_error")
    m["order_r2_per_axis"] = _per_axis(coords[wc], zc, coords[w0], zt)
    m["order_r2_per_axis_spherical"] = _per_axis(
        coords[wc], spherical(zc, origin), coords[w0], spherical(zt, origin)
    )
    err = np.linalg.norm(z_decoder(wc, zc, coords)[w0] - zt, axis=1) * 100.0
    m["error_cm"] = float(np.sqrt(np.mean(err**2)))
    m["error_cm_median"] = float(np.median(err))
    return m


def score_map(
    chain: Chain3D, stage: str, cal: tuple[Views3D, Views3D], test: tuple[Views3D, Views3D]
) -> dict[str, Any]:
    """Map ``stage``'s metrics against the true 3-D positions (the module's account) with its
    fold score."""
    model = chain.model(stage)
    (c0, _), (t0, t1) = cal, test
    x0, y0 = chain.inputs(stage, t0)
    x1, y1 = chain.inputs(stage, t1)
    scores = hard_scores(model, x0, y0)
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(x1, y1, hard=True)
    wc = model.winner(*chain.inputs(stage, c0), hard=True)
    zc, zt = _truth(stage, c0), _truth(stage, t0)
    out = _position_scores(wc, zc, w0, w1, zt, model.map_coords, _origin(stage))
    z = _truth(stage, t0)
    batch = Batch(x0, y0, x1, y1, z, t0.left, t0.gaze, t1.left, t1.gaze)
    starved, te, fold = fold_indicators(model, batch, w0, w1, scores)
    out.update(
        ordered=bool(min(out["order_r2_per_axis"]) >= ORDERED_R2),
        fold_score=fold,
        fold_threshold=FOLD_THRESHOLD,
        folded=bool(fold >= FOLD_THRESHOLD),
        starved_units=starved,
        topographic_error=te,
    )
    return out


def true_position_map(
    stage: str,
    train: tuple[Views3D, Views3D],
    cal: tuple[Views3D, Views3D],
    test: tuple[Views3D, Views3D],
    map_shape: tuple[int, ...],
    iterations: int,
    seed: int,
) -> dict[str, Any]:
    """A same-size Kohonen map trained on the true positions (metres) of the training views:
    a map keyed by the true position, scored as :func:`score_map` scores the learned one."""
    a, b = train
    za, zb = _truth(stage, a), _truth(stage, b)
    empty = np.zeros((za.shape[0], 0))
    som = KohonenSOM(map_shape, iterations=iterations, seed=seed)
    som.fit((za, empty, zb, empty))

    def win(v: Views3D) -> NDArray[np.int64]:
        z = _truth(stage, v)
        return som.winner(z, np.zeros((z.shape[0], 0)))

    (c0, _), (t0, t1) = cal, test
    zc, zt = _truth(stage, c0), _truth(stage, t0)
    return _position_scores(win(c0), zc, win(t0), win(t1), zt, som.coords, _origin(stage))


def kmeans_reference(
    stage: str,
    train: tuple[Views3D, Views3D],
    cal: tuple[Views3D, Views3D],
    test: tuple[Views3D, Views3D],
    k: int,
    seed: int,
    rounds: int = 50,
) -> dict[str, Any]:
    """k-means (k-means++ start, Lloyd's rounds) with ``k`` centres on the true positions of
    the training views (each place once; at most as many centres as places); each test
    view's error is to the mean true position of the calibration views nearest the same
    centre (as the maps are decoded)."""
    rng = np.random.default_rng(seed)
    z = np.unique(np.concatenate([_truth(stage, v) for v in train]), axis=0)
    k = min(k, z.shape[0])
    centres = z[rng.integers(z.shape[0])][None, :]
    for _ in range(1, k):  # k-means++
        d = np.min(np.sum((z[:, None, :] - centres[None, :, :]) ** 2, axis=2), axis=1)
        centres = np.vstack([centres, z[rng.choice(z.shape[0], p=d / d.sum())]])
    for _ in range(rounds):
        lab = _nearest(z, centres)
        for j in range(k):
            if np.any(lab == j):
                centres[j] = z[lab == j].mean(axis=0)
    (c0, _), (t0, _) = cal, test
    zc, zt = _truth(stage, c0), _truth(stage, t0)
    wc, w0 = _nearest(zc, centres), _nearest(zt, centres)
    table = z_decoder(wc, zc, centres)
    err = np.linalg.norm(table[w0] - zt, axis=1) * 100.0
    return {"error_cm": float(np.sqrt(np.mean(err**2))), "error_cm_median": float(np.median(err))}


def _nearest(z: Array, centres: Array) -> NDArray[np.int64]:
    return np.argmin(np.sum((z[:, None, :] - centres[None, :, :]) ** 2, axis=2), axis=1)


def evaluation_pairs(
    scene: ICubScene, n: int
) -> dict[str, tuple[tuple[Views3D, Views3D], tuple[Views3D, Views3D]]]:
    """Calibration and test pairs of each stage from the fixed evaluation seed."""
    out = {}
    for k, stage in enumerate(("eyes", "head")):
        seeds = np.random.SeedSequence([EVAL_SEED, k]).spawn(2)
        cal, test = (np.random.default_rng(s) for s in seeds)
        out[stage] = (record_pairs(scene, n, cal, stage), record_pairs(scene, n, test, stage))
    return out


def run_maps(
    seed: int,
    *,
    train_pairs: int = 2000,
    eval_pairs: int = 400,
    grid: int = 6,
    width: float = 1.0,
    map_shape: tuple[int, int, int] = (6, 6, 6),
    iterations: int = 15_000,
    backend: str = "auto",
) -> dict[str, Any]:
    """One seed of the 3-D maps: record, learn, score against both references."""
    t0 = time.perf_counter()
    scene = ICubScene()
    st.float_ball(scene)
    scene.seal()
    rng = np.random.default_rng(seed)
    train = {s: record_pairs(scene, train_pairs, rng, s) for s in ("eyes", "head")}
    ev = evaluation_pairs(scene, eval_pairs)
    t_record = time.perf_counter() - t0
    chain = learn_chain3d(
        train["eyes"],
        train["head"],
        grid=grid,
        width=width,
        map_shape=map_shape,
        iterations=iterations,
        seed=seed,
        eye_size=scene.eye_size,
        backend=backend,
    )
    t_learn = time.perf_counter() - t0 - t_record
    out: dict[str, Any] = {}
    k = int(np.prod(map_shape))
    for name, stage, data in (("map_head", "head", "eyes"), ("map_torso", "torso", "head")):
        cal, test = ev[data]
        m = score_map(chain, stage, cal, test)
        m["true_position"] = true_position_map(
            stage, train[data], cal, test, map_shape, iterations, seed
        )
        m["kmeans"] = kmeans_reference(stage, train[data], cal, test, k, seed)
        m["error_ratio_to_kmeans"] = m["error_cm"] / m["kmeans"]["error_cm"]
        out[name] = m
    scene.close()
    out["seconds"] = {
        "record": t_record,
        "learn": t_learn,
        "total": time.perf_counter() - t0,
    }
    out["weights"] = int(chain.map_h.weights_.size + chain.map_t.weights_.size)
    return out
