"""Learning curves: a ``fit`` callback that measures the model at checkpoints while it trains.

- :func:`checkpoints`: iteration counts to measure at (log- or linearly spaced).
- :func:`costs`: the approximate cost of section 6.3, at the current sigma and winner-only.
- :class:`LearningCurve`: the callback; its records are the columns of the curves figure.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sigmapi.metrics import evaluate, evaluation_sets

if TYPE_CHECKING:
    from sigmapi.model.som import SigmaPiSOM
    from sigmapi.tasks import Batch

__all__ = ["LearningCurve", "checkpoints", "costs"]


def checkpoints(iterations: int, n: int = 20, spacing: str = "log", block: int = 1000) -> list[int]:
    """About ``n`` iteration counts between ``block`` and ``iterations`` (multiples of ``block``).

    ``spacing``: ``"log"`` (dense early, where the map unfolds) or ``"linear"``. The last
    checkpoint is always ``iterations``.
    """
    if spacing not in ("log", "linear"):
        raise ValueError(f"spacing must be 'log' or 'linear', got {spacing!r}")
    first = min(block, iterations)
    if spacing == "log":
        raw = np.geomspace(first, iterations, n)
    else:
        raw = np.linspace(first, iterations, n)
    pts = {round(float(v) / block) * block for v in raw}
    pts = {min(max(p, first), iterations) for p in pts} | {iterations}
    return sorted(pts)


def costs(model: SigmaPiSOM, batch: Batch) -> tuple[float, float]:
    """The approximate cost of section 6.3 at the current sigma and with the winner alone.

    The same numbers as ``model.cost(batch)`` and ``model.cost(batch, sigma=1e-5)``, computed
    in one pass (one winner search, one activation of view 1, one neighbourhood).
    """
    k, dist, a = model.cost_terms(batch)
    rows = np.arange(k.size)
    return float(np.mean(np.sum(a * dist, axis=1))), float(np.mean(dist[rows, k]))


@dataclass
class LearningCurve:
    """A ``fit`` callback that measures the model at checkpoints during training.

    Call it as ``model.fit(callback=curve)``; each time the model passes a checkpoint it
    records the iteration, sigma, the refinement pairs done (``refined``; 0 while training),
    the metrics of :func:`sigmapi.metrics.evaluate` on a small
    fixed test set, and the approximate cost of section 6.3 (at the current sigma, and
    ``cost_winner``: with the winner alone, sigma -> 0, comparable across the run). After the
    training it also records the end of every refinement round on the built-in task
    (:mod:`sigmapi.rules.refinement`; ``refined`` a multiple of ``config.refine_pairs``), so
    the cost's fall over the rounds is part of the curve.

    Parameters
    ----------
    at : list of int
        Checkpoint iterations (see :func:`checkpoints`).
    n_test : int
        Size of the test and calibration sets (drawn once, from ``seed``).
    seed : int
        Seed of the evaluation data.
    then : callable, optional
        Another callback to call every time (e.g. a progress bar).

    Examples
    --------
    >>> from sigmapi import SigmaPiSOM
    >>> som = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0)
    >>> curve = LearningCurve(at=[1000, 2000], n_test=200)
    >>> _ = som.fit(callback=curve)
    >>> [int(r["t"]) for r in curve.records]
    [1000, 2000]
    """

    at: list[int]
    n_test: int = 1000
    seed: int = 12345
    then: Callable[[Any], None] | None = None
    records: list[dict[str, float]] = field(default_factory=list)
    seconds: float = 0.0
    """Wall seconds spent measuring so far (kept out of the training times)."""
    _sets: tuple[Batch, Batch] | None = field(default=None, repr=False)

    def __call__(self, model: SigmaPiSOM) -> None:
        if self.then is not None:
            self.then(model)
        refined = model.refined_
        if refined:
            per = model.config.refine_pairs
            if refined % per == 0 and refined not in {int(r["refined"]) for r in self.records}:
                self.records.append(self.measure(model))
            return
        done = {int(r["t"]) for r in self.records}
        due = [t for t in self.at if t <= model.t_ and t not in done]
        if not due or model.t_ in done:
            return
        self.records.append(self.measure(model))

    def measure(self, model: SigmaPiSOM) -> dict[str, float]:
        """The record of ``model`` now (called by ``__call__`` at checkpoints)."""
        started = time.perf_counter()
        try:
            return self._measure(model)
        finally:
            self.seconds += time.perf_counter() - started

    def _measure(self, model: SigmaPiSOM) -> dict[str, float]:
        if self._sets is None:
            self._sets = evaluation_sets(model, self.n_test, self.seed)
        cal, test = self._sets
        m = evaluate(model, test=test, calibration=cal).to_dict()
        cost, cost_winner = costs(model, test)
        return {
            "t": float(model.t_),
            "refined": float(model.refined_),
            "sigma": model.sigma_,
            **{k: float(v) for k, v in m.items() if k != "n_test"},
            "cost": cost,
            "cost_winner": cost_winner,
        }

    def to_dict(self) -> dict[str, list[float]]:
        """Columns of the records: ``{"t": [...], "sigma": [...], ...}`` (JSON-able)."""
        keys = list(self.records[0]) if self.records else []
        return {k: [float(r[k]) for r in self.records] for k in keys}
