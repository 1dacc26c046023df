"""The iCub's chain of two maps, learned from its own eye and head movements, and its scores.

- **Map 1** (eyes first): a Sigma-Pi map on the right eye's retina code and the code of its
  eye angles (tilt and the right eye's pan), trained on view pairs from saccades of the eyes
  with the head still (:func:`~sigmapi.envs.icub.view_pairs`, ``stage="eyes"``): the pair
  shares the ball's head-centred direction.
- **Map 2** (then the head): a Sigma-Pi map on map 1's response (rectified, unit length:
  :func:`sigmapi.experiments.chain.run.head_code`) and the code of the neck's pitch and yaw,
  trained on view pairs in which the neck turns too (``stage="head"``): the pair shares the
  ball's torso-centred direction.

Population codes read measured angles, each scaled to [0, 1] over the range the random gazes
are drawn from (:data:`~sigmapi.envs.icub.GAZE_LOW`.. :data:`~sigmapi.envs.icub.GAZE_HIGH`;
:mod:`sigmapi.envs.icub.views`, where map 1's views are also a view source for the kit).
Both maps use the ``icub-2d`` preset (:data:`MAP`: ``paper-2d``'s min-distance winner and
cross-view ordered start, a neighbourhood that ends at 1 map unit, a learning rate that
anneals on to 0.004, no refinement rounds).

Each map is scored on unmoved pairs from the fixed evaluation seed against the true direction
it should code (head-centred for map 1, torso-centred for map 2): the metrics of
:func:`sigmapi.metrics.winner_metrics` (``order_r2``...), the fold score and
``direction_error_deg`` (RMS angle between a test view's true direction and the mean true
direction of the calibration views its winner won). Beside them: a same-size Kohonen map
trained on the true directions themselves (the quantisation floor) and a cubic least-squares
fit from the measured angles (the information bound); and for map 2, the same Sigma-Pi map
(same settings, same seed) fed an exact map 1 (:func:`exact_map1`: the true head-centred
direction as a code on map 1's grid), which tells what of map 2's error the rule itself makes
and what the chain adds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.baselines import KohonenSOM
from sigmapi.codes import PopulationCode
from sigmapi.config import SOMConfig
from sigmapi.envs.icub import (
    HEAD_BOX,
    PAIRS_PER_BALL,
    ICubScene,
    ViewBatch,
    direction_vectors,
    view_pairs,
)
from sigmapi.envs.icub.views import eye_position, neck_position, retina_position, view_codes
from sigmapi.experiments.chain.run import head_code
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.metrics import (
    EVAL_SEED,
    FOLD_THRESHOLD,
    fold_indicators,
    hard_scores,
    winner_metrics,
    z_decoder,
)
from sigmapi.model.som import SigmaPiSOM
from sigmapi.tasks import Batch

Array = NDArray[np.float64]

MAP = MapSpec("icub-2d")
"""The maps' settings: the ``icub-2d`` preset (its schedule, chosen on the tuning seeds, is
explained in the preset file); the run sets the sizes, the codes, the length and the seed."""

HEAD_WIDTH = 0.85
"""Width (map-1 units) of the hill of the code of map 1's place that map 2 reads
(:meth:`ChainMaps.head`); the retina's, the eyes' and the neck's codes keep the config's
``code_width`` (1). Narrower hills lowered map 2's error and wider ones its order (chosen on
the tuning seeds: ``docs/guide/icub.md``, where the settings come from). In the 3-D task,
map T of design ``"grid"`` reads map H's place with hills as wide
(:mod:`~sigmapi.experiments.icub.space3d`)."""

READOUT_RADIUS = 2.0
"""Units (map units on each axis, around the winner) whose response :meth:`ChainMaps.place`
weighs (chosen on the tuning seeds: ``docs/guide/icub.md``)."""


def som_config(
    x_shape: tuple[int, ...],
    y_shape: tuple[int, ...],
    map_shape: tuple[int, ...],
    width: float,
    iterations: int,
    seed: int,
    backend: str,
) -> SOMConfig:
    """The maps' preset (:data:`MAP`) on these grids."""
    return MAP.config(
        map_shape=tuple(map_shape),
        x_shape=tuple(x_shape),
        y_shape=tuple(y_shape),
        code_width=width,
        iterations=iterations,
        seed=seed,
        backend=backend,
    )


