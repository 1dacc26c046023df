"""Refinement: the chapter's batch minimisation of the approximate cost (section 6.3, Eq. 5-7).

After training, rounds of the two alternating steps of section 6.3, each over a stream of
view pairs (never z):

1. **assignments with the weights fixed**: the winner ``k*`` of view 0 under the training
   rule's hard limit (:attr:`~sigmapi.rules.WinnerRule.hard`), on the weights of the round's
   start;
2. **weights with the assignments fixed**: every unit's weights become the
   neighbourhood-weighted mean of view 1's outer products over the round's pairs,
   ``w_k = sum_mu a_k^mu x1^mu y1^mu^T / sum_mu a_k^mu`` (Eq. 7, the minimum of Eq. 5 for
   fixed winners), with ``a`` the L2-normalised Gaussian around ``k*`` at width ``sigma``
   (:func:`~sigmapi.rules.neighbourhood.neighbourhood`, the cost's own) or, at ``sigma = 0``,
   the winner alone (``a_k = 1`` for ``k = k*``). A unit whose mass ``sum_mu a_k^mu`` is 0
   (it won nothing) keeps its weights.

:class:`BatchMean` is the reference arithmetic: :meth:`~BatchMean.start` makes float64
accumulators, :meth:`~BatchMean.accumulate` adds pairs one after another (so the sums do
not depend on how the stream is cut into blocks), :meth:`~BatchMean.finish` divides. The
fast kernel computes the same sums on its own layout
(``sigmapi.kernels.fast.FastKernel.refine_block``, the sparse pairs of ``kernel_tol``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import neighbourhood

__all__ = ["BATCH_MEAN", "REFINEMENTS", "BatchMean", "Sums", "assignment"]


@dataclass
class Sums:
    """Accumulators of one round: ``sums`` (a kernel's layout; the reference's
    ``(K, n_x, n_y)``; float64, float32 on a fast path) and ``mass`` ``(K,)``, float64;
    ``pairs``: how many pairs they hold.

    ``code_shapes``: the grids of the codes ``(x_shape, y_shape)`` if known (a kernel may use
    their geometry to search faster; None: each code a line); ``index``: what a kernel
    prepared from the round's fixed weights for its searches (None until it does); ``tol``:
    the config's ``refine_tol`` (0: the kernel's own arithmetic, bit for bit; above 0 a
    kernel's fast path within a tolerance, its sums maybe float32)."""

    sums: NDArray[np.floating]
    mass: NDArray[np.float64]
    pairs: int = 0
    code_shapes: tuple[tuple[int, ...], tuple[int, ...]] | None = None
    index: Any = None
    tol: float = 0.0


def assignment(
    winners: NDArray[np.int64], geometry: MapGeometry, sigma: float
) -> NDArray[np.float64]:
    """The weight ``a[b, k]`` of pair ``b`` in unit ``k``'s mean, ``(B, K)``: the winner alone
    at ``sigma = 0``, else the L2-normalised Gaussian around the winner (the cost's) on the
    map ``geometry``."""
    if sigma == 0:
        a = np.zeros((winners.size, geometry.units))
        a[np.arange(winners.size), winners] = 1.0
        return a
    return np.asarray(neighbourhood(winners, geometry, sigma), dtype=np.float64)


class BatchMean:
    """Weights to the neighbourhood-weighted mean of view 1's outer products (Eq. 7)."""

    name = "batch_mean"

    def start(self, shape: tuple[int, int, int]) -> Sums:
        """Empty accumulators for weights of ``shape`` ``(K, n_x, n_y)``."""
        return Sums(np.zeros(shape), np.zeros(shape[0]))

    def accumulate(
        self,
        acc: Sums,
        a: NDArray[np.float64],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
    ) -> None:
        """Add pairs in order: ``sums[k] += a[b, k] * (x1[b] y1[b]^T)``, ``mass += a[b]``."""
        for b in range(x1.shape[0]):
            outer = np.outer(x1[b], y1[b])
            acc.sums += a[b][:, None, None] * outer[None, :, :]
            acc.mass += a[b]
        acc.pairs += int(x1.shape[0])

    def finish(self, weights: NDArray[np.floating], acc: Sums) -> NDArray[np.float64]:
        """The new weights: ``sums / mass`` per unit, ``weights`` where the mass is 0."""
        out = np.array(weights, dtype=np.float64, copy=True)
        won = acc.mass > 0
        out[won] = acc.sums[won] / acc.mass[won][:, None, None]
        return out

    def __repr__(self) -> str:
        return f"<refinement {self.name!r}>"


BATCH_MEAN = BatchMean()
REFINEMENTS: dict[str, BatchMean] = {BATCH_MEAN.name: BATCH_MEAN}
"""The refinement rules by name."""
