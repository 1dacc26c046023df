"""Winner rules: how the winning unit is chosen from the activations (docs/algorithm.md,
"Learning: one iteration", step 2).

A rule turns activations ``h`` ``(B, K)`` into per-unit scores ``(B, K)``; the winner is the
unit of the largest score (ties to the lowest index). Each rule object carries its reference
arithmetic (NumPy), whether it needs the units' squared norms ``|w_k|^2``, its hard limit at
sigma -> 0 (what the metrics use) and its border-normalised variant (what a model trains
with under an ordering procedure, :mod:`sigmapi.rules.ordering`).

Adding a rule: one subclass of :class:`WinnerRule` and its entry in :data:`WINNER_RULES`;
the reference kernel runs it at once (it calls :meth:`WinnerRule.scores`), a compiled kernel
once it has the rule's compiled form (``sigmapi.kernels.fast.COMPILED``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import smooth

__all__ = [
    "ARGMAX",
    "MIN_DISTANCE",
    "SOFT",
    "SOFT_MEAN",
    "WINNER_RULES",
    "Argmax",
    "MinDistance",
    "Scoring",
    "Soft",
    "SoftMean",
    "WinnerRule",
]

Array = NDArray[np.floating]
Scores = NDArray[np.float64]


@dataclass(frozen=True)
class Scoring:
    """What a winner rule reads besides the activations.

    Attributes
    ----------
    geometry : MapGeometry
        The map (:class:`~sigmapi.rules.geometry.MapGeometry`): its grid (``K`` units,
        flattened in C order), whether its axes wrap around, and the half-width
        ``soft_cut`` of the smoothing window, in map units along every axis.
    sigma : float
        Width of the smoothing over the map (the rules that smooth), in map units.
    sqnorms : ndarray, shape (K,), optional
        The units' squared norms ``|w_k|^2``, for the rules that need them.
    """

    geometry: MapGeometry
    sigma: float
    sqnorms: NDArray[np.float64] | None = None


class WinnerRule(ABC):
    """A winner rule: per-unit scores ``(B, K)`` of activations ``h`` ``(B, K)`` whose
    row-wise argmax is the winner (ties to the lowest index)."""

    name: ClassVar[str]
    """The rule's name (its key in :data:`WINNER_RULES`, ``SOMConfig.winner_rule``)."""
    needs_norms: ClassVar[bool] = False
    """Whether :meth:`scores` reads the units' squared norms (``Scoring.sqnorms``)."""

    @abstractmethod
    def scores(self, h: Array, at: Scoring) -> Scores:
        """Scores ``(B, K)``; the winner of row b is their argmax (the reference arithmetic)."""

    def winners(self, h: Array, at: Scoring) -> NDArray[np.int64]:
        """Winning unit per row of ``h``, ``(B,)`` flat indices; ties go to the lowest index."""
        return np.asarray(np.argmax(self.scores(h, at), axis=1), dtype=np.int64)

    @property
    def hard(self) -> WinnerRule:
        """The rule's limit at sigma -> 0 (the metrics' hard winner); itself if sigma-free."""
        return self

    @property
    def border_normalised(self) -> WinnerRule:
        """The variant that does not handicap units at the map's border (used under an
        ordering procedure); itself where the rule has no border effect."""
        return self

    def __repr__(self) -> str:
        return f"<winner rule {self.name!r}>"


class Soft(WinnerRule):
    """``"soft"``, the paper's rule: argmax of the activations smoothed over the map with a
    Gaussian of width sigma, summed over a window of ``soft_cut`` units each way."""

    name = "soft"

    def scores(self, h: Array, at: Scoring) -> Scores:
        return smooth(h, at.geometry, at.sigma)

    @property
    def hard(self) -> WinnerRule:
        return ARGMAX

    @property
    def border_normalised(self) -> WinnerRule:
        return SOFT_MEAN


class SoftMean(WinnerRule):
    """``"soft_mean"``: the soft rule with the smoothed activation divided by the window's
    weight inside the map, so that border units are not handicapped. On a periodic map the
    window weight is the same everywhere and the rule picks the soft rule's units."""

    name = "soft_mean"

    def scores(self, h: Array, at: Scoring) -> Scores:
        ones = np.ones((1, at.geometry.units))
        inside = smooth(ones, at.geometry, at.sigma)
        return smooth(h, at.geometry, at.sigma) / inside

    @property
    def hard(self) -> WinnerRule:
        return ARGMAX


class Argmax(WinnerRule):
    """``"argmax"``: the unit of the largest activation."""

    name = "argmax"

    def scores(self, h: Array, at: Scoring) -> Scores:
        return np.asarray(h)


class MinDistance(WinnerRule):
    """``"min_distance"``: ``argmin_k |vec(x y^T) - w_k|``, written as ``argmax(2 h_k -
    |w_k|^2)`` (the same unit: ``|x y^T|^2`` is the same for every unit)."""

    name = "min_distance"
    needs_norms = True

    def scores(self, h: Array, at: Scoring) -> Scores:
        if at.sqnorms is None:
            raise ValueError("the min_distance rule needs the units' squared norms (sqnorms)")
        return np.asarray(2.0 * np.asarray(h) - at.sqnorms[None, :])


SOFT, SOFT_MEAN, ARGMAX, MIN_DISTANCE = Soft(), SoftMean(), Argmax(), MinDistance()

WINNER_RULES: dict[str, WinnerRule] = {r.name: r for r in (SOFT, ARGMAX, MIN_DISTANCE, SOFT_MEAN)}
"""The winner rules by name (``SOMConfig.winner_rule`` looks up here)."""
