# Over 500 lines: the 3-D maps of one chain (its views, codes, three designs, the soft readout)
# and their scoring beside both references, read as one; the measurements live in
# docs/guide/icub-3d.md.
"""The iCub's 3-D peripersonal space seen by both eyes: a chain of two 3-D maps, scored.

The world is :mod:`sigmapi.envs.icub.stereo`'s: a ball anywhere in a box 20 cm deep and 20 cm
high within the right arm's reach, in the air, seen by both eyes.

- **Map H** (head-centred, eyes first) reads what both eyes see (the eyes' mean column and
  row and the horizontal disparity ``u_left - u_right``) and the eyes' angles (version,
  tilt, vergence). Its view pairs come from two random eye commands (the neck still) that
  both see the ball: the pair shares the ball's head-centred position. Per axis the
  relation is close to the paper's sum: the head-centred azimuth is the version plus the
  column's angle, the elevation the tilt plus the row's, and the distance a function of the
  vergence plus the disparity's angle.
- **Map T** (torso-centred, then the head) reads map H's winner's place and the neck's yaw,
  pitch and roll. Its pairs: the head turns to a new random posture between the two views,
  and the eyes find the ball again: the pair shares the torso-centred position.

Each map is one of :data:`DESIGNS` (:func:`learn_chain3d`): ``"grid"``, one 3-D Sigma-Pi map
(``map_shape``, e.g. 6x6x6) on 3-D population codes of both inputs (map T's first code a hill
:data:`~sigmapi.experiments.icub.maps.HEAD_WIDTH` wide at map H's place on its grid);
``"factorised"``, a :class:`FactorMap` of a 2-D direction map (column and row with version and
tilt; map T: map H's direction place with the neck's yaw and pitch) and a 1-D distance map
(disparity with vergence; map T: map H's distance place with the neck's pitch); ``"axes"``, a
:class:`FactorMap` of three 1-D maps, one per axis, each on the pair of variables whose sum
that axis is (map T: the azimuth with the neck's yaw, the elevation and the distance with its
pitch). The codes span the commands' ranges or the sensed ones (:data:`SCALES`); map T reads
map H's place as its winner's grid coordinates or moved between units by the scores
(:data:`READOUTS`). Each part of map T is fitted :data:`RESTARTS` times from seeds spawned from
its own, and the fit with the lowest fold score on map T's own training pairs (the robot's
codes of both views, no truth) kept: :func:`learn_chain3d`'s ``restarts``.

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

import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.baselines import KohonenSOM
from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.envs.icub import ICubScene
from sigmapi.envs.icub import stereo as st
from sigmapi.errors import ConfigError
from sigmapi.experiments.icub.maps import (
    HEAD_WIDTH,
    Extra,
    quantiser_scores,
    som_config,
    unit_rows,
)
from sigmapi.metrics import (
    EVAL_SEED,
    FOLD_THRESHOLD,
    ORDERED_R2,
    affine_fit,
    fold_indicators,
    hard_scores,
    z_decoder,
)
from sigmapi.model.som import SigmaPiSOM
from sigmapi.tasks import Batch

Array = NDArray[np.float64]

DISPARITY = st.FUSION
"""Half the range of horizontal disparities the retina's code spans, pixels (``u_left -
u_right`` within the fusion range, :data:`~sigmapi.envs.icub.stereo.FUSION`)."""
SENSED_PERCENT = 1.0
"""The percentile at either end of a sensed variable's range that :func:`sensed_scales`
spans (the outer 1 % of the views clipped to the ends)."""
PAIRS_PER_BALL_3D = 2
"""View pairs recorded per ball put in the box (each from a new head posture): the 3-D
task's own setting, apart from the table's :data:`~sigmapi.envs.icub.frames.PAIRS_PER_BALL`
(``--pairs-per-ball``, which the box does not read)."""
DESIGN = "axes"
"""The maps' design by default (:data:`DESIGNS`; chosen on seeds 0 and 1,
docs/guide/icub-3d.md)."""
GRID = 24
"""Units of map H's column, row, version and tilt codes by default."""
DEPTH_GRID = 24
"""Units of map H's disparity and vergence codes by default."""
HEAD_SHAPE = (18, 18, 6)
"""Map H's shape by default (its azimuth, elevation and distance maps' units): finer than map
T's (:data:`TORSO_SHAPE`) along the directions, so that a unit of map T spans more than one
of map H."""
TORSO_SHAPE = (6, 6, 6)
"""Map T's shape by default (its azimuth, elevation and distance maps' units)."""
TORSO_GRID = 20
"""Units per axis of map T's codes by default (of map H's place and of the neck's angles)."""
READOUT = "soft"
"""How map T reads map H's place by default (:data:`READOUTS`)."""
ITERATIONS = 30_000
"""Iterations per map by default."""
RESTARTS = 3
"""Fits of each part of map T by default (:func:`learn_chain3d`'s ``restarts``; chosen on
seeds 0-2, docs/guide/icub-3d.md)."""
MAX_RESTARTS = 10
"""Most fits of a part :func:`learn_chain3d` accepts (each costs a whole fit)."""
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


