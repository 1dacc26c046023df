"""Reach by association: a layer that learns, from motor babbling, the posture that puts the
hand where a state says.

During babbling the arm takes random postures ``q`` while the eyes look at the hand; each
babble gives a state ``phi`` (features of what the robot sees: a bump around the winning unit
of a map, or population codes) and the posture that caused it. The :class:`Association` is a
linear layer ``q_hat = W^T phi`` trained by the normalised delta rule

    W <- W + lr * phi (q - W^T phi)^T / |phi|^2

(least mean squares, stable for ``0 < lr < 2``). On a map's bump features, each unit's weight
row becomes the mean posture of the babbles it and its neighbours won: the associative layer
of Weber, Karantzis & Wermter (2005), whose units learn the arm posture that put the hand at
their place. To reach, the state of the target gives the posture (:meth:`Association.predict`).

References
----------
C. Weber, K. Karantzis, S. Wermter, "Grasping with flexible viewing-direction with a learned
coordinate transformation network", IEEE-RAS Humanoids 2005.

Examples
--------
>>> rng = np.random.default_rng(0)
>>> phi = np.eye(3)[rng.integers(0, 3, 300)]          # three states, one-hot
>>> q = phi @ np.array([[0.0, 1.0], [1.0, 0.0], [0.5, 0.5]])
>>> a = Association(3, 2).fit(phi, q)
>>> np.round(a.predict(np.eye(3)), 3).tolist()
[[0.0, 1.0], [1.0, 0.0], [0.5, 0.5]]
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi.errors import DataError, NotFittedError

__all__ = ["Association"]

Array = NDArray[np.float64]


class Association:
    """A linear associative layer from ``n_features`` state features to ``n_out`` joints.

    Parameters
    ----------
    n_features : int
        Length of a state's feature vector.
    n_out : int
        Joints of the posture.
    lr : float
        Learning rate of the normalised delta rule in the first pass, in (0, 2).
    lr_end : float
        Learning rate of the last pass of :meth:`fit` (geometric in between), in (0, lr]: a
        rate that falls averages the babbles out instead of tracking the last few.
    epochs : int
        Passes over the babbles in :meth:`fit`.
    """

    def __init__(
        self, n_features: int, n_out: int, lr: float = 0.5, lr_end: float = 0.02, epochs: int = 8
    ) -> None:
        self.n_features = _validate.integer("n_features", n_features, 1)
        self.n_out = _validate.integer("n_out", n_out, 1)
        self.lr = _validate.number("lr", lr, 1e-9, 1.999)
        self.lr_end = _validate.number("lr_end", lr_end, 1e-9, self.lr)
        self.epochs = _validate.integer("epochs", epochs, 1)
        self.weights_: Array | None = None

    def _check(self, phi: ArrayLike, name: str = "phi") -> Array:
        a = np.asarray(phi, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != self.n_features:
            raise DataError(f"{name} must have shape (B, {self.n_features}), got {a.shape}")
        return a

    def partial_fit(self, phi: ArrayLike, q: ArrayLike, lr: float | None = None) -> Association:
        """One pass of the delta rule (rate ``lr``, default :attr:`lr`) over babbles ``phi``
        ``(B, n_features)`` and postures ``q`` ``(B, n_out)``, in order; returns self."""
        rate = self.lr if lr is None else lr
        p, target = self._check(phi), np.asarray(q, dtype=np.float64)
        if target.shape != (p.shape[0], self.n_out):
            raise DataError(f"q must have shape ({p.shape[0]}, {self.n_out}), got {target.shape}")
        if self.weights_ is None:
            self.weights_ = np.zeros((self.n_features, self.n_out))
        w = self.weights_
        norms = np.einsum("ij,ij->i", p, p)
        for f, t, n in zip(p, target, norms, strict=True):
            if n > 0:
                w += np.outer(f, (rate / n) * (t - f @ w))
        return self

    def fit(
        self,
        phi: ArrayLike,
        q: ArrayLike,
        on_epoch: Callable[[int, Association], None] | None = None,
    ) -> Association:
        """``epochs`` passes of :meth:`partial_fit` from zero weights, the rate falling from
        :attr:`lr` to :attr:`lr_end`; ``on_epoch(k, self)`` after each pass. Returns self."""
        self.weights_ = None
        rates = np.geomspace(self.lr, self.lr_end, self.epochs)
        for k in range(self.epochs):
            self.partial_fit(phi, q, float(rates[k]))
            if on_epoch is not None:
                on_epoch(k, self)
        return self

    def predict(self, phi: ArrayLike) -> Array:
        """Postures ``(B, n_out)`` for states ``phi`` ``(B, n_features)``."""
        if self.weights_ is None:
            raise NotFittedError("this Association is not fitted yet; call fit(phi, q) first")
        return self._check(phi) @ self.weights_
