"""First-order Kohonen maps on the concatenated codes ``v = [x; y]``: what SOM users run.

A first-order unit compares the input with one weight vector, ``d_k = |v - w_k|^2``, so its
response is a sum of a function of x and a function of y. The units of the map of
z = (x + y) / 2 must answer to (0.2, 0.8) and (0.8, 0.2) but not to (0.2, 0.2) or (0.8, 0.8):
for a sum of two functions the first pair adds up to the same as the second (an XOR), so no
first-order unit can respond to z alone. The Sigma-Pi unit's products ``x_i y_j`` can.

:class:`KohonenSOM` is sigmapi's own implementation (online Kohonen rule, Gaussian
neighbourhood on the map grid, linear schedules as MiniSom's ``linear_decay_to_zero`` for the
learning rate and ``linear_decay_to_one`` for sigma); :class:`MiniSomMap` runs MiniSom, the
library SOM users already know, on the same rows, as the external reference.

References
----------
T. Kohonen, "Self-organized formation of topologically correct feature maps", Biological
Cybernetics 43 (1982) 59-69. G. Vettigli, MiniSom (https://github.com/JustGlowing/minisom).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi.codes import grid_coordinates
from sigmapi.schedules import PiecewiseLinear

__all__ = ["KohonenSOM", "MiniSomMap", "concat_views"]

Array = NDArray[np.float64]


def concat_views(x: ArrayLike, y: ArrayLike) -> Array:
    """The first-order input ``[x; y]``: codes ``(B, n_x)``, ``(B, n_y)`` -> ``(B, n_x + n_y)``."""
    return np.hstack([np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)])


@njit(cache=True, nogil=True)
def _train(
    w: Array,
    win: Array,
    learn: Array,
    order: NDArray[np.int64],
    coords: Array,
    sigma: Array,
    eps: Array,
) -> None:  # pragma: no cover - compiled
    """Online Kohonen rule, in place on ``w`` ``(K, D)``.

    Iteration t takes row ``r = order[t]``: the winner ``c = argmin_k |win[r] - w_k|^2`` and
    ``w_k += eps[t] exp(-|g_k - g_c|^2 / (2 sigma[t]^2)) (learn[r] - w_k)`` for every unit k
    (grid coordinates ``g``).
    """
    n_units, dim = w.shape
    for t in range(order.shape[0]):
        r = order[t]
        best = 0
        best_d = np.inf
        for k in range(n_units):
            d = 0.0
            for i in range(dim):
                diff = win[r, i] - w[k, i]
                d += diff * diff
            if d < best_d:
                best_d = d
                best = k
        two_s2 = 2.0 * sigma[t] * sigma[t]
        for k in range(n_units):
            g = 0.0
            for a in range(coords.shape[1]):
                dd = coords[k, a] - coords[best, a]
                g += dd * dd
            h = eps[t] * np.exp(-g / two_s2)
            if h < 1e-12:
                continue
            for i in range(dim):
                w[k, i] += h * (learn[r, i] - w[k, i])


class KohonenSOM:
    """First-order Kohonen SOM on ``[x; y]`` (sigmapi's own; MiniSom is the reference).

    Parameters
    ----------
    map_shape : tuple of int
        Grid of map units, e.g. ``(15,)``.
    iterations : int
        Online updates in :meth:`fit`.
    sigma0 : float, optional
        Starting neighbourhood width in map units (default: half the longest map axis); it
        falls linearly to 1, as MiniSom's ``linear_decay_to_one``.
    eps0 : float
        Starting learning rate; it falls linearly to 0 (MiniSom's ``linear_decay_to_zero``).
    two_view : bool
        False (the usual SOM): every view ``[x; y]`` is a sample, the pairing is not used.
        True: the Sigma-Pi map's rule on first-order units, the winner from view 0 learns
        view 1.
    seed : int, optional
        Seed of the initial weights and of the order of the samples.

    Examples
    --------
    >>> from sigmapi import SigmaPiSOM
    >>> som = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,))
    >>> b = som.sampler.sample(200, np.random.default_rng(0))
    >>> k = KohonenSOM((5,), iterations=1000, seed=0).fit((b.x0, b.y0, b.x1, b.y1))
    >>> k.winner(b.x0[:3], b.y0[:3]).shape
    (3,)
    """

    def __init__(
        self,
        map_shape: tuple[int, ...],
        iterations: int = 100_000,
        sigma0: float | None = None,
        eps0: float = 0.5,
        two_view: bool = False,
        seed: int | None = None,
    ) -> None:
        self.map_shape = _validate.shape("map_shape", map_shape)
        self.iterations = _validate.integer("iterations", iterations, 1, fix="e.g. 100000")
        s0 = max(self.map_shape) / 2.0 if sigma0 is None else sigma0
        self.sigma0 = _validate.positive("sigma0", s0, fix="in map units, e.g. 7.5")
        self.eps0 = _validate.number("eps0", eps0, 0.0, 1.0, lo_open=True, fix="e.g. 0.5")
        self.two_view = _validate.boolean("two_view", two_view)
        self.seed = seed
        self.coords = grid_coordinates(self.map_shape)

    def fit(self, views: tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]) -> KohonenSOM:
        """Train on the rows of ``views = (x0, y0, x1, y1)`` (codes); returns ``self``."""
        x0, y0, x1, y1 = views
        v0, v1 = concat_views(x0, y0), concat_views(x1, y1)
        rng = np.random.default_rng(self.seed)
        if self.two_view:
            win, learn = v0, v1
        else:  # both views are samples of [x; y]
            win = learn = np.vstack([v0, v1])
        order = rng.integers(0, win.shape[0], size=self.iterations)
        t = np.arange(self.iterations)
        sigma = PiecewiseLinear(((0.0, self.sigma0), (1.0, 1.0))).at(t, self.iterations)
        eps = PiecewiseLinear(((0.0, self.eps0), (1.0, 0.0))).at(t, self.iterations)
        n_units = int(np.prod(self.map_shape))
        # random samples as the first weights (MiniSom's ``random_weights_init``)
        self.weights_ = learn[rng.integers(0, learn.shape[0], size=n_units)].copy()
        _train(self.weights_, win, learn, order, self.coords, sigma, eps)
        return self

    def winner(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.int64]:
        """Flat index of the nearest unit to ``[x; y]``, ``(B,)``."""
        return nearest_unit(self.weights_, concat_views(x, y))


def nearest_unit(weights: Array, v: Array) -> NDArray[np.int64]:
    """``argmin_k |v_b - w_k|^2`` for rows ``v`` ``(B, D)`` and weights ``(K, D)``."""
    d = (v**2).sum(1)[:, None] - 2.0 * v @ weights.T + (weights**2).sum(1)[None, :]
    return np.asarray(np.argmin(d, axis=1), dtype=np.int64)


class MiniSomMap(KohonenSOM):
    """MiniSom on ``[x; y]`` with the same schedule as :class:`KohonenSOM` (needs ``minisom``).

    A 1-D map of n units is MiniSom's ``1 x n`` grid; unit ``(i, j)`` of a 2-D grid is flat
    index ``i * cols + j`` (C order, as sigmapi's maps). Winners are MiniSom's (Euclidean
    distance to the weights), computed for a whole batch from ``get_weights()``. The
    parameters are :class:`KohonenSOM`'s, without ``two_view`` (MiniSom learns each sample).
    """

    def __init__(
        self,
        map_shape: tuple[int, ...],
        iterations: int = 100_000,
        sigma0: float | None = None,
        eps0: float = 0.5,
        seed: int | None = None,
    ) -> None:
        super().__init__(map_shape, iterations, sigma0, eps0, two_view=False, seed=seed)
        if len(self.map_shape) > 2:
            raise _validate.fail("map_shape", "1-D or 2-D for MiniSom", self.map_shape)

    def fit(self, views: tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]) -> MiniSomMap:
        """Train MiniSom on both views of every row as samples; returns ``self``."""
        from minisom import MiniSom

        x0, y0, x1, y1 = views
        data = np.vstack([concat_views(x0, y0), concat_views(x1, y1)])
        rows, cols = (1, *self.map_shape) if len(self.map_shape) == 1 else self.map_shape
        som: Any = MiniSom(
            rows,
            cols,
            data.shape[1],
            sigma=self.sigma0,
            learning_rate=self.eps0,
            decay_function="linear_decay_to_zero",
            sigma_decay_function="linear_decay_to_one",
            random_seed=self.seed,
        )
        som.random_weights_init(data)
        som.train(data, self.iterations, random_order=True)
        self.weights_ = np.asarray(som.get_weights(), dtype=np.float64).reshape(rows * cols, -1)
        return self
