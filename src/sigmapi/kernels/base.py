"""The kernel contract: what every backend module offers.

A kernel is a module that satisfies :class:`Kernel`; its state (the weights in the
kernel's own layout) is opaque to the estimator, which only passes it back to the kernel.
The reference kernel's state is the dense weight array itself; the fast kernel's is a
:class:`~sigmapi.kernels.fast.FastState`. Both satisfy :class:`KernelState`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from sigmapi.rules import WinnerRule, winner_rule
from sigmapi.rules.winners import Scoring

__all__ = ["Kernel", "KernelState", "columns_to_dense", "columns_top", "rule_scores"]


def rule_scores(
    rule: WinnerRule | str,
    h: NDArray[np.floating],
    map_shape: tuple[int, ...],
    sigma: float,
    cut: int,
    map_periodic: bool,
    norms: Callable[[], NDArray[np.float64]],
) -> NDArray[np.float64]:
    """Scores ``(B, K)`` of activations ``h`` under ``rule`` (an object or its name) by the
    rule's own arithmetic; ``norms()`` gives the units' ``|w_k|^2``, called only for a rule
    that needs them. A kernel's winners of ``h`` are the row-wise argmax."""
    r = winner_rule(rule, "rule")
    at = Scoring(map_shape, sigma, cut, map_periodic, norms() if r.needs_norms else None)
    return r.scores(h, at)


def columns_top(
    raw: NDArray[np.floating], scale: NDArray[np.floating], shape: tuple[int, int, int]
) -> float:
    """Largest ``|W[k, i, j]|`` of the column layout with per-unit scales (see
    :func:`columns_to_dense`), without forming ``W``; NaN or inf if ``raw`` holds them.

    Raises ``ValueError`` if the shapes do not fit ``shape`` or a scale is not finite and > 0.
    """
    k, nx, ny = shape
    raw, scale = np.asarray(raw), np.asarray(scale)
    if raw.shape != (nx * ny, k) or raw.dtype.kind != "f":
        raise ValueError(f"raw must be float of shape {(nx * ny, k)}, got {raw.dtype} {raw.shape}")
    if scale.shape != (k,) or scale.dtype != np.float64:
        raise ValueError(f"scale must be float64 of shape ({k},), got {scale.dtype} {scale.shape}")
    if not np.all(np.isfinite(scale) & (scale > 0)):
        raise ValueError("scale must be finite and > 0")
    if raw.size == 0:
        return 0.0
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is the answer here
        return float((np.abs(raw).max(axis=0).astype(np.float64) * scale).max())


def columns_to_dense(
    raw: NDArray[np.floating], scale: NDArray[np.floating], shape: tuple[int, int, int]
) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)`` of the column layout with per-unit scales:
    ``W[k] = scale[k] * raw[:, k]``, ``raw`` ``(n_x * n_y, K)`` (the fast kernel's state, as
    a model file stores it; plain NumPy, so any backend can read such a file).
    """
    columns_top(raw[:0], scale, (shape[0], 0, 0))  # checks the scales
    k, nx, ny = shape
    if np.shape(raw) != (nx * ny, k):
        raise ValueError(f"raw must have shape {(nx * ny, k)}, got {np.shape(raw)}")
    w = np.asarray(raw).T.astype(np.float64) * scale[:, None]
    return np.ascontiguousarray(w.reshape(k, nx, ny))


class KernelState(Protocol):
    """The weights of a map in a kernel's own layout; ``shape`` is ``(K, n_x, n_y)``."""

    @property
    def shape(self) -> tuple[int, ...]: ...


S = TypeVar("S", bound=KernelState)


class Kernel(Protocol[S]):
    """The functions of a kernel module (``S``: the type of its state).

    Shapes: weights ``(K, n_x, n_y)``; codes ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``;
    activations ``h`` ``(B, K)``; ``K`` map units on ``map_shape``, flattened in C order.
    ``map_periodic``: the map's axes wrap around (grid distances the shorter way round).
    Winner rules are :class:`~sigmapi.rules.WinnerRule` objects or their names
    (:data:`sigmapi.rules.WINNER_RULES`).
    """

    NAME: str
    """The backend's name (a member of :data:`sigmapi.kernels.BACKENDS`)."""

    def supports(self, rule: WinnerRule | str) -> bool:
        """Whether the kernel trains and finds winners with ``rule``."""
        ...

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
        shape: tuple[int, int, int],
        arrays: dict[str, NDArray[np.floating]],
        tol: float = ...,
    ) -> S:
        """Inverse of :meth:`state_arrays` for weights of ``shape`` ``(K, n_x, n_y)``."""
        ...

    def sqnorms(self, state: S) -> NDArray[np.float64]:
        """``|w_k|^2`` of every unit, ``(K,)`` (the ``min_distance`` rule's norms)."""
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
        rule: WinnerRule | str,
        sigma: float,
        cut: int,
        map_periodic: bool = ...,
    ) -> NDArray[np.int64]:
        """Winning unit per row of ``h`` under ``rule``."""
        ...

    def winners_of(
        self,
        state: S,
        x: NDArray[np.floating],
        y: NDArray[np.floating],
        map_shape: tuple[int, ...],
        rule: WinnerRule | str,
        sigma: float,
        cut: int,
        map_periodic: bool = ...,
    ) -> NDArray[np.int64]:
        """Winning unit of each pair ``(x_b, y_b)``, ``(B,)``: the same as ``winners`` of
        ``activation``, for one pair as fast as the kernel allows (no per-call preparation)."""
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
        winner_rule: WinnerRule | str,
        soft_cut: int,
        threads: bool = False,
        map_periodic: bool = False,
    ) -> NDArray[np.int64]:
        """``len(x0)`` learning iterations in place: winner of view 0 at ``sigmas[t]``,
        Kohonen update towards view 1 at rate ``eps[t]``. Returns the winners ``(T,)``.
        ``threads``: the kernel may use several threads (the result must not change).
        ``map_periodic``: every map axis wraps around (a ring in 1-D, a torus in 2-D)."""
        ...
