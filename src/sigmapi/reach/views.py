"""Training data for the map from the robot's own behaviour: saccades while the body is still.

While the body keeps still, ``z`` does not change, and every saccade shows the same object at
a new retinal position under a new gaze: two views ``(x0, y0)`` and ``(x1, y1)`` of one ``z``,
exactly what the Sigma-Pi SOM learns from (docs/algorithm.md), gathered without a teacher and
without reading ``z``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.reach.env import GazeReachEnv

__all__ = ["collect_saccade_views"]

STAY = 0
"""The action that keeps the body still (row 0 of :func:`~sigmapi.reach.env.move_table`)."""


def collect_saccade_views(
    env: GazeReachEnv, n_pairs: int, seed: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Gather ``n_pairs`` pairs of views of the same ``z`` by keeping still and looking around.

    Per pair the environment makes a random restart (the body lands at a random place, the
    object anywhere outside the goal region, as in every episode), then the agent takes the
    "stay" action until the eye makes a saccade; the observations before and after that
    saccade are the two views. Only observations are used, never ``info["z"]``.

    Parameters
    ----------
    env : GazeReachEnv
        The environment (unwrapped: its observations are the retina and gaze codes).
    n_pairs : int
        Number of view pairs.
    seed : int, optional
        Seed of the environment's first reset (later restarts continue its stream).

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
    n = env.code.size
    out = [np.empty((n_pairs, n)) for _ in range(4)]
    obs, _ = env.reset(seed=seed)
    for i in range(n_pairs):
        if i > 0:
            obs, _ = env.reset()
        while True:
            nxt, _, terminated, truncated, info = env.step(STAY)
            if info["saccade"]:
                break
            if terminated or truncated:  # a long still spell hit the time limit: restart
                nxt, _ = env.reset()
            obs = nxt
        out[0][i], out[1][i] = obs["retina"], obs["gaze"]
        out[2][i], out[3][i] = nxt["retina"], nxt["gaze"]
    return out[0], out[1], out[2], out[3]
