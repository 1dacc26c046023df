"""The approximate cost of the chapter's section 6.3 (after Kaski 1997): :class:`CostMixin`.

``E = mean_mu sum_k a_k^mu |x1^mu y1^mu^T - w_k|^2``: the neighbourhood ``a^mu`` of the winner
of view 0, the data outer product of view 1. Computed from the model's kernel (activations,
unit norms, neighbourhood) without forming an outer product.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import DataError
from sigmapi.model._core import MapCore
from sigmapi.tasks import Batch

__all__ = ["CostMixin"]


class CostMixin(MapCore):
    """``cost`` and its terms, from the model's kernel, winners and responses."""

    def cost_terms(
        self, batch: Batch, sigma: float | None = None
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """Winners of view 0 ``(B,)``, ``|x1 y1^T - w_k|^2`` for every unit ``(B, n_units)``
        and the neighbourhood of each winner at width ``sigma`` (default: the current sigma)
        ``(B, n_units)``, from the model's kernel.

        The distances use ``|x y^T|^2 = |x|^2 |y|^2`` and ``<x y^T, w_k> = h_k``, so no outer
        product is formed.
        """
        self._run.fitted()  # NotFittedError before fitting, whatever the batch
        if not all(hasattr(batch, name) for name in ("x0", "y0", "x1", "y1")):
            raise DataError(
                f"batch must be a sigmapi.tasks.Batch of two views (x0, y0, x1, y1), got "
                f"{type(batch).__name__}; e.g. model.sampler.sample(1000, rng)"
            )
        if sigma is not None:
            sigma = _validate.width("sigma", sigma, 0.0, lo_open=True)
        k = self.winner(batch.x0, batch.y0)
        h1 = self.respond(batch.x1, batch.y1)
        wn = self.unit_sqnorms()
        dn = (batch.x1**2).sum(1) * (batch.y1**2).sum(1)
        s = self.sigma_ if sigma is None else float(sigma)
        a = self._run.kernel.neighbourhood(k, self.config.geometry, s)
        return k, dn[:, None] - 2.0 * h1 + wn[None, :], a

    def cost(self, batch: Batch, sigma: float | None = None) -> float:
        """Approximate cost of section 6.3 (after Kaski 1997), mean per sample.

        ``E = mean_mu sum_k a_k^mu |x1^mu y1^mu^T - w_k|^2``, with the neighbourhood a^mu of
        the winner of view 0 at width ``sigma`` (default: the current sigma) and the data
        outer product of view 1.
        """
        _, dist, a = self.cost_terms(batch, sigma)
        return float(np.mean(np.sum(a * dist, axis=1)))