def _look(
    scene: ICubScene, rng: np.random.Generator, turn: float | None = None
) -> tuple[Array, Array] | None:
    """New random head postures and eye commands until both eyes see the ball; ``turn``
    (radians): each posture within ``turn`` of the neck's present one on each joint (clipped
    to the random postures' range), else anywhere in it."""
    neck = scene.gaze()[3:6]
    for _ in range(_SEARCHES):
        if turn is None:
            new = st.random_neck3d(rng)
        else:
            new = np.clip(neck + rng.uniform(-turn, turn, 3), st.NECK_LOW, st.NECK_HIGH)
        scene.set_gaze([0.0, 0.0, 0.0, *new])
        seen = st.search_both(scene, rng, tries=_SEARCH_TRIES)
        if seen is not None:
            return seen
    return None


def record_pairs(
    scene: ICubScene,
    n: int,
    rng: np.random.Generator,
    stage: str,
    turn: float | None = None,
) -> tuple[Views3D, Views3D]:
    """``n`` view pairs of balls put uniformly in :data:`~sigmapi.envs.icub.stereo.BOX`:
    ``stage="eyes"`` two random eye commands with the neck still (map H), ``"head"`` a new
    random head posture between the two views (map T; ``turn``: within ``turn`` radians of
    the first view's on each neck joint, :func:`_look`)."""
    first: list[tuple[Array, ...]] = []
    second: list[tuple[Array, ...]] = []
    while len(first) < n:
        p = st.random_point(rng, 1)[0]
        st.place_ball(scene, p)
        for _ in range(PAIRS_PER_BALL_3D):
            a = _look(scene, rng)
            if a is None or len(first) >= n:
                break
            va = _view(scene, a, p)
            if stage == "head":
                b = _look(scene, rng, turn)
            else:
                b = st.search_both(scene, rng, tries=_SEARCH_TRIES)
            if b is not None:
                first.append(va)
                second.append(_view(scene, b, p))
    return _stack(first), _stack(second)


SENSED = (
    "column",
    "row_up",
    "disparity",
    "version",
    "tilt",
    "vergence",
    "neck_yaw_right",
    "neck_pitch",
    "neck_roll",
)
"""The sensed variables the codes read, in :func:`sensed` order: both eyes' mean column and
mean row (upward) and the horizontal disparity ``u_left - u_right`` (pixels), the eyes'
version, tilt and vergence and the neck's yaw (to the right), pitch and roll (radians)."""


def sensed(v: Views3D) -> Array:
    """The :data:`SENSED` variables of views ``v`` ``(n, 9)``: pixels and joint angles only."""
    g = v.gaze
    return np.column_stack(
        [
            0.5 * (v.left[:, 0] + v.right[:, 0]),
            -0.5 * (v.left[:, 1] + v.right[:, 1]),
            v.left[:, 0] - v.right[:, 0],
            g[:, 1],
            g[:, 0],
            g[:, 2],
            -g[:, 5],
            g[:, 3],
            g[:, 4],
        ]
    )


@dataclass(frozen=True)
class Scales:
    """The interval ``[low, high]`` of each :data:`SENSED` variable that its code spans (a
    value outside is clipped to the nearer end)."""

    low: Array
    """``(9,)`` the low ends."""
    high: Array
    """``(9,)`` the high ends."""

    def unit(self, v: Views3D) -> Array:
        """The sensed variables of ``v`` scaled to [0, 1] ``(n, 9)``."""
        span = np.where(self.high > self.low, self.high - self.low, 1.0)  # a constant: 0
        return np.clip((sensed(v) - self.low) / span, 0.0, 1.0)


SCALES = ("fixed", "sensed")
"""What the codes span (:func:`learn_chain3d`): the commands' ranges or the sensed ones."""


def fixed_scales(eye_size: int) -> Scales:
    """The ranges the robot's commands span: the whole image, disparities within
    +-:data:`DISPARITY` pixels, the eyes' random commands
    (:data:`~sigmapi.envs.icub.stereo.EYE_LOW`..``EYE_HIGH``) and the neck's random postures
    (:data:`~sigmapi.envs.icub.stereo.NECK_LOW`..``NECK_HIGH``)."""
    e, n = st.EYE_LOW[[1, 0, 2]], st.NECK_LOW
    eh, nh = st.EYE_HIGH[[1, 0, 2]], st.NECK_HIGH
    low = [0.0, -float(eye_size), -DISPARITY, *e, -nh[2], n[0], n[1]]
    high = [float(eye_size), 0.0, DISPARITY, *eh, -n[2], nh[0], nh[1]]
    return Scales(np.array(low), np.array(high))


