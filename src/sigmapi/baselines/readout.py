"""Baselines that need a teacher for z: a gain-field layer or an RBM, then a linear read-out.

- :class:`GainFieldNetwork`, the basis-function network (Pouget and Sejnowski 1997; Salinas
  and Abbott 1995): a fixed middle layer of gain-field units, one per product ``x_i y_j`` of
  the two codes (the very products a Sigma-Pi unit sums), and a linear read-out of z fitted
  to labelled samples. It learns nothing without labels: the chapter's point is that its
  middle layer is hard to train without a teacher.
- :class:`RBMFeatures`, the route of De Filippo De Grazia, Cutini, Lisi and Zorzi (2012): a
  restricted Boltzmann machine (scikit-learn's ``BernoulliRBM``) trained without a teacher on
  ``[x; y]``, whose hidden probabilities are read out linearly.

The read-out (:func:`fit_readout`) is scikit-learn's ``RidgeCV``: least squares with an L2
penalty chosen by leave-one-out on the labelled samples alone, the closed-form limit of the
delta rule the papers train. Both need ``scikit-learn`` (``pip install 'sigmapi[baselines]'``).

References
----------
A. Pouget and T. J. Sejnowski, "Spatial transformations in the parietal cortex using basis
functions", J. Cognitive Neuroscience 9 (1997) 222-237. M. De Filippo De Grazia, S. Cutini,
M. Lisi and M. Zorzi, "Space coding for sensorimotor transformations can emerge through
unsupervised learning", Cognitive Processing 13 (2012) S141-S146.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi.baselines.kohonen import concat_views

__all__ = ["READOUT_ALPHAS", "GainFieldNetwork", "RBMFeatures", "fit_readout"]

Array = NDArray[np.float64]

READOUT_ALPHAS = tuple(10.0**k for k in range(-6, 3))
"""L2 penalties the read-out chooses from (leave-one-out on the labelled samples)."""


def fit_readout(features: Array, z: Array) -> Callable[[Array], Array]:
    """A linear read-out ``z ~ features @ A + b`` fitted to labelled samples (``RidgeCV``).

    ``features`` ``(L, F)``, ``z`` ``(L, d)``; returns ``predict(features) -> (B, d)``.
    """
    from sklearn.linear_model import RidgeCV

    model: Any = RidgeCV(alphas=READOUT_ALPHAS).fit(features, z)
    d = z.shape[1]
    return lambda f: np.asarray(model.predict(f), dtype=np.float64).reshape(f.shape[0], d)


class GainFieldNetwork:
    """Gain-field layer ``g_ij = x_i y_j`` (fixed, ``n_x * n_y`` units); no unsupervised step.

    Examples
    --------
    >>> GainFieldNetwork().features(np.ones((2, 3)), np.ones((2, 4))).shape
    (2, 12)
    """

    def fit(self, views: tuple[ArrayLike, ...]) -> GainFieldNetwork:
        """Nothing to learn without a teacher; returns ``self`` (the read-out needs labels)."""
        return self

    def features(self, x: ArrayLike, y: ArrayLike) -> Array:
        """The gain-field responses ``(B, n_x * n_y)``: the outer product of the codes."""
        xa, ya = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        return (xa[:, :, None] * ya[:, None, :]).reshape(xa.shape[0], -1)


class RBMFeatures:
    """A Bernoulli RBM trained without a teacher on both views ``[x; y]`` of every row.

    Parameters
    ----------
    n_hidden : int
        Hidden units (the comparison gives it as many as the gain-field layer has).
    epochs : int
        Passes of persistent contrastive divergence over the data.
    learning_rate : float
        scikit-learn's ``learning_rate``.
    seed : int, optional
        ``random_state`` of the RBM.
    """

    def __init__(
        self,
        n_hidden: int = 225,
        epochs: int = 10,
        learning_rate: float = 0.05,
        seed: int | None = None,
    ) -> None:
        self.n_hidden = _validate.integer("n_hidden", n_hidden, 1, fix="e.g. 225")
        self.epochs = _validate.integer("epochs", epochs, 1, fix="e.g. 10")
        self.learning_rate = _validate.positive("learning_rate", learning_rate, fix="e.g. 0.05")
        self.seed = seed

    def fit(self, views: tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]) -> RBMFeatures:
        """Train the RBM on ``[x0; y0]`` and ``[x1; y1]`` of every row; returns ``self``."""
        from sklearn.neural_network import BernoulliRBM

        x0, y0, x1, y1 = views
        data = np.vstack([concat_views(x0, y0), concat_views(x1, y1)])
        self.rbm_ = BernoulliRBM(
            n_components=self.n_hidden,
            learning_rate=self.learning_rate,
            batch_size=20,
            n_iter=self.epochs,
            random_state=self.seed,
        ).fit(data)
        return self

    def features(self, x: ArrayLike, y: ArrayLike) -> Array:
        """Hidden-unit probabilities ``P(h = 1 | [x; y])``, ``(B, n_hidden)``."""
        return np.asarray(self.rbm_.transform(concat_views(x, y)), dtype=np.float64)
