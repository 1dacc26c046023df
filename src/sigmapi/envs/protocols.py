"""What a world must offer to train a map and a learner: two small protocols and one space.

A **view source** is a body that can look at an object without moving it: every pair it
returns shows one body-centred position ``z`` from two gaze directions, coded as the
population codes of the retinal position ``x`` and of the gaze ``y`` (docs/algorithm.md).
That is all the Sigma-Pi map needs to learn ``z = f(x, y)``:
:func:`~sigmapi.envs.collect_saccade_views` and :func:`~sigmapi.envs.learn_map_in_env` take
any :class:`ViewSource`. A source that can also show a *given* ``z``
(:class:`PlacedViewSource`) lets analyses sample the state a learner would see at each ``z``
(the critic's value over ``z``).

An **environment** the wrappers and the learner can use is any Gymnasium environment
whose observation space is like :func:`view_space` (checked by :func:`check_view_space`): a
``Dict`` with a ``"retina"`` and a ``"gaze"`` entry, 1-D float ``Box`` codes. Its ``info``
holds ``"is_success"`` and ``"z"``, the true body-centred position in ``[0, 1]^d`` (for
analysis and the oracle state only, never in the observation); its time limit is set by
Gymnasium's ``TimeLimit``. The gaze-and-reach world (:class:`~sigmapi.envs.GazeReachEnv`) is
one; a robot is the next.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError

__all__ = [
    "OBS_KEYS",
    "Obs",
    "PlacedViewSource",
    "ViewSource",
    "Views",
    "check_view_space",
    "view_space",
]

Obs = dict[str, Any]
"""An observation: ``{"retina": float32 code of x, "gaze": float32 code of y}``."""

Views = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""Pairs of views ``(x0, y0, x1, y1)``: codes of shape ``(n, x_code.size)`` and
``(n, y_code.size)``; row ``i`` of view 0 and of view 1 show one ``z``."""

OBS_KEYS = ("retina", "gaze")
"""The entries of an environment's observation: the codes of ``x`` and of ``y``."""


@runtime_checkable
class ViewSource(Protocol):
    """A body that shows an unmoved object from two gaze directions (saccades while still).

    Attributes
    ----------
    x_code : PopulationCode
        The code of the retinal position ``x`` (the views' ``x0``, ``x1`` and an
        environment's ``"retina"`` observation); a map that reads the views must be trained
        with this code (``SOMConfig.x_shape``, ``code_width``, ...).
    y_code : PopulationCode
        The code of the gaze ``y`` (``y0``, ``y1``, the ``"gaze"`` observation).
    """

    @property
    def x_code(self) -> PopulationCode: ...

    @property
    def y_code(self) -> PopulationCode: ...

    def sample_views(self, n: int, rng: np.random.Generator) -> Views:
        """``n`` pairs of views, each pair of one ``z`` (drawn by the source, never returned).

        Everything random comes from ``rng``; the codes are float64 arrays
        (:data:`Views`).
        """
        ...


@runtime_checkable
class PlacedViewSource(ViewSource, Protocol):
    """A view source that can show a given body-centred position (for analysis).

    Attributes
    ----------
    z_dim : int
        Dimensions of ``z`` (the length of ``info["z"]``).
    """

    @property
    def z_dim(self) -> int: ...

    def views_of(
        self, z: NDArray[np.float64], rng: np.random.Generator
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One view of each position ``z`` ``(B, z_dim)``: the codes ``x`` and ``y``."""
        ...


def view_space(n_x: int, n_y: int) -> spaces.Dict:
    """The observation space of an environment the wrappers read: float32 codes in [0, 1]."""
    return spaces.Dict(
        {
            "retina": spaces.Box(0.0, 1.0, (n_x,), dtype=np.float32),
            "gaze": spaces.Box(0.0, 1.0, (n_y,), dtype=np.float32),
        }
    )


def check_view_space(space: spaces.Space, keys: tuple[str, ...] = OBS_KEYS) -> dict[str, int]:
    """The number of values of each entry in ``keys`` of ``space``, after checking its form.

    ``space`` must be a ``Dict`` whose ``keys`` entries are 1-D ``Box`` spaces (the codes,
    flattened in C order); anything else raises a ConfigError that says what was found.
    """
    if not isinstance(space, spaces.Dict):
        raise ConfigError(
            f"the environment's observation space must be a Dict with entries {keys}, got "
            f"{space!r}; the wrappers read population codes of the retina and the gaze"
        )
    sizes = {}
    for key in keys:
        entry = space.spaces.get(key)
        if not isinstance(entry, spaces.Box) or len(entry.shape) != 1:
            raise ConfigError(
                f"the observation space's entry {key!r} must be a 1-D Box (a code flattened in "
                f"C order), got {entry!r}; entries: {sorted(space.spaces)}"
            )
        sizes[key] = int(entry.shape[0])
    return sizes