def sensed_scales(views: tuple[Views3D, ...], percent: float = SENSED_PERCENT) -> Scales:
    """Each variable's ``percent``-th to ``(100 - percent)``-th percentile over ``views``: the
    ranges the robot's own senses met (pixels and joint angles; never the truth)."""
    s = np.concatenate([sensed(v) for v in views])
    return Scales(*(np.percentile(s, [percent, 100.0 - percent], axis=0)))


def projected(scene: ICubScene, v: Views3D) -> Views3D:
    """Views ``v`` with each eye's detection replaced by the camera's projection of the
    ball's true centre at the same gaze: **a reference arm that reads the truth** (the
    comparison "maps from pixels against maps from projections"), never a learner's input
    in the pixels arm. The ball is put back where each view saw it (from its torso-centred
    label: the torso does not move)."""
    left, right = np.empty_like(v.left), np.empty_like(v.right)
    world = st.torso_to_world(scene, v.torso)
    with scene.truth():
        for i in range(v.n):
            scene.set_gaze(v.gaze[i])
            left[i] = scene.project(world[i], "l_eye")[0]
            right[i] = scene.project(world[i], "r_eye")[0]
    return Views3D(left, right, v.gaze, v.head, v.torso)


def retina3(v: Views3D, eye_size: int) -> Array:
    """Both eyes' retina as positions in [0, 1]^3: mean column, mean row (upward) and the
    horizontal disparity over +-:data:`DISPARITY` pixels."""
    return fixed_scales(eye_size).unit(v)[:, 0:3]


def eyes3(v: Views3D) -> Array:
    """The eyes' version, tilt and vergence scaled to [0, 1] over the random commands'
    range (:data:`~sigmapi.envs.icub.stereo.EYE_LOW`..``EYE_HIGH``)."""
    return fixed_scales(1).unit(v)[:, 3:6]


def neck3(v: Views3D) -> Array:
    """The neck's yaw (to the right), pitch and roll scaled to [0, 1] over the random
    postures' range (:data:`~sigmapi.envs.icub.stereo.NECK_LOW`..``NECK_HIGH``; the
    fixation's extra pitch clipped)."""
    return fixed_scales(1).unit(v)[:, 6:9]


class FactorMap:
    """A 3-D map made of lower-dimensional Sigma-Pi maps, each on some of the three axes
    (a 2-D direction map and a 1-D distance map, or one 1-D map per axis). Unit ``(i, j,
    k)`` of the product grid (the parts' grids side by side) wins when each part's unit
    does; :meth:`winner` reads one ``(x, y)`` pair of codes per part (so
    ``model.winner(*chain.inputs(stage, v))`` holds for either design)."""

    def __init__(self, *parts: SigmaPiSOM) -> None:
        self.parts = parts
        self.map_shape = tuple(int(n) for p in parts for n in p.map_shape)
        self.map_coords = grid_coordinates(self.map_shape)
        self.n_units = int(np.prod(self.map_shape))

    @property
    def axes(self) -> list[list[int]]:
        """The axes of the 3-D position each part lays out."""
        out, k = [], 0
        for p in self.parts:
            out.append(list(range(k, k + len(p.map_shape))))
            k += len(p.map_shape)
        return out

    @property
    def n_weights(self) -> int:
        """The weights of all parts."""
        return int(sum(p.weights_.size for p in self.parts))

    def join(self, *winners: NDArray[np.int64]) -> NDArray[np.int64]:
        """The product grid's unit of the parts' units ``winners``."""
        sizes = tuple(p.n_units for p in self.parts)
        return np.asarray(np.ravel_multi_index(winners, sizes), dtype=np.int64)

    def winner(self, *codes: tuple[Array, Array], hard: bool = True) -> NDArray[np.int64]:
        """The product grid's winners of the parts' codes ``codes`` (one ``(x, y)`` each)."""
        return self.join(*(p.winner(*c, hard=hard) for p, c in zip(self.parts, codes, strict=True)))


Model = SigmaPiSOM | FactorMap


