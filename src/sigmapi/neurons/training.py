"""The chapter's two-view rule for maps of first-order neurons (docs/guide/neurons.md).

A map of this package is a :class:`FirstOrderMap`: ``respond(x, y)`` gives every unit's
activation ``(B, K)`` and the unit of the largest one is the winner. Training is the rule of
the Sigma-Pi map (docs/algorithm.md), for any such unit:

1. the winner ``k*`` from view 0, ``(x0, y0)``: the border-normalised soft winner the
   presets train with under their ordered start (``"soft_mean"``,
   :mod:`sigmapi.rules.winners`: the activations smoothed over the map with width
   ``sigma(t)``), the argmax of the activations at the end;
2. the neighbourhood ``a_k`` around it on the map (an L2-normalised Gaussian of width
   ``sigma(t)``, :func:`sigmapi.rules.neighbourhood.neighbourhood`);
3. every unit learns **view 1**, ``(x1, y1)``, in proportion to ``a_k`` (the model's
   :meth:`FirstOrderMap.learn`, a local rule of its own);

then, as the ``paper-1d`` and ``paper-2d`` presets do, a few batch steps of the same rule
with ``sigma = 0`` (:meth:`FirstOrderMap.refine`): every unit set to the fixed point of its
rule over the pairs it wins. The start is ordered the way the presets order the Sigma-Pi map
(``ordering = "crossview"``): each pair of a first batch is placed on the map by the
cross-view components of the two views (:func:`sigmapi.rules.ordering.crossview_scores`,
which never read z) and each unit starts from the pairs placed near it
(:meth:`FirstOrderMap.start`). Pairs are drawn by the model's own
:class:`~sigmapi.tasks.TwoViewSampler` and learned in mini-batches of ``batch`` pairs, each
pair with the rate ``eps`` (the sum of their updates, as ``batch`` online steps would
nearly give).
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from sigmapi import _validate
from sigmapi.codes import grid_coordinates
from sigmapi.config import SOMConfig
from sigmapi.model._grids import GridsMixin
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import gaussian, neighbourhood
from sigmapi.rules.ordering import INIT_PAIRS, crossview_scores
from sigmapi.rules.winners import ARGMAX, SOFT_MEAN, Scoring, WinnerRule

__all__ = ["CHUNK", "FirstOrderMap", "TrainingConfig", "train"]

Array = NDArray[np.float64]

CHUNK = 4096
"""Pairs drawn from the sampler at once."""


@dataclass(frozen=True)
class TrainingConfig:
    """The schedule of the two-view rule for a map of first-order neurons."""

    pairs: int = 100_000
    """View pairs of the online phase."""
    batch: int = 16
    """Pairs per update of the online phase."""
    eps: tuple[float, float] = (0.02, 0.005)
    """Learning rate per pair at the start and at the end of the online phase (linear)."""
    sigma: tuple[float, float] = (3.0, 0.05)
    """Neighbourhood width (map units) at the start and at the end of the online phase: held
    at the start for the first ``hold`` of it, then shrinking exponentially; 3 is the cap the
    presets' ordered start trains with."""
    hold: float = 0.3
    """Share of the online phase at the first ``sigma``."""
    start_sigma: float = 3.0
    """Width of the neighbourhood that averages the pairs placed near each unit at the start."""
    refine_rounds: int = 2
    """Batch steps of the rule with ``sigma = 0`` after the online phase."""
    refine_pairs: int = 50_000
    """View pairs of each batch step."""

    def __post_init__(self) -> None:
        _validate.integer("pairs", self.pairs, 0, fix="e.g. 100000")
        _validate.integer("batch", self.batch, 1, 4096, fix="e.g. 16")
        for name, pair, lo in (("eps", self.eps, 0.0), ("sigma", self.sigma, 1e-3)):
            if len(pair) != 2:
                raise _validate.fail(name, "a (start, end) pair", pair, "e.g. (0.02, 0.005)")
            for v in pair:
                _validate.number(name, v, lo, lo_open=name == "eps", fix="a positive number")
        if self.batch * self.eps[0] > 1.0:
            raise _validate.fail(
                "batch * eps",
                "<= 1 (an update overshoots beyond it)",
                self.batch * self.eps[0],
                "use a smaller batch or eps",
            )
        _validate.number("hold", self.hold, 0.0, 1.0, hi_open=True, fix="e.g. 0.3")
        _validate.number("start_sigma", self.start_sigma, 1e-3, fix="e.g. 3.0")
        _validate.integer("refine_rounds", self.refine_rounds, 0, fix="e.g. 2")
        _validate.integer("refine_pairs", self.refine_pairs, 1, fix="e.g. 50000")


