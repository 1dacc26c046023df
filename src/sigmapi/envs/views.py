"""Training data for the map from the body's own behaviour: saccades while the body is still.

While the body keeps still, ``z`` does not change, and every saccade shows the same object at
a new retinal position under a new gaze: two views ``(x0, y0)`` and ``(x1, y1)`` of one ``z``,
exactly what the Sigma-Pi SOM learns from (docs/algorithm.md), gathered without a teacher and
without reading ``z``. Any :class:`~sigmapi.envs.ViewSource` provides them; these functions
check what it returns and learn a map from it.
"""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
import numpy as np

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.envs.protocols import PlacedViewSource, Views, ViewSource
from sigmapi.errors import ConfigError
from sigmapi.model.som import SigmaPiSOM

__all__ = ["Seed", "collect_saccade_views", "collect_stream", "learn_map_in_env", "view_source"]

Seed = int | np.random.SeedSequence | np.random.Generator | None
"""What draws a source's views: a seed, a ``SeedSequence`` or the generator itself (None:
fresh entropy), as :func:`numpy.random.default_rng` takes it."""


def view_source(source: object) -> ViewSource:
    """``source`` as a :class:`~sigmapi.envs.ViewSource`: a Gymnasium environment is
    unwrapped first (wrappers hide the world's attributes); anything else must implement the
    protocol itself."""
    base = source.unwrapped if isinstance(source, gym.Env) else source
    if not isinstance(base, ViewSource):
        raise ConfigError(
            f"source must be a view source (x_code, y_code and sample_views(n, rng), see "
            f"sigmapi.envs.ViewSource), got {type(base).__name__}"
        )
    return base


def collect_saccade_views(source: object, n_pairs: int, seed: Seed = None) -> Views:
    """Gather ``n_pairs`` pairs of views of the same ``z`` by keeping still and looking around.

    Parameters
    ----------
    source : ViewSource or gymnasium.Env
        What shows the views (:meth:`~sigmapi.envs.ViewSource.sample_views`), e.g. a
        :class:`~sigmapi.envs.GazeReachEnv`, wrapped or not.
    n_pairs : int
        Number of view pairs.
    seed : int, SeedSequence or Generator, optional
        Seed of the source's random choices (object positions, fixations), or the generator
        they are drawn from.

    Returns
    -------
    x0, y0, x1, y1 : ndarray, float64
        Codes of the two views, ``(n_pairs, x_code.size)`` and ``(n_pairs, y_code.size)``,
        ready for ``SigmaPiSOM.fit(views)``. Only the codes are returned, never ``z``.
    """
    n_pairs = _validate.integer("n_pairs", n_pairs, 1, fix="e.g. n_pairs=20000")
    src = view_source(source)
    views = src.sample_views(n_pairs, np.random.default_rng(seed))
    sizes = (src.x_code.size, src.y_code.size) * 2
    if len(views) != 4:
        raise ConfigError(
            f"{type(src).__name__}.sample_views must return (x0, y0, x1, y1), got "
            f"{len(views)} arrays"
        )
    out = []
    for name, v, size in zip(("x0", "y0", "x1", "y1"), views, sizes, strict=True):
        arr = np.asarray(v, dtype=np.float64)
        if arr.shape != (n_pairs, size):
            raise ConfigError(
                f"{type(src).__name__}.sample_views gave {name} of shape {arr.shape}, expected "
                f"({n_pairs}, {size}) (n pairs x the size of its code)"
            )
        out.append(arr)
    return out[0], out[1], out[2], out[3]


def collect_stream(
    source: object, n_frames: int, dwell: int, seed: Seed = None
) -> tuple[np.ndarray, np.ndarray]:
    """A stream of ``n_frames`` views as the body sees them: the object stays at one place for
    ``dwell`` saccades, then moves to a fresh place, and nothing marks when.

    Parameters
    ----------
    source : PlacedViewSource or gymnasium.Env
        What shows a given place (:meth:`~sigmapi.envs.PlacedViewSource.views_of`): the
        gaze-and-reach world (:class:`~sigmapi.envs.GazeReachEnv`) or the robot's camera
        (:class:`~sigmapi.envs.robot.RobotViews`), wrapped or not.
    n_frames : int
        Frames (saccades) of the stream.
    dwell : int
        Saccades per place of the object.
    seed : int, SeedSequence or Generator, optional
        Seed (or generator) of the places (uniform in ``[0, 1]`` per dimension of ``z``, as
        both sources place the object) and of the source's saccades.

    Returns
    -------
    x, y : ndarray, float64
        Codes ``(n_frames, x_code.size)`` and ``(n_frames, y_code.size)`` in time order, ready
        for ``SigmaPiSOM.fit_stream((x, y))``; ``z`` is not returned.
    """
    n_frames = _validate.integer("n_frames", n_frames, 1, fix="e.g. n_frames=20001")
    dwell = _validate.integer("dwell", dwell, 1, fix="saccades per place of the object")
    src = view_source(source)
    if not isinstance(src, PlacedViewSource):
        raise ConfigError(
            f"source must show a given place to make a stream (views_of(z, rng) and z_dim, "
            f"sigmapi.envs.PlacedViewSource), got {type(src).__name__}"
        )
    rng = np.random.default_rng(seed)
    places = rng.random((-(-n_frames // dwell), src.z_dim))
    x, y = src.views_of(np.repeat(places, dwell, axis=0)[:n_frames], rng)
    return np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)


def learn_map_in_env(
    source: object,
    config: SOMConfig,
    seed: Seed = None,
    callback: Callable[[SigmaPiSOM], None] | None = None,
) -> SigmaPiSOM:
    """Train a :class:`~sigmapi.SigmaPiSOM` on saccade views of ``source``.

    ``config.iterations`` view pairs are collected with :func:`collect_saccade_views` (no
    teacher, no access to z) and learned with ``partial_fit(views=...)``: the winner from one
    view, the update from the other. ``config`` must code x and y as the source does
    (``x_shape``, ``y_shape``, ``code_width``, ...: the map's ``x_code`` and ``y_code`` equal
    the source's). ``seed``: of the views (:func:`collect_saccade_views`); the map's own
    streams are ``config.seed``'s.
    """
    src = view_source(source)
    som = SigmaPiSOM(config)
    for axis, mine, theirs in (("x", som.x_code, src.x_code), ("y", som.y_code, src.y_code)):
        if mine != theirs:
            raise ConfigError(
                f"the map codes {axis} as {mine} but the source as {theirs}; give the map's "
                f"config the source's code ({axis}_shape, code_width, ...)"
            )
    views = collect_saccade_views(src, config.iterations, seed=seed)
    return som.partial_fit(views=views, callback=callback)