class Chain3D:
    """Map H and map T of one seed, and the codes that feed them (each map a 3-D
    :class:`~sigmapi.model.som.SigmaPiSOM` or a :class:`FactorMap`)."""

    def __init__(
        self,
        map_h: Model,
        map_t: Model,
        eye_size: int,
        scales: Scales | None = None,
        readout: str = READOUT,
    ) -> None:
        self.map_h, self.map_t, self.eye_size = map_h, map_t, eye_size
        self.scales = fixed_scales(eye_size) if scales is None else scales
        _check_choice("readout", readout, READOUTS)
        self.readout = readout
        self.restart_scores: list[list[float]] = []
        """Map T's parts' fold scores on its training pairs, one per fit (:func:`learn_chain3d`'s
        ``restarts``; empty lists for one fit)."""

    def inputs_h(self, v: Views3D) -> Any:
        """Map H's codes of views ``v``: both retinas (column, row, disparity) and the eyes'
        angles (version, tilt, vergence), an ``(x, y)`` pair; of a :class:`FactorMap` one
        pair per part, on its axes (e.g. column and row with version and tilt)."""
        s = self.scales.unit(v)
        return _codes(self.map_h, s[:, 0:3], s[:, 3:6])

    def winners_h(self, v: Views3D) -> NDArray[np.int64]:
        """Map H's winners of views ``v``."""
        return self.map_h.winner(*self.inputs_h(v), hard=True)

    def place_h(self, v: Views3D) -> Array:
        """Map H's winner's place ``(n, 3)`` in [0, 1] per axis: the winner's grid
        coordinates (``readout="hard"``), or moved along each axis to the vertex of the
        parabola through the winner's and its two neighbours' scores (``"soft"``, at most half
        a unit: :func:`soft_place`)."""
        m = self.map_h
        size = np.asarray(m.map_shape) - 1.0
        if self.readout == "hard":
            return m.map_coords[self.winners_h(v)] / size
        return self.soft_grid_place("head", v) / size

    def soft_grid_place(self, stage: str, v: Views3D) -> Array:
        """Map ``stage``'s winner's place on its grid ``(n, 3)`` (grid units), moved along
        each axis to the vertex of the parabola through the winner's and its two neighbours'
        scores (:func:`soft_place`)."""
        m, inputs = self.model(stage), self.inputs(stage, v)
        if isinstance(m, FactorMap):
            return np.column_stack(
                [soft_place(p, *c) for p, c in zip(m.parts, inputs, strict=True)]
            )
        return soft_place(m, *inputs)

    def inputs_t(self, v: Views3D) -> Any:
        """Map T's codes of views ``v``: map H's place (hills
        :data:`~sigmapi.experiments.icub.maps.HEAD_WIDTH` wide) and
        the neck's yaw, pitch and roll; of a :class:`FactorMap` one pair per part: map H's
        place on the part's axes with the neck's yaw for the azimuth and its pitch for the
        elevation and the distance."""
        neck, m = self.scales.unit(v)[:, 6:9], self.map_t
        if self.readout == "population":
            return self._population_inputs(v, neck)
        place = self.place_h(v)
        if isinstance(m, FactorMap):
            return _codes(m, place, neck[:, [0, 1, 1]])
        code = PopulationCode(self.map_h.map_shape, HEAD_WIDTH).encode(place)
        return code, m.y_code.encode(neck)

    def _neck_codes(self, neck: Array) -> list[Array]:
        """Map T's second codes, per part of a :class:`FactorMap`: the neck's yaw on the
        azimuth's axis, its pitch on the elevation's and the distance's."""
        m, ny = self.map_t, neck[:, [0, 1, 1]]
        assert isinstance(m, FactorMap)
        return [p.y_code.encode(ny[:, a]) for p, a in zip(m.parts, m.axes, strict=True)]

    def response_h(self, v: Views3D) -> list[Array]:
        """Map H's population response to views ``v``, per part (one array for a 3-D
        map): each unit's activation (:meth:`~sigmapi.model.som.SigmaPiSOM.respond`) clipped
        at zero, the vector of a view scaled to length 1 (a code as the others are)."""
        m, inputs = self.map_h, self.inputs_h(v)
        pairs = zip(m.parts, inputs, strict=True) if isinstance(m, FactorMap) else [(m, inputs)]
        return [unit_rows(np.maximum(p.respond(*c), 0.0)) for p, c in pairs]

    def _population_inputs(self, v: Views3D, neck: Array) -> Any:
        """Map T's codes under ``readout="population"``: each part reads the response vector of
        map H's part on the same axes (:meth:`response_h`) with the neck's code."""
        m, resp = self.map_t, self.response_h(v)
        if isinstance(m, FactorMap):
            return tuple(zip(resp, self._neck_codes(neck), strict=True))
        return resp[0], m.y_code.encode(neck)

    def inputs(self, stage: str, v: Views3D) -> Any:
        """The codes of map ``stage`` (``"head"`` for H, ``"torso"`` for T)."""
        return self.inputs_h(v) if stage == "head" else self.inputs_t(v)

    def model(self, stage: str) -> Model:
        """Map H (``"head"``) or map T (``"torso"``)."""
        return self.map_h if stage == "head" else self.map_t

    def winners(self, stage: str, v: Views3D) -> NDArray[np.int64]:
        """Map ``stage``'s winners of views ``v`` (units of its 3-D grid)."""
        return self.model(stage).winner(*self.inputs(stage, v), hard=True)

    @property
    def n_weights(self) -> int:
        """The weights of both maps."""
        return sum(_n_weights(m) for m in (self.map_h, self.map_t))


