"""The map the robot learns from its own view pairs (:func:`learn_map`), and its scores against
the true ``z`` (:func:`score_map`, with the definitions and keys of :func:`sigmapi.evaluate`).
Its configuration (:func:`robot_som_config`) is the ``robot-2d`` preset: ``paper-2d``'s
min-distance winner, learning rate 0.1 -> 0.01 and cross-view ordered start, with a
neighbourhood that ends at 0.5 map units instead of 1e-5 (the preset file gives the evidence).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi.codes import PopulationCode
from sigmapi.config import SOMConfig
from sigmapi.envs import collect_saccade_views
from sigmapi.envs.robot.views import RobotViewBatch, RobotViews
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.worlds import World
from sigmapi.experiments.robot.config import ROBOT_WORLD, RobotConfig
from sigmapi.metrics import (
    EVAL_SEED,
    FOLD_THRESHOLD,
    fold_indicators,
    grid_spacing,
    hard_scores,
    winner_metrics,
)
from sigmapi.model.som import SigmaPiSOM
from sigmapi.tasks import Batch


def robot_som_config(
    code: PopulationCode,
    map_shape: tuple[int, ...],
    iterations: int,
    seed: int,
    backend: str = "auto",
    spec: MapSpec = ROBOT_WORLD.map,
) -> SOMConfig:
    """``spec`` (default: the robot world's, ``robot-2d``) on the robot's codes (``code``,
    retina and gaze alike), a ``map_shape`` map, ``iterations`` long."""
    return spec.config(
        map_shape=tuple(map_shape),
        x_shape=code.shape,
        y_shape=code.shape,
        code_width=code.width,
        iterations=iterations,
        seed=seed,
        backend=backend,
    )


def learn_map(
    config: RobotConfig, seed: int, views: np.random.Generator, world: World = ROBOT_WORLD
) -> SigmaPiSOM:
    """The map of seed ``seed``: ``config.map.train_pairs`` view pairs recorded from the still
    body's saccades in ``world`` (its view source; ``config.env.moved_share`` of them
    spoiled), drawn from ``views``, then ``fit(views)`` with the world's map spec, the map
    built with the seed itself (its weights' streams the seed's,
    :mod:`sigmapi.experiments.kit.seeds`)."""
    source = world.source(config.env)
    pairs = collect_saccade_views(source, config.map.train_pairs, seed=views)
    m = config.map
    cfg = robot_som_config(
        source.x_code, m.map_shape, m.iterations, seed, m.backend, spec=world.map
    )
    return SigmaPiSOM(cfg).fit(pairs)


def evaluation_pairs(config: RobotConfig) -> tuple[RobotViewBatch, RobotViewBatch]:
    """Calibration and test pairs (unmoved) drawn from :data:`~sigmapi.metrics.EVAL_SEED`:
    the same for every seed and run."""
    source = RobotViews(config.env.grid, config.env.code_width)
    cal, test = (np.random.default_rng(s) for s in np.random.SeedSequence(EVAL_SEED).spawn(2))
    return (
        source.sample_views_with_z(config.map.eval_pairs, cal),
        source.sample_views_with_z(config.map.eval_pairs, test),
    )


def unit_positions(model: SigmaPiSOM, calibration: RobotViewBatch) -> NDArray[np.float64]:
    """Each unit's preferred ``z``: the mean ``z`` of the calibration views it wins (NaN for a
    unit that wins none), ``(n_units, 2)``."""
    wc = model.winner(calibration.x0, calibration.y0, hard=True)
    out = np.full((model.n_units, 2), np.nan)
    for k in np.unique(wc):
        out[k] = calibration.z[wc == k].mean(axis=0)
    return out


def _batch(b: RobotViewBatch) -> Batch:
    return Batch(b.x0, b.y0, b.x1, b.y1, b.z, b.px0, b.py0, b.px1, b.py1)


def score_map(
    model: SigmaPiSOM, calibration: RobotViewBatch, test: RobotViewBatch
) -> dict[str, float | int | bool]:
    """The map's metrics against the true ``z`` of the pairs (keys of ``sigmapi evaluate``).

    ``calibration`` fits the z decoder and the affine order fit; ``test`` is scored (both
    should hold unmoved pairs). z is the workspace position of the ball's direction, so the
    z error is in grid spacings of the codes per unit of the workspace.
    """
    scores = hard_scores(model, test.x0, test.y0)
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(test.x1, test.y1, hard=True)
    wc = model.winner(calibration.x0, calibration.y0, hard=True)
    spacing = grid_spacing(model.x_shape)
    m = winner_metrics(wc, calibration.z, w0, w1, test.z, model.map_coords, spacing)
    starved, te, score = fold_indicators(model, _batch(test), w0, w1, scores)
    return {
        **m,
        "n_test": int(test.z.shape[0]),
        "fold_score": score,
        "fold_threshold": FOLD_THRESHOLD,
        "folded": bool(score >= FOLD_THRESHOLD),
        "starved_units": starved,
        "topographic_error": te,
    }