@dataclass(frozen=True)
class MapData:
    """Pairs of views for one map: ``(first, second)`` view batches."""

    eyes: tuple[ViewBatch, ViewBatch]
    """Saccades of the eyes, the head still (map 1)."""
    head: tuple[ViewBatch, ViewBatch]
    """Turns of the neck and eyes (map 2)."""

    @classmethod
    def record(
        cls,
        scene: ICubScene,
        n: int,
        rng: np.random.Generator,
        moved_share: float = 0.0,
        balls: str = "table",
        per_ball: int = PAIRS_PER_BALL,
    ) -> MapData:
        """``n`` pairs of each kind from ``rng``, ``moved_share`` of them with a moved ball, the
        balls put as ``balls`` says (:data:`~sigmapi.envs.icub.frames.BALLS`), ``per_ball``
        pairs each."""
        return cls(
            *(
                view_pairs(
                    scene,
                    n,
                    rng,
                    stage=stage,
                    moved_share=moved_share,
                    balls=balls,
                    per_ball=per_ball,
                )
                for stage in ("eyes", "head")
            )
        )

    @classmethod
    def evaluation(
        cls, scene: ICubScene, n: int, balls: str = "table", per_ball: int = PAIRS_PER_BALL
    ) -> tuple[MapData, MapData]:
        """Calibration and test pairs (unmoved) from the fixed evaluation seed, the balls put
        as ``balls`` says, ``per_ball`` pairs each."""
        cal, test = (np.random.default_rng(s) for s in np.random.SeedSequence(EVAL_SEED).spawn(2))
        return (
            cls.record(scene, n, cal, balls=balls, per_ball=per_ball),
            cls.record(scene, n, test, balls=balls, per_ball=per_ball),
        )


class ChainMaps:
    """Map 1 and map 2 of one seed, and the codes that feed them."""

    def __init__(
        self,
        map1: SigmaPiSOM,
        map2: SigmaPiSOM,
        eye_size: int,
        code: str = "winner",
        head_width: float | None = None,
    ) -> None:
        self.map1, self.map2, self.eye_size, self.code = map1, map2, eye_size, code
        self.head_width = head_width
        """Width of the hill of :meth:`head`'s place code (None: map 1's ``code_width``)."""

    def head(self, v: ViewBatch) -> Array:
        """What map 1 hands to map 2 for views ``v``: its response (rectified, unit length),
        or a population code on its grid, hills :attr:`head_width` wide, of its winner's
        place (``code="winner"``) or of the centre of mass of its rectified response over the
        winner and its neighbours (``code="centroid"``)."""
        if self.code == "response":
            return head_code(self.map1, retina_position(v, self.eye_size), eye_position(v))
        m = self.map1
        x, y = self.inputs1(v)
        if self.code == "centroid":
            place = response_centroid(m, x, y, 1.0)
        else:
            place = m.map_coords[m.winner(x, y, hard=True)]
        return self.place_code(place / (np.asarray(m.map_shape) - 1.0))

    def place_code(self, pos: Array) -> Array:
        """A population code on map 1's grid, hills :attr:`head_width` wide, of positions
        ``pos`` ``(B, 2)`` in [0, 1] per axis."""
        m = self.map1
        width = m.config.code_width if self.head_width is None else self.head_width
        return PopulationCode(m.map_shape, width).encode(pos)

    def inputs1(self, v: ViewBatch) -> tuple[Array, Array]:
        """Map 1's codes of views ``v``: retina, eye angles."""
        return view_codes(self.map1.x_code, self.map1.y_code, v, self.eye_size)

    def inputs2(self, v: ViewBatch) -> tuple[Array, Array]:
        """Map 2's codes of views ``v``: map 1's response, neck angles."""
        return self.head(v), self.map2.y_code.encode(neck_position(v))

    def place(self, v: ViewBatch, radius: float = READOUT_RADIUS) -> Array:
        """Map 2's reading of views ``v`` below the grid's spacing, ``(B, 2)`` map coordinates:
        the centre of mass of its rectified response over the units within ``radius`` of its
        winner (:func:`response_centroid`)."""
        return response_centroid(self.map2, *self.inputs2(v), radius)

    def winner(self, v: ViewBatch, stage: int = 2) -> NDArray[np.int64]:
        """Hard winners of map ``stage`` (1 or 2) for views ``v``."""
        if stage == 1:
            return self.map1.winner(*self.inputs1(v), hard=True)
        return self.map2.winner(*self.inputs2(v), hard=True)