def _codes(m: Model, x: Array, y: Array) -> Any:
    """Codes of positions ``x`` and ``y`` ``(n, 3)`` in [0, 1]: one ``(x, y)`` pair for a
    Sigma-Pi map, one per part, on its axes, for a :class:`FactorMap`."""
    if isinstance(m, FactorMap):
        return tuple(
            (p.x_code.encode(x[:, a]), p.y_code.encode(y[:, a]))
            for p, a in zip(m.parts, m.axes, strict=True)
        )
    return m.x_code.encode(x), m.y_code.encode(y)


def _n_weights(m: Model) -> int:
    return m.n_weights if isinstance(m, FactorMap) else int(m.weights_.size)


def _fit(m: Model, a: Any, b: Any) -> None:
    """Fit ``m`` on the codes of a pair's first views ``a`` and second views ``b``."""
    if isinstance(m, FactorMap):
        for part, pa, pb in zip(m.parts, a, b, strict=True):
            part.fit((*pa, *pb))
    else:
        m.fit((*a, *b))


def restart_seeds(seed: int, restarts: int) -> list[int]:
    """The seeds of a part's ``restarts`` fits: its own ``seed`` first (so one fit is the fit
    without restarts), then one from each child of a :class:`numpy.random.SeedSequence`
    spawned from it (the list for ``n`` fits the first ``n`` of the list for more)."""
    kids = np.random.SeedSequence(seed).spawn(restarts - 1)
    return [seed, *(int(k.generate_state(1)[0]) for k in kids)]


def pair_fold_score(model: SigmaPiSOM, a: tuple[Array, Array], b: tuple[Array, Array]) -> float:
    """The fold score (:func:`sigmapi.metrics.fold_indicators`) of a Sigma-Pi map on the codes
    ``a`` and ``b`` of view pairs' two views: it reads the robot's codes only (the batch's true
    positions are empty: no label can enter the score)."""
    empty = np.zeros((a[0].shape[0], 0))
    return fold_indicators(model, Batch(*a, *b, empty, empty, empty, empty, empty))[2]


def _fit_kept(
    part: SigmaPiSOM, a: tuple[Array, Array], b: tuple[Array, Array], restarts: int
) -> tuple[SigmaPiSOM, list[float]]:
    """``part`` fitted on the pairs' codes ``a``, ``b`` from each of its :func:`restart_seeds`,
    and the fit kept: the one with the lowest :func:`pair_fold_score` on these same training
    pairs (the first on a tie), with every fit's score (none for one fit: nothing chosen)."""
    part.fit((*a, *b))
    if restarts == 1:
        return part, []
    seed = part.config.seed
    assert seed is not None  # the chain's maps are always seeded (learn_chain3d)
    fits, scores = [part], [pair_fold_score(part, a, b)]
    for s in restart_seeds(seed, restarts)[1:]:
        m = SigmaPiSOM(part.config.replace(seed=s))
        m.fit((*a, *b))
        fits.append(m)
        scores.append(pair_fold_score(m, a, b))
    return fits[int(np.argmin(scores))], scores


def _fit_restarts(m: Model, a: Any, b: Any, restarts: int) -> tuple[Model, list[list[float]]]:
    """``m`` fitted with :func:`_fit_kept` per part (a Sigma-Pi map: as one part), and each
    part's scores."""
    if not isinstance(m, FactorMap):
        kept, scores = _fit_kept(m, a, b, restarts)
        return kept, [scores]
    out = [_fit_kept(p, pa, pb, restarts) for p, pa, pb in zip(m.parts, a, b, strict=True)]
    return FactorMap(*(p for p, _ in out)), [sc for _, sc in out]


def _new_map(
    design: str,
    codes: tuple[int, int, int],
    map_shape: tuple[int, int, int],
    width: float,
    iterations: int,
    seed: int,
    backend: str,
    x_shapes: list[tuple[int, ...]] | None = None,
) -> Model:
    """A fresh 3-D map on codes of ``codes`` units per axis (both inputs): ``"grid"`` one
    Sigma-Pi map; ``"factorised"`` a :class:`FactorMap` of a 2-D map on the first two axes
    and a 1-D map on the third; ``"axes"`` one 1-D map per axis. ``x_shapes``: the first
    input's shape per part (one for ``"grid"``), when it is not a code of ``codes``."""
    if design == "grid":
        x = codes if x_shapes is None else x_shapes[0]
        return SigmaPiSOM(som_config(x, codes, map_shape, width, iterations, seed, backend))
    split = [[0, 1], [2]] if design == "factorised" else [[0], [1], [2]]
    seeds = [seed, *(int(s) for s in np.random.default_rng(seed).integers(0, 2**31 - 1, 2))]
    parts = []
    for i, (axes, s) in enumerate(zip(split, seeds, strict=False)):
        c, ms = tuple(codes[a] for a in axes), tuple(map_shape[a] for a in axes)
        x = c if x_shapes is None else x_shapes[i]
        parts.append(SigmaPiSOM(som_config(x, c, ms, width, iterations, s, backend)))
    return FactorMap(*parts)


