"""The Gaussian over the map, bounded or periodic: the neighbourhood and the soft winner's
smoothing (docs/algorithm.md, "Learning: one iteration", steps 2 and 3).

Written once: :func:`gaussian` and :func:`axis_distance` are plain functions of scalars or
arrays that the reference arithmetic below calls with NumPy arrays and the fast kernel
compiles with numba (:mod:`sigmapi.kernels._rows`), so that every backend evaluates the same
expression. Shapes: winners ``(B,)``, activations and neighbourhoods ``(B, K)`` over ``K``
units on the grid ``geometry.shape`` (:class:`~sigmapi.rules.geometry.MapGeometry`),
flattened in C order. ``geometry.periodic``: every map axis wraps around (a ring in 1-D, a
torus in 2-D); distances go the shorter way round.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.codes import grid_coordinates
from sigmapi.rules.geometry import MapGeometry

__all__ = [
    "GAUSSIAN",
    "NEIGHBOURHOODS",
    "Gaussian",
    "axis_distance",
    "gaussian",
    "neighbourhood",
    "smooth",
    "smoothing_matrix",
]


def gaussian(d2: Any, sigma: Any) -> Any:
    """The Gaussian profile ``exp(-d2 / (2 sigma^2))`` of squared grid distances ``d2``.

    ``sigma**2`` is written as a power on purpose: CPython evaluates it with the C library's
    ``pow`` and numba as ``sigma * sigma``, which is what each backend computed before this
    function served both, so that neither backend's numbers moved.
    """
    return np.exp(-d2 / (2.0 * sigma**2))


def axis_distance(d: Any, n: Any, map_periodic: bool) -> Any:
    """Distance along one map axis of ``n`` units from the offset ``d = |i - j|`` (>= 0):
    ``d`` on a bounded axis, ``min(d, n - d)`` (the shorter way round) on a periodic one."""
    return np.minimum(d, n - d) if map_periodic else d


@functools.lru_cache(maxsize=16)
def _coords(map_shape: tuple[int, ...]) -> NDArray[np.float64]:
    coords = grid_coordinates(map_shape)
    coords.flags.writeable = False
    return coords


def neighbourhood(
    winner: NDArray[np.int64], geometry: MapGeometry, sigma: float
) -> NDArray[np.float64]:
    """Gaussian neighbourhood around each winner, L2-normalised; ``(B,)`` -> ``(B, K)``.

    ``a_k = exp(-|g_k - g_k*|^2 / (2 sigma^2)) / norm`` with grid coordinates ``g``; on a
    periodic map each axis's difference is taken the shorter way round the ring.

    Examples
    --------
    >>> a = neighbourhood(np.array([0]), MapGeometry((3,)), 1.0)
    >>> a.shape, bool(a[0, 0] > a[0, 1] > a[0, 2])
    ((1, 3), True)
    """
    coords = _coords(geometry.shape)
    diff = np.abs(coords[None, :, :] - coords[np.asarray(winner)][:, None, :])
    diff = axis_distance(diff, np.asarray(geometry.shape, dtype=np.float64), geometry.periodic)
    d2 = (diff**2).sum(axis=2)
    a = gaussian(d2, sigma)
    return np.asarray(a / np.linalg.norm(a, axis=1, keepdims=True))


def smoothing_matrix(n: int, sigma: float, cut: int, map_periodic: bool) -> NDArray[np.float64]:
    """``(n, n)`` Gaussian weights between the units of one map axis, zero beyond ``cut``."""
    d = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    d = axis_distance(d, n, map_periodic)
    g = gaussian(d.astype(np.float64) ** 2, sigma)
    g[np.abs(d) > cut] = 0.0
    return np.asarray(g)


def smooth(h: NDArray[np.floating], geometry: MapGeometry, sigma: float) -> NDArray[np.float64]:
    """Convolve activations ``(B, K)`` over the map grid with a Gaussian of width ``sigma``.

    Summed over a window of ``geometry.soft_cut`` units each way along every axis (the
    authors' script: 15). On a bounded map (the paper) the window stops at the border; on a
    periodic map it wraps around, and every unit of the window counts once, at its distance
    the shorter way round. Separable: one matrix product per map axis.
    """
    b = h.shape[0]
    g = np.asarray(h, dtype=np.float64).reshape((b, *geometry.shape))
    for axis, n in enumerate(geometry.shape):
        m = smoothing_matrix(n, sigma, geometry.soft_cut, geometry.periodic)
        g = np.moveaxis(np.tensordot(g, m, axes=([axis + 1], [1])), -1, axis + 1)
    return g.reshape(b, -1)


class Gaussian:
    """The neighbourhood of the paper: an L2-normalised Gaussian around the winner.

    Calling it is :func:`neighbourhood` (the reference arithmetic); the fast kernel's compiled
    form is ``sigmapi.kernels.fast._neighbourhood``, built from the same :func:`gaussian`.
    """

    name = "gaussian"

    def __call__(
        self, winner: NDArray[np.int64], geometry: MapGeometry, sigma: float
    ) -> NDArray[np.float64]:
        return neighbourhood(winner, geometry, sigma)

    def __repr__(self) -> str:
        return f"<neighbourhood {self.name!r}>"


GAUSSIAN = Gaussian()
NEIGHBOURHOODS: dict[str, Gaussian] = {GAUSSIAN.name: GAUSSIAN}
"""The neighbourhoods by name."""