class _ExactMap1(ChainMaps):
    """A chain whose map 1 is exact: map 2 reads :meth:`ChainMaps.place_code` of the true
    head-centred direction, scaled over
    :data:`~sigmapi.envs.icub.HEAD_BOX`. A reference for the analysis only: it reads the
    truth, which the robot never does."""

    def head(self, v: ViewBatch) -> Array:
        pos = (v.head - HEAD_BOX[:, 0]) / (HEAD_BOX[:, 1] - HEAD_BOX[:, 0])
        return self.place_code(np.clip(pos, 0.0, 1.0))


def exact_map1(chain: ChainMaps, train: MapData, cal: MapData, test: MapData) -> dict[str, Any]:
    """Map 2 again, with its settings and seed, trained on ``train``'s head turns with map 1
    exact (:class:`_ExactMap1`), scored as :func:`score` scores map 2: the error and order the
    rule reaches when all of map 1's error is taken away."""
    ref = _ExactMap1(chain.map1, chain.map1, chain.eye_size, chain.code, chain.head_width)
    ref.map2 = SigmaPiSOM(chain.map2.config)
    a, b = train.head
    ref.map2.fit((*ref.inputs2(a), *ref.inputs2(b)))
    return score(ref, 2, cal, test)


def response_centroid(model: SigmaPiSOM, x: Array, y: Array, radius: float) -> Array:
    """The centre of mass ``(B, 2)``, in map coordinates, of ``model``'s rectified response to
    codes ``x``, ``y`` over the units within ``radius`` map units (on each axis) of its hard
    winner; the winner's place where that response is all zero."""
    place = model.map_coords[model.winner(x, y, hard=True)]
    h = np.maximum(model.respond(x, y), 0.0)
    near = np.max(np.abs(model.map_coords[None, :, :] - place[:, None, :]), axis=2) <= radius
    h = np.where(near, h, 0.0)
    total = h.sum(axis=1, keepdims=True)
    return np.where(total > 0, (h @ model.map_coords) / np.where(total > 0, total, 1.0), place)


def learn_chain(
    data: MapData,
    *,
    grid: int,
    width: float,
    map_shape: tuple[int, ...],
    iterations: int,
    seed: int,
    eye_size: int,
    backend: str = "auto",
    code: str = "winner",
    head_width: float | None = None,
) -> ChainMaps:
    """Map 1 on ``data.eyes``, then map 2 on map 1's code of ``data.head`` (hills
    ``head_width`` wide, None: ``width``), both built with ``seed`` (their streams the
    seed's own, :mod:`sigmapi.experiments.kit.seeds`)."""
    g = (grid, grid)
    map1 = SigmaPiSOM(som_config(g, g, map_shape, width, iterations, seed, backend))
    chain = ChainMaps(map1, map1, eye_size, code, head_width)
    a, b = data.eyes
    map1.fit((*chain.inputs1(a), *chain.inputs1(b)))
    cfg2 = som_config(map1.map_shape, g, map_shape, width, iterations, seed, backend)
    chain.map2 = SigmaPiSOM(cfg2)
    a, b = data.head
    chain.map2.fit((*chain.inputs2(a), *chain.inputs2(b)))
    return chain


def unit_rows(a: Array) -> Array:
    """Rows of ``a`` scaled to length 1 (a zero row stays zero): the codes the 2-D and 3-D
    tasks' states and map T's population input are made of."""
    n = np.linalg.norm(a, axis=1, keepdims=True)
    return a / np.where(n > 0, n, 1.0)


def angle_error_deg(decoded: Array, true: Array) -> float:
    """RMS angle (degrees) between directions ``(azimuth, elevation)`` ``(N, 2)``."""
    cos = np.clip(np.sum(direction_vectors(decoded) * direction_vectors(true), axis=1), -1.0, 1.0)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(cos) ** 2))))


Extra = Callable[[Array, Array, Array, Array, Array], dict[str, object]]
"""A map's own scores from its calibration views' places and true positions, its test views'
places and true positions, and the test views' decoded positions."""


def quantiser_scores(
    wc: NDArray[np.int64],
    zc: Array,
    w0: NDArray[np.int64],
    w1: NDArray[np.int64],
    zt: Array,
    coords: Array,
    extra: Extra,
) -> dict[str, Any]:
    """Order, view consistency and usage (:func:`~sigmapi.metrics.winner_metrics`, without
    its z error) of a quantiser whose calibration winners are ``wc`` (true positions ``zc``)
    and test winners ``w0``, ``w1`` (true positions ``zt``), units at ``coords``, with the
    scores ``extra`` computes."""
    m: dict[str, Any] = dict(winner_metrics(wc, zc, w0, w1, zt, coords, 1.0))
    m.pop("z_error")
    m.update(extra(coords[wc], zc, coords[w0], zt, z_decoder(wc, zc, coords)[w0]))
    return m


