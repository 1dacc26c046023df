"""A basis-function network (Deneve et al. 2001): a fixed conjunctive layer, learned readout.

The hidden layer is fixed: hidden unit ``m`` has two ordinary synapses, one from retinal unit
``i_m`` and one from gaze unit ``j_m`` (every ``stride``-th unit of each grid, all
combinations), and fires ``phi_m = 1 / (1 + exp(-g (x_i + y_j - theta)))``: with ``theta``
near the height of one code's peak it needs both inputs, a conjunction. Each map unit sums the
hidden layer through learned first-order weights, ``h_k = sum_m c_km phi_m``, and the weights
learn by the chapter's rule with the hidden layer as input: winner from view 0, then

    dc_k = eps a_k (phi(x1, y1) - c_k),

a Kohonen step towards the hidden response to view 1 (:mod:`sigmapi.neurons.training`); its
fixed point is the mean hidden response over the pairs a unit wins. With ``phi_m = x_i y_j``
this is the Sigma-Pi map itself; with a sigmoid of a sum, a map of connectionist neurons on a
layer of connectionist neurons. Only the readout learns: the hidden units respond to the
views, not to z, so they could not learn by a slowness principle (the chapter's section 7.1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.neurons.training import FirstOrderMap, TrainingConfig, train

__all__ = ["BasisFunctionMap"]

Array = NDArray[np.float64]


class BasisFunctionMap(FirstOrderMap):
    """A map that reads a fixed layer of conjunctive basis-function units (module docstring).

    Parameters
    ----------
    config : SOMConfig
        The task: codes, relation, map grid.
    stride : int
        Every ``stride``-th retinal and gaze unit (along every axis) gets hidden units.
    gain, threshold : float
        Slope and threshold of the hidden units' sigmoid of ``x_i + y_j``.

    Examples
    --------
    >>> from sigmapi.config import load_preset
    >>> m = BasisFunctionMap(load_preset("tiny-1d"))
    >>> m.n_hidden == m.x_code.size * m.y_code.size
    True
    """

    def __init__(
        self, config: SOMConfig, stride: int = 1, gain: float = 30.0, threshold: float = 1.2
    ) -> None:
        self.config = config
        self.stride = _validate.integer("stride", stride, 1, fix="e.g. 1 (every unit)")
        self.gain = _validate.number("gain", gain, 0.0, lo_open=True, fix="e.g. 30")
        self.threshold = _validate.number("threshold", threshold, -10.0, 10.0, fix="e.g. 1.2")
        self.ix = self._subgrid(self.x_shape)
        self.iy = self._subgrid(self.y_shape)
        self.c_ = np.zeros((self.n_units, self.n_hidden))

    def _subgrid(self, shape: tuple[int, ...]) -> NDArray[np.int64]:
        grids = np.meshgrid(*(np.arange(0, n, self.stride) for n in shape), indexing="ij")
        return np.asarray(np.ravel_multi_index(tuple(g.ravel() for g in grids), shape))

    @property
    def n_hidden(self) -> int:
        """Hidden (basis-function) units."""
        return int(self.ix.size * self.iy.size)

    def fit(
        self, training: TrainingConfig | None = None, seed: int | np.random.SeedSequence = 0
    ) -> BasisFunctionMap:
        """Train the readout with the two-view rule (``seed``: of its pairs and start, an int
        or a ``SeedSequence``); returns self."""
        train(self, training or TrainingConfig(), np.random.default_rng(seed))
        return self

    def hidden(self, x: Array, y: Array) -> Array:
        """The basis-function layer's response ``(B, M)``."""
        s = np.asarray(x)[:, self.ix, None] + np.asarray(y)[:, None, self.iy]
        z = np.clip(self.gain * (s - self.threshold), -60.0, 60.0)
        return np.asarray((1.0 / (1.0 + np.exp(-z))).reshape(s.shape[0], -1))

    def respond(self, x: Array, y: Array) -> Array:
        """``h_k = sum_m c_km phi_m`` ``(B, K)``."""
        return np.asarray(self.hidden(x, y) @ self.c_.T)

    @property
    def synapses(self) -> int:
        """Per map unit: ``M`` readout synapses plus its share of the hidden layer's ``2 M``."""
        return round(self.n_hidden * (1.0 + 2.0 / self.n_units))

    def start(self, a: Array, x1: Array, y1: Array, rng: np.random.Generator) -> None:
        """Each unit the neighbourhood mean of the hidden responses to the pairs placed near it."""
        self.c_ = a @ self.hidden(x1, y1)

    def learn(self, a: Array, x1: Array, y1: Array, eps: float) -> None:
        """``dc_k = eps sum_pairs a_k (phi(x1, y1) - c_k)``."""
        coef = eps * a
        self.c_ += coef.T @ self.hidden(x1, y1) - coef.sum(axis=0)[:, None] * self.c_

    def refine(self, winners: NDArray[np.int64], x1: Array, y1: Array) -> None:
        """Every unit to the mean hidden response to view 1 over the pairs it won."""
        sums = np.zeros_like(self.c_)
        np.add.at(sums, winners, self.hidden(x1, y1))
        n = np.bincount(winners, minlength=self.n_units)
        seen = n > 0
        self.c_[seen] = sums[seen] / n[seen, None]
