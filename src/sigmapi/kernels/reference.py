"""Reference kernel: dense NumPy, written to be read. The definition the tests trust.

Shapes: ``W`` is ``(K, n_x, n_y)`` (one Sigma-Pi weight per map unit and input pair), codes
``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)``, activations ``h`` ``(B, K)``; ``K`` map units on a
grid ``map_shape`` flattened in C order.

One learning iteration (Fig. 7 of the chapter; docs/algorithm.md):

1. ``h_k = x0^T W_k y0``                                    (:func:`activation`)
2. winner ``k*``: argmax of h smoothed over the map with a Gaussian of width sigma
   (:func:`soft_winner`), or plain argmax, or min distance ``argmax(2 h_k - |w_k|^2)``
3. ``a_k = exp(-|k - k*|^2 / (2 sigma^2))``, L2-normalised      (:func:`neighbourhood`)

On a periodic (toroidal) map, grid distances in steps 2 and 3 go the shorter way round.
4. ``w_kij += eps a_k (x1_i y1_j - w_kij)`` with the OTHER view   (:func:`kohonen_update`)

This module satisfies the kernel contract (:class:`sigmapi.kernels.base.Kernel`): its state
is the dense weight array ``W`` itself. It also offers the steps of the iteration one by one
(``smooth``, ``neighbourhood``, ``kohonen_update``), which the tests check by hand.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

from sigmapi.codes import grid_coordinates
from sigmapi.kernels.base import WINNER_RULES

__all__ = [
    "NAME",
    "activation",
    "export",
    "from_state_arrays",
    "kohonen_update",
    "neighbourhood",
    "prepare",
    "smooth",
    "sqnorms",
    "state_arrays",
    "train_block",
    "winners",
    "winners_of",
]

Array = NDArray[np.floating]
NAME = "reference"

# Activations of at most this many (sample x weight) products are formed at once.
_CHUNK_ELEMS = 2**24


def prepare(weights: NDArray[np.float64], tol: float = 0.0) -> NDArray[np.float64]:
    """Backend state from float64 weights ``(K, n_x, n_y)``: here a float64 copy.

    ``tol`` (the fast kernel's truncation tolerance) has no meaning here: this kernel is exact.
    """
    return np.array(weights, dtype=np.float64, copy=True)


def export(state: NDArray[np.float64]) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)`` from backend state."""
    return np.asarray(state, dtype=np.float64)


def state_arrays(state: NDArray[np.float64]) -> dict[str, NDArray[np.floating]]:
    """Arrays beyond the dense weights that restore the state exactly: none here."""
    return {}


def from_state_arrays(
    shape: tuple[int, int, int], arrays: dict[str, NDArray[np.floating]], tol: float = 0.0
) -> NDArray[np.float64]:
    """Inverse of :func:`state_arrays`: this kernel has no state beyond the weights."""
    raise ValueError("the reference kernel has no backend state; load its weights instead")


def sqnorms(W: Array) -> NDArray[np.float64]:
    """``|w_k|^2 = sum_ij W[k, i, j]^2`` of every unit; ``(K,)``."""
    return np.einsum("kij,kij->k", W, W)


def activation(W: Array, x: Array, y: Array) -> NDArray[np.float64]:
    """Sigma-Pi activations ``h[b, k] = sum_ij W[k, i, j] x[b, i] y[b, j]``; ``(B, K)``."""
    k, nx, ny = W.shape
    wf = W.reshape(k, nx * ny)
    b = x.shape[0]
    rows = max(1, _CHUNK_ELEMS // (nx * ny))
    out = np.empty((b, k), dtype=np.float64)
    for s in range(0, b, rows):
        xy = np.einsum("bi,bj->bij", x[s : s + rows], y[s : s + rows]).reshape(-1, nx * ny)
        out[s : s + rows] = xy @ wf.T
    return out


@functools.lru_cache(maxsize=16)
def _coords(map_shape: tuple[int, ...]) -> NDArray[np.float64]:
    coords = grid_coordinates(map_shape)
    coords.flags.writeable = False
    return coords


def _grid_offsets(n: int, periodic: bool) -> NDArray[np.int64]:
    """``|i - j|`` between the units of an axis of ``n``; on a ring the shorter way round."""
    d = np.abs(np.arange(n)[:, None] - np.arange(n)[None, :])
    return np.minimum(d, n - d) if periodic else d


def _smoothing_matrix(n: int, sigma: float, cut: int, periodic: bool) -> NDArray[np.float64]:
    d = _grid_offsets(n, periodic)
    g = np.exp(-(d.astype(np.float64) ** 2) / (2.0 * sigma**2))
    g[np.abs(d) > cut] = 0.0
    return g


def smooth(
    h: Array, map_shape: tuple[int, ...], sigma: float, cut: int, periodic: bool = False
) -> NDArray[np.float64]:
    """Convolve activations ``(B, K)`` over the map grid with a Gaussian of width ``sigma``.

    Summed over a window of ``cut`` units each way along every axis (the authors' script:
    cut = 15). On a bounded map (the paper) the window stops at the border; on a ``periodic``
    map it wraps around, and every unit of the window counts once, at its distance the
    shorter way round. Separable: one matrix product per map axis.
    """
    b = h.shape[0]
    g = np.asarray(h, dtype=np.float64).reshape((b, *map_shape))
    for axis, n in enumerate(map_shape):
        m = _smoothing_matrix(n, sigma, cut, periodic)
        g = np.moveaxis(np.tensordot(g, m, axes=([axis + 1], [1])), -1, axis + 1)
    return g.reshape(b, -1)


def winners(
    W: Array,
    h: Array,
    map_shape: tuple[int, ...],
    rule: str,
    sigma: float,
    cut: int,
    periodic: bool = False,
) -> NDArray[np.int64]:
    """Winning unit per row of activations ``h`` ``(B, K)``; ``(B,)`` flat indices.

    ``rule``: ``"soft"`` argmax of the Gaussian-smoothed activation (the paper's rule),
    ``"argmax"`` plain argmax, ``"min_distance"`` ``argmin |vec(x y^T) - w_k|`` written as
    ``argmax(2 h_k - |w_k|^2)`` (exact for unit-length data), ``"soft_mean"`` the soft rule
    divided by the smoothing weight inside the map. ``periodic``: the map wraps around (the
    smoothing window too; "soft" and "soft_mean" then differ by a constant factor). Ties go
    to the lowest index.
    """
    if rule == "soft":
        return np.argmax(smooth(h, map_shape, sigma, cut, periodic), axis=1)
    if rule == "soft_mean":
        ones = np.ones((1, int(np.prod(map_shape))))
        inside = smooth(ones, map_shape, sigma, cut, periodic)
        return np.argmax(smooth(h, map_shape, sigma, cut, periodic) / inside, axis=1)
    if rule == "argmax":
        return np.argmax(h, axis=1)
    if rule == "min_distance":
        wn = sqnorms(W)
        return np.argmax(2.0 * h - wn[None, :], axis=1)
    raise ValueError(f"rule must be one of {WINNER_RULES}, got {rule!r}")


def winners_of(
    W: Array,
    x: Array,
    y: Array,
    map_shape: tuple[int, ...],
    rule: str,
    sigma: float,
    cut: int,
    periodic: bool = False,
) -> NDArray[np.int64]:
    """Winning unit of each pair ``(x_b, y_b)``: :func:`winners` of :func:`activation`."""
    return winners(W, activation(W, x, y), map_shape, rule, sigma, cut, periodic)


def neighbourhood(
    winner: NDArray[np.int64], map_shape: tuple[int, ...], sigma: float, periodic: bool = False
) -> NDArray[np.float64]:
    """Gaussian neighbourhood around each winner, L2-normalised; ``(B,)`` -> ``(B, K)``.

    ``a_k = exp(-|g_k - g_k*|^2 / (2 sigma^2)) / norm`` with grid coordinates ``g``; on a
    ``periodic`` map each axis's difference is taken the shorter way round the ring.
    """
    coords = _coords(map_shape)
    diff = np.abs(coords[None, :, :] - coords[np.asarray(winner)][:, None, :])
    if periodic:
        n = np.asarray(map_shape, dtype=np.float64)
        diff = np.minimum(diff, n - diff)
    d2 = (diff**2).sum(axis=2)
    a = np.exp(-d2 / (2.0 * sigma**2))
    return a / np.linalg.norm(a, axis=1, keepdims=True)


def kohonen_update(W: Array, a: Array, x1: Array, y1: Array, eps: float) -> None:
    """In place: ``W_k <- W_k + eps a_k (x1 y1^T - W_k)`` for one sample; ``a`` is ``(K,)``."""
    ea = (eps * a)[:, None, None]
    W *= 1.0 - ea
    W += ea * np.outer(x1, y1)[None, :, :]


def train_block(
    W: Array,
    x0: Array,
    y0: Array,
    x1: Array,
    y1: Array,
    sigmas: Array,
    eps: Array,
    *,
    map_shape: tuple[int, ...],
    winner_rule: str,
    soft_cut: int,
    threads: bool = False,
    periodic: bool = False,
) -> NDArray[np.int64]:
    """Run ``len(x0)`` learning iterations in order, updating ``W`` in place.

    Iteration ``t`` finds the winner of view ``(x0[t], y0[t])`` at width ``sigmas[t]`` (rule
    ``winner_rule``, smoothing window ``soft_cut``) and learns view ``(x1[t], y1[t])`` with
    rate ``eps[t]``. Returns the winners ``(T,)``. ``threads`` is ignored: this kernel is
    written to be read, on one thread. ``periodic``: every map axis wraps around (a ring in
    1-D, a torus in 2-D), in the winner's smoothing and in the neighbourhood.
    """
    t_total = x0.shape[0]
    out = np.empty(t_total, dtype=np.int64)
    for t in range(t_total):
        h = activation(W, x0[t : t + 1], y0[t : t + 1])
        k = winners(W, h, map_shape, winner_rule, float(sigmas[t]), soft_cut, periodic)
        a = neighbourhood(k, map_shape, float(sigmas[t]), periodic)[0]
        kohonen_update(W, a, x1[t], y1[t], float(eps[t]))
        out[t] = k[0]
    return out
