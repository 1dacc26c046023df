"""The kernel contract: what every backend module offers, and the winner rules it knows.

A kernel is a module that satisfies :class:`Kernel`; its state (the weights in the
kernel's own layout) is opaque to the estimator, which only passes it back to the kernel.
The reference kernel's state is the dense weight array itself; the fast kernel's is a
:class:`~sigmapi.kernels.fast.FastState`. Both satisfy :class:`KernelState`.
"""

from __future__ import annotations

from typing import Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

__all__ = ["WINNER_RULES", "Kernel", "KernelState"]

WINNER_RULES = ("soft", "argmax", "min_distance", "soft_mean")
"""How the winner is chosen: ``"soft"`` (argmax of the Gaussian-smoothed activation, the
paper), ``"argmax"``, ``"min_distance"`` (``argmin |vec(x y^T) - w_k|``), ``"soft_mean"``
(the soft rule with the smoothed activation divided by the window's weight inside the map, so
that border units are not handicapped)."""


class KernelState(Protocol):
    """The weights of a map in a kernel's own layout; ``shape`` is ``(K, n_x, n_y)``."""

    @property
    def shape(self) -> tuple[int, ...]: ...


S = TypeVar("S", bound=KernelState)


class Kernel(Protocol[S]):
    """The functions of a kernel module (``S``: the type of its state).

    Shapes: weights ``(K, n_x, n_y)``; codes ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``;
    activations ``h`` ``(B, K)``; ``K`` map units on ``map_shape``, flattened in C order.
    """

    NAME: str
    """The backend's name (a member of :data:`sigmapi.kernels.BACKENDS`)."""

    def prepare(self, weights: NDArray[np.float64], tol: float = ...) -> S:
        """State from dense float64 weights (``tol``: truncation tolerance, 0 = exact)."""
        ...

    def export(self, state: S) -> NDArray[np.float64]:
        """Dense float64 weights ``(K, n_x, n_y)`` of ``state``."""
        ...

    def state_arrays(self, state: S) -> dict[str, NDArray[np.floating]]:
        """Arrays beyond the dense weights that restore ``state`` exactly (may be empty)."""
        ...

    def from_state_arrays(
        self,
        weights: NDArray[np.float64],
        arrays: dict[str, NDArray[np.floating]],
        tol: float = ...,
    ) -> S:
        """Inverse of :meth:`state_arrays`."""
        ...

    def activation(
        self, state: S, x: NDArray[np.floating], y: NDArray[np.floating]
    ) -> NDArray[np.float64]:
        """``h[b, k] = x_b^T W_k y_b``; ``(B, K)``."""
        ...

    def winners(
        self,
        state: S,
        h: NDArray[np.floating],
        map_shape: tuple[int, ...],
        rule: str,
        sigma: float,
        cut: int,
    ) -> NDArray[np.int64]:
        """Winning unit per row of ``h`` under ``rule`` (one of :data:`WINNER_RULES`)."""
        ...

    def train_block(
        self,
        state: S,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        sigmas: NDArray[np.floating],
        eps: NDArray[np.floating],
        *,
        map_shape: tuple[int, ...],
        winner_rule: str,
        soft_cut: int,
        threads: bool = False,
    ) -> NDArray[np.int64]:
        """``len(x0)`` learning iterations in place: winner of view 0 at ``sigmas[t]``,
        Kohonen update towards view 1 at rate ``eps[t]``. Returns the winners ``(T,)``.
        ``threads``: the kernel may use several threads (the result must not change)."""
        ...
