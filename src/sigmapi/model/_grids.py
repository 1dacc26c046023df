"""The estimator's grids and codes: :class:`GridsMixin`.

Everything here follows from the config alone (no weights): the map, retina and gaze grids,
the population codes the model encodes positions with, the built-in task's two-view sampler
and the grid coordinates of the map units.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.config import SOMConfig
from sigmapi.model.views import CodeViews, encode_views
from sigmapi.tasks import TwoViewSampler

__all__ = ["GridsMixin", "code_of", "sampler_of"]


def code_of(c: SOMConfig, shape: tuple[int, ...]) -> PopulationCode:
    """The population code of config ``c`` on a grid of ``shape`` (its x or y code)."""
    return PopulationCode(shape, c.code_width, c.code_height, c.code_normalize, c.periodic)


def sampler_of(c: SOMConfig) -> TwoViewSampler:
    """The two-view sampler of the built-in task of config ``c``: its relation and codes."""
    return TwoViewSampler(c.relation, code_of(c, c.x_shape), code_of(c, c.y_shape))


class GridsMixin:
    """Grids, codes and the sampler of a model with a ``config`` (a :class:`SOMConfig`)."""

    config: SOMConfig

    @property
    def map_shape(self) -> tuple[int, ...]:
        return self.config.map_shape

    @property
    def x_shape(self) -> tuple[int, ...]:
        return self.config.x_shape

    @property
    def y_shape(self) -> tuple[int, ...]:
        return self.config.y_shape

    @property
    def n_units(self) -> int:
        return int(np.prod(self.map_shape))

    @property
    def x_code(self) -> PopulationCode:
        """The code of x the model was trained with: ``x_code.encode(p)`` for positions p."""
        return code_of(self.config, self.x_shape)

    @property
    def y_code(self) -> PopulationCode:
        """The code of y the model was trained with."""
        return code_of(self.config, self.y_shape)

    @property
    def sampler(self) -> TwoViewSampler:
        """The two-view sampler of the model's relation and codes."""
        return sampler_of(self.config)

    @property
    def map_coords(self) -> NDArray[np.float64]:
        """Grid coordinates of the map units, ``(n_units, map_ndim)``, C order."""
        return grid_coordinates(self.map_shape)

    def encode_views(
        self, px0: ArrayLike, py0: ArrayLike, px1: ArrayLike, py1: ArrayLike
    ) -> CodeViews:
        """Two views given as positions, as the codes :meth:`fit` takes: ``(x0, y0, x1, y1)``.

        ``px0``, ``px1`` are retinal positions and ``py0``, ``py1`` gaze directions, each of
        shape ``(B, d)`` (``(B,)`` in 1-D) in [0, 1], fractions of the axis (rescale your
        units first); row b of the four arrays shows the same body-centred position twice.
        The codes are the model's own (:attr:`x_code`, :attr:`y_code`).
        """
        return encode_views(self.x_code, self.y_code, px0, py0, px1, py1)
