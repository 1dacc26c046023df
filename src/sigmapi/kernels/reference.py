"""Reference kernel: dense NumPy, written to be read. The definition the tests trust.

Shapes: ``W`` is ``(K, n_x, n_y)`` (one Sigma-Pi weight per map unit and input pair), codes
``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)``, activations ``h`` ``(B, K)``; ``K`` map units on a
grid ``map_shape`` flattened in C order.

One learning iteration (Fig. 7 of the chapter; docs/algorithm.md):

1. ``h_k = x0^T W_k y0``                                    (:func:`activation`)
2. winner ``k*`` under the winner rule: the rule object's arithmetic
   (:mod:`sigmapi.rules.winners`; the paper's: argmax of h smoothed over the map)
3. ``a_k = exp(-|k - k*|^2 / (2 sigma^2))``, L2-normalised      (:func:`neighbourhood`)
4. ``w_kij += eps a_k (x1_i y1_j - w_kij)`` with the OTHER view
   (:data:`sigmapi.rules.KOHONEN`)

On a periodic map (``map_periodic``), grid distances in steps 2 and 3 go the shorter way
round. Steps 2-4 are the rules' reference arithmetic (:mod:`sigmapi.rules`); this module
runs them in order on dense weights, so it computes every rule there is.

This module satisfies the kernel contract (:class:`sigmapi.kernels.base.Kernel`): its state
is the dense weight array ``W`` itself, and a model file holds it as ``weights``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import rules
from sigmapi.kernels.base import FileArrays, dense_file_weights, rule_scores
from sigmapi.rules import BATCH_MEAN, KOHONEN, WINNER_RULES, WinnerRule
from sigmapi.rules.neighbourhood import neighbourhood
from sigmapi.rules.refinement import Sums, assignment
from sigmapi.rules.trace import trace_step

__all__ = [
    "NAME",
    "activation",
    "export",
    "file_arrays",
    "file_weights",
    "from_file_arrays",
    "max_abs",
    "memory_bytes",
    "neighbourhood",
    "prepare",
    "refine_block",
    "refine_finish",
    "refine_start",
    "scores",
    "sqnorms",
    "supports",
    "train_block",
    "train_gated_block",
    "train_stream",
    "winners",
    "winners_of",
]

Array = NDArray[np.floating]
NAME = "reference"

# Activations of at most this many (sample x weight) products are formed at once.
_CHUNK_ELEMS = 2**24


def supports(rule: WinnerRule | str) -> bool:
    """Every winner rule: this kernel runs the rule objects' own arithmetic."""
    return isinstance(rule, WinnerRule) or rule in WINNER_RULES


def prepare(weights: NDArray[np.float64], tol: float = 0.0) -> NDArray[np.float64]:
    """Backend state from float64 weights ``(K, n_x, n_y)``: here a float64 copy.

    ``tol`` (the fast kernel's truncation tolerance) has no meaning here: this kernel is exact.
    """
    return np.array(weights, dtype=np.float64, copy=True)