class FirstOrderMap(GridsMixin):
    """A map of units that sum first-order synapses (through whatever nonlinearity) on the
    task of a :class:`~sigmapi.config.SOMConfig` (its codes, relation and map grid).

    It has what :func:`sigmapi.evaluate` reads of a map (``winner``, ``respond``, the grids,
    ``sampler``), so that the Sigma-Pi map and these maps are scored by one function.
    """

    config: SOMConfig
    sigma_: float = 0.0
    """The neighbourhood width :func:`sigmapi.evaluate` scores at: hard winners."""

    @property
    def winner_rule_(self) -> WinnerRule:
        """The winner rule: the unit of the largest activation."""
        return ARGMAX

    def unit_sqnorms(self) -> Array:
        """Unused by the argmax rule; here for the interface :func:`sigmapi.evaluate` reads."""
        return np.zeros(self.n_units)

    @abstractmethod
    def respond(self, x: Array, y: Array) -> Array:
        """Every unit's activation ``(B, K)`` for codes ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``."""

    def winner(self, x: Array, y: Array, hard: bool = True) -> NDArray[np.int64]:
        """The unit of the largest activation ``(B,)`` (ties: the lowest index)."""
        return np.asarray(np.argmax(self.respond(np.asarray(x), np.asarray(y)), axis=1))

    @abstractmethod
    def start(self, a: Array, x1: Array, y1: Array, rng: np.random.Generator) -> None:
        """The ordered start: ``a`` ``(K, N)`` how near each of N pairs was placed to each
        unit (rows sum to 1); ``x1``, ``y1`` view 1 of the pairs."""

    @abstractmethod
    def learn(self, a: Array, x1: Array, y1: Array, eps: float) -> None:
        """One update of every unit from view 1 of a batch, ``a`` ``(B, K)`` the neighbourhood
        of each pair's view-0 winner."""

    @abstractmethod
    def refine(self, winners: NDArray[np.int64], x1: Array, y1: Array) -> None:
        """One batch step at ``sigma = 0``: every unit to the fixed point of its rule over
        the pairs it won (``winners`` from view 0); units that won none keep their weights."""

    def restructure(self, progress: float) -> None:
        """Structural plasticity after each online update, ``progress`` the share of the
        online phase done (1 after it); none here."""

    @property
    @abstractmethod
    def synapses(self) -> int:
        """Synapses per map unit (its share of any shared layer included)."""


def _draw(model: FirstOrderMap, n: int, rng: np.random.Generator) -> tuple[Array, ...]:
    b = model.sampler.sample(n, rng)
    return b.x0, b.y0, b.x1, b.y1


def placement(model: FirstOrderMap, views: tuple[Array, ...], sigma: float) -> Array:
    """``(K, N)``: how near each pair of ``views`` lies to each unit after the cross-view
    placement (rows sum to 1), as :func:`sigmapi.rules.ordering.crossview_init` weighs them."""
    shape = model.map_shape
    sizes = np.asarray(shape, dtype=np.float64)
    with threadpool_limits(limits=1, user_api="blas"):
        scores = crossview_scores(views, model.x_shape, model.y_shape, len(shape))
    n = views[0].shape[0]
    ranks = (np.argsort(np.argsort(scores, axis=0, kind="stable"), axis=0) + 0.5) / n
    place = ranks * (sizes - 1.0)
    units = grid_coordinates(shape)
    d2 = ((units[:, None, :] - place[None, :, :]) ** 2).sum(axis=-1)
    a = gaussian(d2 - d2.min(axis=1, keepdims=True), sigma)
    return np.asarray(a / a.sum(axis=1, keepdims=True))


def train(model: FirstOrderMap, config: TrainingConfig, rng: np.random.Generator) -> None:
    """Train ``model`` in place with the two-view rule (module docstring)."""
    views = _draw(model, INIT_PAIRS, rng)
    model.start(placement(model, views, config.start_sigma), views[2], views[3], rng)
    steps = config.pairs // config.batch
    s0, s1 = config.sigma
    e0, e1 = config.eps
    # the winner's smoothing over the whole map (the window as wide as the map); the update's
    # neighbourhood on the bounded grid
    smoothing = MapGeometry(model.map_shape, model.config.map_periodic, max(model.map_shape))
    grid = MapGeometry(model.map_shape)
    pool: tuple[Array, ...] = ()
    used = CHUNK
    for step in range(steps):
        if used + config.batch > CHUNK:
            pool, used = _draw(model, CHUNK, rng), 0
        x0, y0, x1, y1 = (v[used : used + config.batch] for v in pool)
        used += config.batch
        f = step / max(steps - 1, 1)
        sigma = s0 * (s1 / s0) ** max(0.0, (f - config.hold) / (1.0 - config.hold))
        w = SOFT_MEAN.winners(model.respond(x0, y0), Scoring(smoothing, sigma))
        model.learn(neighbourhood(w, grid, sigma), x1, y1, e0 + (e1 - e0) * f)
        model.restructure(f)
    model.restructure(1.0)
    for _ in range(config.refine_rounds):
        chunks = []
        for s in range(0, config.refine_pairs, CHUNK):
            x0, y0, x1, y1 = _draw(model, min(CHUNK, config.refine_pairs - s), rng)
            chunks.append((model.winner(x0, y0), x1, y1))
        model.refine(*(np.concatenate(c) for c in zip(*chunks, strict=True)))