def learn_chain3d(
    eyes: tuple[Views3D, Views3D],
    head: tuple[Views3D, Views3D],
    *,
    seed: int,
    eye_size: int,
    grid: int = GRID,
    width: float = 1.0,
    map_shape: tuple[int, int, int] = TORSO_SHAPE,
    iterations: int = ITERATIONS,
    backend: str = "auto",
    design: str = DESIGN,
    torso_design: str | None = None,
    scales: str = "fixed",
    depth_grid: int | None = DEPTH_GRID,
    readout: str = READOUT,
    torso_grid: int | None = TORSO_GRID,
    head_shape: tuple[int, int, int] | None = HEAD_SHAPE,
    restarts: int = RESTARTS,
) -> Chain3D:
    """Map H on the eyes' pairs, then map T on map H's code of the head's pairs (codes of
    ``grid`` units per axis, hills ``width`` wide; map T ``map_shape``). The defaults are the
    measured design (docs/guide/icub-3d.md): the one place :func:`run_maps` and the reach's
    run take it from.

    ``design``: ``"grid"`` (each map one 3-D Sigma-Pi map) or ``"factorised"`` (each a
    :class:`FactorMap`: a 2-D direction map and a 1-D distance map, ``map_shape`` their
    product); ``torso_design``: map T's, when it differs. ``scales``: ``"fixed"`` (the codes
    span the commands' ranges, :func:`fixed_scales`) or ``"sensed"`` (the training views'
    percentiles, :func:`sensed_scales`). ``depth_grid``: units of the codes along the depth
    (the disparity and the vergence; None: ``grid``). ``readout``: how map T reads map H
    (:data:`READOUTS`, :meth:`Chain3D.place_h`, :meth:`Chain3D.response_h`).
    ``torso_grid``: units per axis of map T's codes (None: ``grid``). ``head_shape``: map H's
    shape (None: ``map_shape``).

    ``restarts``: fits of each part of map T (each 1-D map of ``"axes"``; the whole map of
    ``"grid"``), the first from the seed one fit uses, the others from seeds spawned from it
    (:func:`restart_seeds`); per part the fit kept is the one with the lowest fold score on
    map T's own training pairs (:func:`pair_fold_score`): the choice reads the robot's codes
    of both views of each pair (map H's place and the neck's angles), never a true position.
    Each fit's score per part is kept in ``Chain3D.restart_scores``. 1: one fit, the map T of
    before the option, bit for bit."""
    _validate.integer("restarts", restarts, 1, MAX_RESTARTS, fix="e.g. 1 (one fit) or 3")
    _check_choice("design", design, DESIGNS)
    t_design = design if torso_design is None else torso_design
    _check_choice("torso_design", t_design, DESIGNS)
    _check_choice("scales", scales, SCALES)
    if readout == "population" and t_design != design:
        raise ConfigError(
            f"readout 'population' needs map T's design to be map H's ({design!r}), got "
            f"torso_design {t_design!r}; drop torso_design or pick readout 'soft'"
        )
    sc = fixed_scales(eye_size) if scales == "fixed" else sensed_scales((*eyes, *head))
    dg = grid if depth_grid is None else depth_grid
    s1, s2 = (int(s) for s in np.random.default_rng(seed).integers(0, 2**31 - 1, 2))
    h_shape = map_shape if head_shape is None else head_shape
    map_h = _new_map(design, (grid, grid, dg), h_shape, width, iterations, s1, backend)
    chain = Chain3D(map_h, map_h, eye_size, sc, readout)
    a, b = eyes
    _fit(map_h, chain.inputs_h(a), chain.inputs_h(b))
    tg = (grid if torso_grid is None else torso_grid,) * 3
    if readout == "population":  # each part of map T on the response of map H's part
        parts = map_h.parts if isinstance(map_h, FactorMap) else [map_h]
        xs = [tuple(int(n) for n in p.map_shape) for p in parts]
        chain.map_t = _new_map(t_design, tg, map_shape, width, iterations, s2, backend, xs)
    elif t_design == "grid":  # map H's place code (its grid) with the neck's
        cfg = som_config(map_h.map_shape, tg, map_shape, width, iterations, s2, backend)
        chain.map_t = SigmaPiSOM(cfg)
    else:
        chain.map_t = _new_map(t_design, tg, map_shape, width, iterations, s2, backend)
    a, b = head
    chain.map_t, chain.restart_scores = _fit_restarts(
        chain.map_t, chain.inputs_t(a), chain.inputs_t(b), restarts
    )
    return chain