def _direction(cc: Array, zc: Array, ct: Array, zt: Array, decoded: Array) -> dict[str, object]:
    return {"direction_error_deg": angle_error_deg(decoded, zt)}


def score(chain: ChainMaps, stage: int, cal: MapData, test: MapData) -> dict[str, Any]:
    """Map ``stage``'s metrics against the true directions (head-centred for map 1,
    torso-centred for map 2) on the evaluation pairs, with its fold score."""
    model = chain.map1 if stage == 1 else chain.map2
    pick = (lambda d: d.eyes) if stage == 1 else (lambda d: d.head)
    truth = (lambda v: v.head) if stage == 1 else (lambda v: v.torso)
    (c0, _), (t0, t1) = pick(cal), pick(test)
    inputs = chain.inputs1 if stage == 1 else chain.inputs2
    x0, y0 = inputs(t0)
    x1, y1 = inputs(t1)
    scores = hard_scores(model, x0, y0)
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(x1, y1, hard=True)
    wc = model.winner(*inputs(c0), hard=True)
    out = quantiser_scores(wc, truth(c0), w0, w1, truth(t0), model.map_coords, _direction)
    batch = Batch(x0, y0, x1, y1, truth(t0), t0.retina, t0.gaze, t1.retina, t1.gaze)
    starved, te, fold = fold_indicators(model, batch, w0, w1, scores)
    out.update(
        fold_score=fold,
        fold_threshold=FOLD_THRESHOLD,
        folded=bool(fold >= FOLD_THRESHOLD),
        starved_units=starved,
        topographic_error=te,
    )
    return out


def true_direction_map(
    train: MapData,
    cal: MapData,
    test: MapData,
    stage: int,
    map_shape: tuple[int, ...],
    iterations: int,
    seed: int,
) -> dict[str, Any]:
    """A same-size Kohonen map trained on the true directions (radians) of the training views:
    the quantisation floor of a map of this many units."""
    pick = (lambda d: d.eyes) if stage == 1 else (lambda d: d.head)
    truth = (lambda v: v.head) if stage == 1 else (lambda v: v.torso)
    a, b = pick(train)
    empty = np.zeros((a.head.shape[0], 0))
    som = KohonenSOM(map_shape, iterations=iterations, seed=seed)
    som.fit((truth(a), empty, truth(b), empty))
    (c0, _), (t0, t1) = pick(cal), pick(test)

    def win(v: ViewBatch) -> NDArray[np.int64]:
        return som.winner(truth(v), np.zeros((truth(v).shape[0], 0)))

    return quantiser_scores(win(c0), truth(c0), win(t0), win(t1), truth(t0), som.coords, _direction)


def _cubic(x: Array) -> Array:
    """Monomials of the columns of ``x`` up to degree 3 (a constant included)."""
    cols = [np.ones(x.shape[0])]
    n = x.shape[1]
    for i in range(n):
        cols.append(x[:, i])
        for j in range(i, n):
            cols.append(x[:, i] * x[:, j])
            cols.extend(x[:, i] * x[:, j] * x[:, k] for k in range(j, n))
    return np.column_stack(cols)


def supervised_fit(train: MapData, test: MapData, stage: int, eye_size: int) -> dict[str, Any]:
    """A cubic least-squares fit from the measured positions (retina, eye angles and, for map
    2, neck angles) to the true direction: the information those measurements hold."""
    pick = (lambda d: d.eyes) if stage == 1 else (lambda d: d.head)
    truth = (lambda v: v.head) if stage == 1 else (lambda v: v.torso)

    def feats(v: ViewBatch) -> Array:
        parts = [retina_position(v, eye_size), eye_position(v)]
        if stage == 2:
            parts.append(neck_position(v))
        return _cubic(np.hstack(parts))

    a, _ = pick(train)
    t0, _ = pick(test)
    beta, *_ = np.linalg.lstsq(feats(a), truth(a), rcond=None)
    return {"direction_error_deg": angle_error_deg(feats(t0) @ beta, truth(t0))}