def export(state: NDArray[np.float64]) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)`` from backend state."""
    return np.asarray(state, dtype=np.float64)


def memory_bytes(shape: tuple[int, int, int], tol: float = 0.0) -> int:
    """Bytes of the state of weights of ``shape``: the float64 weights."""
    return 8 * int(np.prod(shape, dtype=np.int64))


def max_abs(state: NDArray[np.float64]) -> float:
    """Largest ``|w_kij|`` (NaN if the weights hold NaN)."""
    return float(np.abs(state).max(initial=0.0))


def file_arrays(state: NDArray[np.float64]) -> FileArrays:
    """What a model file stores: the float64 ``weights`` ``(K, n_x, n_y)`` (a copy)."""
    return {"weights": np.array(state, dtype=np.float64)}


def file_weights(shape: tuple[int, int, int], arrays: FileArrays) -> NDArray[np.float64]:
    """The dense weights :func:`file_arrays` wrote (checked against ``shape``)."""
    return dense_file_weights(shape, arrays)


def from_file_arrays(
    shape: tuple[int, int, int], arrays: FileArrays, tol: float = 0.0
) -> NDArray[np.float64]:
    """The state :func:`file_arrays` wrote: a float64 copy of its ``weights``."""
    return prepare(file_weights(shape, arrays))


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


def scores(
    W: Array,
    h: Array,
    map_shape: tuple[int, ...],
    rule: WinnerRule | str,
    sigma: float,
    cut: int,
    map_periodic: bool = False,
) -> NDArray[np.float64]:
    """Per-unit scores ``(B, K)`` of activations ``h`` under ``rule`` (an object or its name,
    one of :data:`sigmapi.rules.WINNER_RULES`): the rule's own arithmetic, with the norms of
    ``W`` where it needs them; :func:`winners` is their row-wise argmax."""
    return rule_scores(rule, h, map_shape, sigma, cut, map_periodic, lambda: sqnorms(W))


def winners(
    W: Array,
    h: Array,
    map_shape: tuple[int, ...],
    rule: WinnerRule | str,
    sigma: float,
    cut: int,
    map_periodic: bool = False,
) -> NDArray[np.int64]:
    """Winning unit per row of activations ``h`` ``(B, K)``; ``(B,)`` flat indices.

    The argmax of :func:`scores`; ``map_periodic``: the map wraps around (the smoothing
    window too). Ties go to the lowest index.
    """
    s = scores(W, h, map_shape, rule, sigma, cut, map_periodic)
    return np.asarray(np.argmax(s, axis=1), dtype=np.int64)


def winners_of(
    W: Array,
    x: Array,
    y: Array,
    map_shape: tuple[int, ...],
    rule: WinnerRule | str,
    sigma: float,
    cut: int,
    map_periodic: bool = False,
) -> NDArray[np.int64]:
    """Winning unit of each pair ``(x_b, y_b)``: :func:`winners` of :func:`activation`."""
    return winners(W, activation(W, x, y), map_shape, rule, sigma, cut, map_periodic)


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
    winner_rule: WinnerRule | str,
    soft_cut: int,
    threads: bool = False,
    map_periodic: bool = False,
) -> NDArray[np.int64]:
    """Run ``len(x0)`` learning iterations in order, updating ``W`` in place.

    Iteration ``t`` finds the winner of view ``(x0[t], y0[t])`` at width ``sigmas[t]`` (rule
    ``winner_rule``, smoothing window ``soft_cut``) and learns view ``(x1[t], y1[t])`` with
    rate ``eps[t]`` (the Kohonen rule). Returns the winners ``(T,)``. ``threads`` is
    ignored: this kernel is written to be read, on one thread. ``map_periodic``: every map
    axis wraps around (a ring in 1-D, a torus in 2-D), in the winner's smoothing and in the
    neighbourhood.
    """
    return _learn(
        W, x0, y0, x1, y1, sigmas, eps, None, map_shape, winner_rule, soft_cut, map_periodic
    )


def _learn(
    W: Array,
    x0: Array,
    y0: Array,
    x1: Array,
    y1: Array,
    sigmas: Array,
    eps: Array,
    gates: Array | None,
    map_shape: tuple[int, ...],
    winner_rule: WinnerRule | str,
    soft_cut: int,
    map_periodic: bool,
) -> NDArray[np.int64]:
    """The iterations of :func:`train_block`; ``gates`` ``(T, K)`` scale iteration ``t``'s
    neighbourhood per unit (:func:`train_gated_block`), ``None`` is the ungated rule."""
    rule = rules.winner_rule(winner_rule, "winner_rule")
    t_total = x0.shape[0]
    out = np.empty(t_total, dtype=np.int64)
    for t in range(t_total):
        h = activation(W, x0[t : t + 1], y0[t : t + 1])
        k = winners(W, h, map_shape, rule, float(sigmas[t]), soft_cut, map_periodic)
        a = neighbourhood(k, map_shape, float(sigmas[t]), map_periodic)[0]
        KOHONEN.update(W, a if gates is None else a * gates[t], x1[t], y1[t], float(eps[t]))
        out[t] = k[0]
    return out


def train_gated_block(
    W: Array,
    x0: Array,
    y0: Array,
    x1: Array,
    y1: Array,
    sigmas: Array,
    eps: Array,
    gates: Array,
    *,
    map_shape: tuple[int, ...],
    winner_rule: WinnerRule | str,
    soft_cut: int,
    map_periodic: bool = False,
) -> NDArray[np.int64]:
    """:func:`train_block` with a gate per iteration and unit (reward-gated plasticity,
    :mod:`sigmapi.rules.gating`): iteration ``t`` learns with the neighbourhood
    ``a_k * gates[t, k]``, so ``w_k += eps[t] gates[t, k] a_k (x1_i y1_j - w_k)``.

    ``gates`` ``(T, K)`` in ``[0, 1]``: 0 leaves unit ``k`` as it was, 1 is the ungated rule.
    The winner is found on the weights as they are before iteration ``t``, as in
    :func:`train_block`. Returns the winners ``(T,)``.
    """
    g = np.asarray(gates, dtype=np.float64)
    return _learn(W, x0, y0, x1, y1, sigmas, eps, g, map_shape, winner_rule, soft_cut, map_periodic)


def train_stream(
    W: Array,
    x: Array,
    y: Array,
    trace: Array | None,
    sigmas: Array,
    eps: Array,
    *,
    lam: float,
    map_shape: tuple[int, ...],
    winner_rule: WinnerRule | str,
    soft_cut: int,
    threads: bool = False,
    map_periodic: bool = False,
) -> tuple[NDArray[np.int64], NDArray[np.float64] | None]:
    """Learn the frames ``(x[t], y[t])`` of a stream in order under the trace rule
    (:mod:`sigmapi.rules.trace`), updating ``W`` in place.

    Frame ``t``: if a trace exists (``trace`` ``(K,)`` from the frames before this call, or
    the one built from frames ``0 .. t-1``), the Kohonen update with rate ``eps[t]`` and the
    trace as neighbourhood towards frame ``t``; then the winner of frame ``t`` on the updated
    weights at width ``sigmas[t]``, its neighbourhood ``a`` and the next trace
    ``lam * trace + (1 - lam) * a`` (``a`` alone when there was none). ``eps[0]`` is unused
    when ``trace`` is None. Returns the winners ``(T,)`` and the trace after the last frame
    (a copy of ``trace`` when there are no frames: None stays None). At ``lam = 0`` the iterations
    are those of :func:`train_block` on the consecutive pairs ``(frame t, frame t + 1)``.
    ``threads`` is ignored (one thread).
    """
    rule = rules.winner_rule(winner_rule, "winner_rule")
    out = np.empty(x.shape[0], dtype=np.int64)
    tr = None if trace is None else np.array(trace, dtype=np.float64)
    for t in range(x.shape[0]):
        if tr is not None:
            KOHONEN.update(W, tr, x[t], y[t], float(eps[t]))
        h = activation(W, x[t : t + 1], y[t : t + 1])
        k = winners(W, h, map_shape, rule, float(sigmas[t]), soft_cut, map_periodic)
        a = neighbourhood(k, map_shape, float(sigmas[t]), map_periodic)[0]
        tr = a if tr is None else trace_step(tr, a, lam)
        out[t] = k[0]
    return out, tr


def refine_start(W: Array) -> Sums:
    """Empty accumulators of a refinement round: sums ``(K, n_x, n_y)`` and mass ``(K,)``."""
    k, nx, ny = W.shape
    return BATCH_MEAN.start((k, nx, ny))


def refine_block(
    W: Array,
    acc: Sums,
    x0: Array,
    y0: Array,
    x1: Array,
    y1: Array,
    *,
    map_shape: tuple[int, ...],
    winner_rule: WinnerRule | str,
    soft_cut: int,
    sigma: float,
    map_periodic: bool = False,
) -> NDArray[np.int64]:
    """Add ``len(x0)`` pairs to ``acc`` (:meth:`sigmapi.rules.BatchMean.accumulate`): winners
    of view 0 on the fixed ``W``, view 1's outer products weighted by
    :func:`~sigmapi.rules.refinement.assignment` at ``sigma``. Returns the winners."""
    k = winners_of(W, x0, y0, map_shape, winner_rule, 0.0, soft_cut, map_periodic)
    BATCH_MEAN.accumulate(acc, assignment(k, map_shape, float(sigma), map_periodic), x1, y1)
    return k


def refine_finish(W: Array, acc: Sums) -> NDArray[np.float64]:
    """The new weights (:meth:`sigmapi.rules.BatchMean.finish`)."""
    return BATCH_MEAN.finish(W, acc)