DESIGNS = ("grid", "factorised", "axes")
"""The maps' designs (:func:`learn_chain3d`)."""
PART_NAMES = {2: ("direction", "distance"), 3: ("azimuth", "elevation", "distance")}
"""The names of a :class:`FactorMap`'s parts in the scores, by their number."""
READOUTS = ("hard", "soft", "population")
"""How map T reads map H: its place (:meth:`Chain3D.place_h`) or its population response
(:meth:`Chain3D.response_h`)."""


def _check_choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ConfigError(
            f"{name} must be one of {', '.join(choices)}, got {value!r}; pick one of those"
        )


def soft_place(model: SigmaPiSOM, x: Array, y: Array) -> Array:
    """Grid places ``(n, d)`` of the hard winners of codes ``x``, ``y`` moved to the vertex
    of the parabola through their scores (:func:`~sigmapi.metrics.hard_scores`,
    :func:`parabola_place`)."""
    return parabola_place(hard_scores(model, x, y), tuple(int(n) for n in model.map_shape))


def parabola_place(scores: Array, shape: tuple[int, ...]) -> Array:
    """Grid places ``(n, d)`` of the best units of ``scores`` ``(n, prod(shape))`` (units in
    C order on grid ``shape``), each axis moved to the vertex of the parabola through the
    best unit's and its two neighbours' scores along that axis, by at most half a unit (no
    move at the grid's ends or where the scores do not bend down)."""
    w = np.argmax(scores, axis=1)
    idx = np.array(np.unravel_index(w, shape)).T  # (n, d)
    place = idx.astype(np.float64)
    rows = np.arange(w.size)
    for a, n in enumerate(shape):
        lo, hi = idx.copy(), idx.copy()
        lo[:, a] = np.maximum(idx[:, a] - 1, 0)
        hi[:, a] = np.minimum(idx[:, a] + 1, n - 1)
        s_lo = scores[rows, np.ravel_multi_index(lo.T, shape)]
        s_hi = scores[rows, np.ravel_multi_index(hi.T, shape)]
        bend = s_lo - 2.0 * scores[rows, w] + s_hi
        inside = (idx[:, a] > 0) & (idx[:, a] < n - 1) & (bend < 0)
        step = np.where(inside, 0.5 * (s_lo - s_hi) / np.where(inside, bend, -1.0), 0.0)
        place[:, a] += np.clip(step, -0.5, 0.5)
    return place


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


def _position(origin: Array) -> Extra:
    """The scores of a map of 3-D positions beside its order: per axis of ``x, y, z`` and per
    axis of :func:`spherical` from ``origin``, and the error in cm."""

    def extra(cc: Array, zc: Array, ct: Array, zt: Array, decoded: Array) -> dict[str, object]:
        err = np.linalg.norm(decoded - zt, axis=1) * 100.0
        return {
            "order_r2_per_axis": _per_axis(cc, zc, ct, zt),
            "order_r2_per_axis_spherical": _per_axis(
                cc, spherical(zc, origin), ct, spherical(zt, origin)
            ),
            "error_cm": float(np.sqrt(np.mean(err**2))),
            "error_cm_median": float(np.median(err)),
        }

    return extra


def _folds(
    model: SigmaPiSOM, a: tuple[Array, Array], b: tuple[Array, Array], z: Array
) -> tuple[NDArray[np.int64], dict[str, Any]]:
    """View 0's winners of a Sigma-Pi map on the codes ``a`` and ``b`` of the test pairs'
    two views, and its fold indicators."""
    scores = hard_scores(model, *a)
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(*b, hard=True)
    empty = np.zeros((z.shape[0], 0))
    batch = Batch(*a, *b, z, empty, empty, empty, empty)
    starved, te, fold = fold_indicators(model, batch, w0, w1, scores)
    return w0, {
        "fold_score": fold,
        "folded": bool(fold >= FOLD_THRESHOLD),
        "starved_units": starved,
        "topographic_error": te,
    }


