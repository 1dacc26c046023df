"""The map's geometry as one value: its grid, whether its axes wrap, the soft winner's window.

The winner rules and the neighbourhood read the map through these three numbers, and every
kernel computes on them; :class:`MapGeometry` carries them together (built once by the model
from its config, :attr:`sigmapi.SOMConfig.geometry`) instead of ``map_shape``,
``map_periodic`` and ``soft_cut`` as loose arguments.

Examples
--------
>>> g = MapGeometry((3, 4), periodic=True)
>>> g.units, g.strides
(12, (4, 1))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sigmapi import _validate

__all__ = ["DEFAULT_SOFT_CUT", "MapGeometry"]

DEFAULT_SOFT_CUT = 15
"""The soft winner's window half-width of the authors' script (``SOMConfig.soft_cut``)."""


@dataclass(frozen=True)
class MapGeometry:
    """The map the kernels compute on (immutable, hashable).

    Attributes
    ----------
    shape : tuple of int
        The grid of map units, e.g. ``(15,)`` or ``(15, 15)``; ``K`` units flattened in C
        order (``SOMConfig.map_shape``).
    periodic : bool
        Every map axis wraps around (a ring in 1-D, a torus in 2-D): grid distances in the
        neighbourhood and the soft winner's smoothing go the shorter way round
        (``SOMConfig.map_periodic``).
    soft_cut : int
        Half-width of the soft winner's smoothing window, in map units along every axis
        (``SOMConfig.soft_cut``; the authors' script: 15).

    Bad values are a :class:`~sigmapi.errors.ConfigError` naming the field.
    """

    shape: tuple[int, ...]
    periodic: bool = False
    soft_cut: int = DEFAULT_SOFT_CUT

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "shape", _validate.shape("map_shape", self.shape))
        _validate.boolean("map_periodic", self.periodic)
        cut = _validate.integer(
            "soft_cut", self.soft_cut, 0, fix="in map units; the script uses 15"
        )
        set_(self, "soft_cut", cut)

    @property
    def units(self) -> int:
        """``K``, the number of map units."""
        return math.prod(self.shape)

    @property
    def ndim(self) -> int:
        """The number of map axes."""
        return len(self.shape)

    @property
    def strides(self) -> tuple[int, ...]:
        """Flat-index steps of the axes (C order): unit ``k`` sits at
        ``(k // strides[a]) % shape[a]`` along axis ``a``."""
        out = [1] * len(self.shape)
        for ax in range(len(self.shape) - 2, -1, -1):
            out[ax] = out[ax + 1] * self.shape[ax + 1]
        return tuple(out)
