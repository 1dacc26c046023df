"""Training data for the map from the robot's own behaviour: saccades while the body is still.

While the body keeps still, ``z`` does not change, and every saccade shows the same object at
a new retinal position under a new gaze: two views ``(x0, y0)`` and ``(x1, y1)`` of one ``z``,
exactly what the Sigma-Pi SOM learns from (docs/algorithm.md), gathered without a teacher and
without reading ``z``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.envs.gaze_reach import GazeReachEnv
from sigmapi.errors import ConfigError
from sigmapi.som import SigmaPiSOM

__all__ = ["collect_saccade_views", "learn_map_in_env"]


def collect_saccade_views(
    env: GazeReachEnv, n_pairs: int, seed: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Gather ``n_pairs`` pairs of views of the same ``z`` by keeping still and looking around.

    Per pair the object lies anywhere in the workspace (uniform ``z``, the goal region
    included: the map must know the goal's z too) and, while the body keeps still, the eye
    makes two saccades (each to a uniform fixation that keeps the object on the retina, the
    environment's :meth:`~sigmapi.envs.GazeReachEnv.saccade_targets`); the two fixations are
    the two views, coded as the environment codes its observations
    (:meth:`~sigmapi.envs.GazeReachEnv.codes`). Computed for all pairs at once rather than by
    stepping: the environment ends an episode as soon as ``z`` is in the goal box, so stepping
    could never show a goal ``z`` twice. Only the codes are used for learning, never ``z``.

    Parameters
    ----------
    env : GazeReachEnv
        The environment (unwrapped: its observations are the retina and gaze codes).
    n_pairs : int
        Number of view pairs.
    seed : int, optional
        Seed of the object positions and fixations.

    Returns
    -------
    x0, y0, x1, y1 : ndarray, shape (n_pairs, grid**dim)
        Codes of the two views, ready for ``SigmaPiSOM.partial_fit(views=...)``.
    """
    n_pairs = _validate.integer("n_pairs", n_pairs, 1, fix="e.g. n_pairs=20000")
    if not isinstance(env, GazeReachEnv):
        raise ConfigError(
            f"env must be a GazeReachEnv (use env.unwrapped), got {type(env).__name__}"
        )
    if env.saccade_rate == 0.0:
        raise ConfigError(
            "saccade_rate must be > 0 to collect views: a still eye never shows a second view"
        )
    rng = np.random.default_rng(seed)
    z = rng.random((n_pairs, env.dim))
    x0, y0 = env.codes(z, env.saccade_targets(z, rng))
    x1, y1 = env.codes(z, env.saccade_targets(z, rng))
    f64 = [np.asarray(v, dtype=np.float64) for v in (x0, y0, x1, y1)]
    return f64[0], f64[1], f64[2], f64[3]


def learn_map_in_env(
    env: GazeReachEnv,
    config: SOMConfig,
    seed: int | None = None,
    callback: Callable[[SigmaPiSOM], None] | None = None,
) -> SigmaPiSOM:
    """Train a :class:`~sigmapi.SigmaPiSOM` on saccade views gathered in ``env``.

    ``config.iterations`` view pairs are collected with
    :func:`collect_saccade_views` (no teacher, no access to z) and learned
    with ``partial_fit(views=...)``: the winner from one view, the update from the other.
    """
    views = collect_saccade_views(env, config.iterations, seed=seed)
    return SigmaPiSOM(config).partial_fit(views=views, callback=callback)