def score_map(
    chain: Chain3D, stage: str, cal: tuple[Views3D, Views3D], test: tuple[Views3D, Views3D]
) -> dict[str, Any]:
    """Map ``stage``'s metrics against the true 3-D positions (the module's account) with its
    fold score; a :class:`FactorMap`'s fold indicators are its two maps' (``parts``): the
    score the larger, the starved units summed, the topographic error the larger, and
    folded when either is."""
    model = chain.model(stage)
    (c0, _), (t0, t1) = cal, test
    a, b = chain.inputs(stage, t0), chain.inputs(stage, t1)
    z = _truth(stage, t0)
    if isinstance(model, FactorMap):
        names = PART_NAMES[len(model.parts)]
        parts = {
            n: _folds(m, pa, pb, z) for n, m, pa, pb in zip(names, model.parts, a, b, strict=True)
        }
        w0 = model.join(*(w for w, _ in parts.values()))
        folds = {k: v for k, (_, v) in parts.items()}
        fold = {
            "fold_score": max(f["fold_score"] for f in folds.values()),
            "folded": any(f["folded"] for f in folds.values()),
            "starved_units": sum(f["starved_units"] for f in folds.values()),
            "topographic_error": max(f["topographic_error"] for f in folds.values()),
            "parts": folds,
        }
    else:
        w0, fold = _folds(model, a, b, z)
    w1 = model.winner(*b, hard=True)
    wc = chain.winners(stage, c0)
    out = quantiser_scores(
        wc, _truth(stage, c0), w0, w1, z, model.map_coords, _position(_origin(stage))
    )
    out.update(fold, ordered=bool(min(out["order_r2_per_axis"]) >= ORDERED_R2))
    out["fold_threshold"] = FOLD_THRESHOLD
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
    return quantiser_scores(
        win(c0), zc, win(t0), win(t1), zt, som.coords, _position(_origin(stage))
    )


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
    centres = np.empty((k, z.shape[1]))
    centres[0] = z[rng.integers(z.shape[0])]
    d = np.sum((z - centres[0]) ** 2, axis=1)
    for j in range(1, k):  # k-means++ (d: each place's squared distance to its nearest centre)
        centres[j] = z[rng.choice(z.shape[0], p=d / d.sum())]
        d = np.minimum(d, np.sum((z - centres[j]) ** 2, axis=1))
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


def record_box(
    rng: np.random.Generator, train_pairs: int, eval_pairs: int
) -> tuple[
    ICubScene,
    dict[str, tuple[Views3D, Views3D]],
    dict[str, tuple[tuple[Views3D, Views3D], tuple[Views3D, Views3D]]],
]:
    """A sealed scene with the floating ball, each stage's ``train_pairs`` training pairs
    (from ``rng``) and its :func:`evaluation_pairs`; the caller closes the scene."""
    scene = ICubScene()
    st.float_ball(scene)
    scene.seal()  # the truth only where scene.truth() says: scoring and references
    train = {s: record_pairs(scene, train_pairs, rng, s) for s in ("eyes", "head")}
    return scene, train, evaluation_pairs(scene, eval_pairs)


def score_chain(
    chain: Chain3D,
    train: dict[str, tuple[Views3D, Views3D]],
    ev: dict[str, tuple[tuple[Views3D, Views3D], tuple[Views3D, Views3D]]],
    iterations: int,
    seed: int,
) -> dict[str, Any]:
    """Both maps of ``chain`` scored (:func:`score_map`) beside a same-size map keyed by the
    true position and k-means with as many centres as the map has units."""
    out: dict[str, Any] = {}
    for name, stage, data in (("map_head", "head", "eyes"), ("map_torso", "torso", "head")):
        cal, test = ev[data]
        shape = tuple(int(n) for n in chain.model(stage).map_shape)
        m = score_map(chain, stage, cal, test)
        m["true_position"] = true_position_map(
            stage, train[data], cal, test, shape, iterations, seed
        )
        m["kmeans"] = kmeans_reference(stage, train[data], cal, test, int(np.prod(shape)), seed)
        m["error_ratio_to_kmeans"] = m["error_cm"] / m["kmeans"]["error_cm"]
        out[name] = m
    return out


def run_maps(
    seed: int,
    *,
    train_pairs: int = 2000,
    eval_pairs: int = 400,
    iterations: int = ITERATIONS,
    **options: Any,
) -> dict[str, Any]:
    """One seed of the 3-D maps: record, learn (``options``: :func:`learn_chain3d`'s, its
    defaults the measured design), score against both references; the seconds taken and the
    process's peak resident memory."""
    t0 = time.perf_counter()
    scene, train, ev = record_box(np.random.default_rng(seed), train_pairs, eval_pairs)
    scene.close()
    t_record = time.perf_counter() - t0
    chain = learn_chain3d(
        train["eyes"],
        train["head"],
        iterations=iterations,
        seed=seed,
        eye_size=scene.eye_size,
        **options,
    )
    t_learn = time.perf_counter() - t0 - t_record
    out = score_chain(chain, train, ev, iterations, seed)
    out["seconds"] = {
        "record": t_record,
        "learn": t_learn,
        "total": time.perf_counter() - t0,
    }
    out["weights"] = chain.n_weights
    out["peak_rss_mb"] = _peak_rss_mb()
    return out


def _peak_rss_mb() -> float | None:
    """The process's peak resident memory, MB (None where the platform does not say)."""
    try:
        import resource
    except ImportError:  # not on Windows
        return None
    kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return kb / 1024.0 if sys.platform != "darwin" else kb / 2**20
