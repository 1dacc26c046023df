# Over 400 lines: one kernel (its compiled helpers, three training drivers, its class).
"""Fast CPU kernel: numba, sparse codes, lazy decay, parallel over map units.

Computes the same learning iteration as :mod:`sigmapi.kernels.reference` (the definition),
using the structure of the problem:

- **Sparse codes.** The codes are Gaussian hills, so the outer product ``x y^T`` of a view has
  few non-negligible entries. Entries with ``|x_i y_j| <= tol * max|x| * max|y|`` are skipped,
  in the activation and in the update: a 4-D ball of pairs around the peak, a small share
  of the ``n_x n_y`` pairs for narrow codes (docs/algorithm.md counts them at paper-2d).
- **Lazy decay.** Unit ``k`` stores ``W_k = s_k V_k`` with a scale ``s_k``. The Kohonen update
  ``W_k <- (1 - eps a_k) W_k + eps a_k x' y'^T`` becomes ``s_k <- s_k (1 - eps a_k)`` (O(1))
  plus the sparse ``V_k <- V_k + (eps a_k / s_k) x' y'^T``. Before ``s_k`` falls below
  ``2**-50`` the decay is folded into ``V_k`` and ``s_k`` reset to 1.
- **Sparse neighbourhood.** Units with ``a_k <= tol * max_k a_k`` get no additive update
  (their decay, being O(1), is still applied exactly).
- **float32 storage** of ``V`` (accumulation in float64), laid out ``(n_x * n_y, K)`` so that
  one input pair touches the weights of all units contiguously.
- **Vectorised loops over units.** Every loop over a range of units runs over array slices
  indexed from 0, which LLVM turns into SIMD code (a loop indexed from ``k0`` keeps the
  wrap-around check of possibly negative indices and stays scalar, with the same
  arithmetic). The activation takes four input pairs per pass over the units.
- **Parallel over units**, in fixed chunks: every unit's arithmetic is the same whatever the
  number of threads, so results do not depend on it (no reductions across units).

``tol = 0`` is the exact mode: no truncation and float64 storage, matching the reference to
float64 rounding (used by the tests). What larger ``tol`` costs in winners and weights is
measured in ``benchmarks/README.md`` (kernel tolerance table).

State (:class:`FastState`): ``raw`` ``(n_x * n_y, K)`` (float32, or float64 when exact),
``scale`` ``(K,)`` and ``sqnorm`` ``(K,)`` = ``sum_p raw[p, k]**2`` (tracked incrementally for
the ``min_distance`` rule; ``|w_k|^2 = scale_k^2 sqnorm_k``). A model file stores all three
(:meth:`FastKernel.file_arrays`, the layout of :mod:`sigmapi.kernels.columns`, which reads
without numba), so a saved model continues bit for bit on this backend. The rules are those of
:mod:`sigmapi.rules`; their compiled forms are :func:`_neighbourhood` (the neighbourhood),
:func:`_unit_chunk` (the Kohonen update as lazy decay) and ``_rows._winner`` (the winner
rules of :data:`COMPILED`).

References
----------
C. Weber and S. Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007)
2552-2560.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numba
import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.kernels import _refining, _rows, columns
from sigmapi.kernels._rows import _pairs, _winner, activate, axis_distance, gaussian, prefetch
from sigmapi.kernels.base import FileArrays, KernelBase, check_codes, check_steps
from sigmapi.rules import WinnerRule, winner_rule
from sigmapi.rules import trace as trace_rule
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.refinement import Sums, assignment

__all__ = ["COMPILED", "KERNEL", "NAME", "FastKernel", "FastState"]

NAME = "fast"

RENORM = 2.0**-50
"""A unit's scale is folded into its stored weights before it falls below this."""

CHUNK = 32
"""Map units per parallel work item (a multiple of 16: whole cache lines of float32)."""

PARALLEL_MIN_WORK = 1 << 18
"""With ``threads=True`` (``SOMConfig.threads``), training uses threads when ``K * n_x * n_y``
is at least this; below it, synchronising the threads costs more than it saves.

Off by default: one learning step is little work between two synchronisations, so on a
busy machine a descheduled worker thread stalls every step (the ``fast-threads`` variant of
``benchmarks/bench_bandwidth.py`` measures it). The batched :meth:`FastKernel.activation` (one
synchronisation per call) always uses all threads.
"""

NO_GATES = np.empty((0, 0))
"""The gates of an ungated training block: :func:`_train` learns with the plain neighbourhood."""

SERIAL_ROWS = 16
"""Inference calls (:meth:`~FastKernel.activation`, :meth:`~FastKernel.winners_of`) with at
most this many rows run in the caller's thread on scratch memory kept in the state (no thread
start-up, no allocation but the result); larger batches run in parallel over blocks of rows."""

PREFETCH_AHEAD = 8
"""Inference prefetches the weight row of the input pair this many pairs ahead (0: off)."""

TRAIN_PREFETCH_AHEAD = 8
"""Training prefetches the weight row of the input pair this many pairs ahead (0: off), in
the update and in the activation pass (benchmarks/README.md: its effect)."""

PREFETCH_MIN_BYTES = 1 << 21
"""Prefetching is used only for weights of at least this many bytes (about a core's L2
cache): weights that stay in cache gain nothing from it and pay its instructions, while
weights beyond the caches gain (the ``fast-noprefetch`` variant of
``benchmarks/bench_bandwidth.py`` measures both)."""


def _ahead(state: FastState, ahead: int) -> int:
    """``ahead`` if ``state``'s weights are large enough to gain from prefetching, else 0."""
    return ahead if state.raw.nbytes >= PREFETCH_MIN_BYTES else 0


COMPILED = {
    "soft": _rows.SOFT,
    "argmax": _rows.ARGMAX,
    "min_distance": _rows.MIN_DISTANCE,
    "soft_mean": _rows.SOFT_MEAN,
}
"""The winner rules this kernel computes, by name -> code of their compiled form in
:func:`sigmapi.kernels._rows._winner`: the one place where rule objects become codes."""


def _rule_code(rule: WinnerRule | str, field: str = "rule") -> tuple[WinnerRule, int]:
    """The rule object and its compiled code; a ConfigError if it has no compiled form."""
    r = winner_rule(rule, field)
    if r.name not in COMPILED:
        raise ConfigError(
            f"{field} {r.name!r} has no compiled form in the fast kernel (it computes "
            f"{tuple(COMPILED)}); use backend='reference', or add the rule to fast.COMPILED"
        )
    return r, COMPILED[r.name]


@dataclass
class FastState:
    """Weights of the fast kernel: ``W[k] = scale[k] * raw[:, k].reshape(n_x, n_y)``.

    Attributes
    ----------
    raw : ndarray, shape (n_x * n_y, K)
        Unscaled weights, float32 (float64 in exact mode, ``tol == 0``).
    scale : ndarray, shape (K,)
        Per-unit scale factors (float64).
    sqnorm : ndarray, shape (K,)
        ``sum_p raw[p, k]**2`` (float64): exact after :meth:`FastKernel.prepare`, tracked
        through updates while training with the ``min_distance`` rule (the only rule that needs it).
    norms_valid : bool
        Whether ``sqnorm`` is current; if not, it is recomputed when needed.
    tol : float
        Relative truncation tolerance of codes and neighbourhoods (0 = exact).
    shape : tuple of int
        ``(K, n_x, n_y)``.

    The state also keeps the scratch memory of serial inference (:meth:`scratch`); it holds no
    information about the weights, so training never makes it stale.
    """

    raw: NDArray[np.floating]
    scale: NDArray[np.float64]
    sqnorm: NDArray[np.float64]
    tol: float
    shape: tuple[int, int, int]
    norms_valid: bool = True
    _scratch: tuple[NDArray[Any], ...] | None = field(default=None, repr=False, compare=False)

    def scratch(self) -> tuple[NDArray[Any], ...]:
        """Work arrays of one row at a time ``(jb, pi, pv, acc, h, t1, t2)``, made once."""
        if self._scratch is None:
            k, nx, ny = self.shape
            n = nx * ny
            self._scratch = (
                np.empty(ny, dtype=np.int64),
                np.empty(n, dtype=np.int64),
                np.empty(n),
                *(np.empty(k) for _ in range(4)),
            )
        return self._scratch

    def refresh_norms(self) -> None:
        """Recompute ``sqnorm`` exactly from ``raw`` if it is stale."""
        if not self.norms_valid:
            self.sqnorm[:] = columns.sqnorms(self.raw)
            self.norms_valid = True


# ---------------------------------------------------------------------------- state


def _storage_dtype(tol: float) -> type[np.floating]:
    return np.float64 if tol == 0 else np.float32


def _check_tol(tol: float) -> float:
    return _validate.number("tol", tol, 0.0, 1.0, hi_open=True, fix="0 is the exact mode")


# ---------------------------------------------------------------------------- numba helpers


@njit(cache=True, nogil=True)
def _neighbourhood(winner, sigma, eps, tol, dims, strides, map_periodic, ea):
    """``ea[k] = eps * a_k``: the compiled form of
    :func:`sigmapi.rules.neighbourhood.neighbourhood` (L2-normalised Gaussian around
    ``winner``; ``map_periodic``: the map's axes are rings, distances go the shorter way).

    Returns the flat index range ``[lo, hi)`` from the first to the last unit with
    ``a_k > tol max a`` (on a ring these may lie at both ends: the range then covers the
    units between them too, whose update the caller skips below the threshold).
    """
    k_units = ea.shape[0]
    ssq = 0.0
    for k in range(k_units):
        d2 = 0.0
        for ax in range(dims.shape[0]):
            c = (k // strides[ax]) % dims[ax]
            cw = (winner // strides[ax]) % dims[ax]
            dc = axis_distance(abs(c - cw), dims[ax], map_periodic)
            d2 += float(dc) ** 2
        a = gaussian(d2, sigma)
        ea[k] = a
        ssq += a * a
    norm = np.sqrt(ssq)
    amax = 0.0
    for k in range(k_units):
        ea[k] = ea[k] / norm
        amax = max(amax, ea[k])
    thr = tol * amax
    lo = k_units
    hi = 0
    for k in range(k_units):
        if ea[k] > thr:
            lo = min(lo, k)
            hi = k + 1
    for k in range(k_units):
        ea[k] = eps * ea[k]
    return lo, hi


# left unformatted: its arguments in rows, as its calls pass them
@njit(cache=True, nogil=True)
def _unit_chunk(
    raw, scale, sqnorm, k0, k1, ea, thr, lo, hi,
    pi1, pv1, n1, pi0, pv0, n0, do_act, track, h, gain, acc, ahead,
):  # fmt: skip
    """Units ``[k0, k1)``: Kohonen update with pairs 1, then activation of pairs 0 into ``h``.

    ``ea[k] = eps a_k``; units in ``[lo, hi)`` with ``ea[k] > thr`` get the additive update.
    ``track``: keep ``sqnorm`` up to date. ``ahead``: prefetch the weight row of the pair this
    many pairs ahead (0: none). Touches only indices ``[k0, k1)`` of the per-unit arrays, so
    chunks can run in parallel.
    """
    n_pairs = raw.shape[0]
    for k in range(k0, k1):
        sn = scale[k] * (1.0 - ea[k])
        if sn < RENORM:  # fold the decay into the stored weights
            ss = 0.0
            for p in range(n_pairs):
                raw[p, k] = raw[p, k] * sn
                v = np.float64(raw[p, k])
                ss += v * v
            sqnorm[k] = ss
            sn = 1.0
        scale[k] = sn
        gain[k] = ea[k] / sn if (ea[k] > thr and lo <= k < hi) else 0.0
    u0 = max(lo, k0)
    u1 = min(hi, k1)
    if u0 < u1 and n1 > 0:
        # loops over slices from 0, so that LLVM vectorises them (see _rows.activate)
        g = gain[u0:u1]
        m = u1 - u0
        for q in range(min(ahead, n1)):
            prefetch(raw, pi1[q], u0, u1)
        if track:
            a = acc[u0:u1]
            for k in range(m):
                a[k] = 0.0
            for q in range(n1):
                if ahead > 0 and q + ahead < n1:
                    prefetch(raw, pi1[q + ahead], u0, u1)
                row = raw[pi1[q], u0:u1]
                val = pv1[q]
                for k in range(m):
                    # np.float64, not float(): numba types float() of a float32 as float32,
                    # which made these squares float32 (tiny weights late in long runs then
                    # gave denormal products, which the CPU computes far more slowly)
                    old = np.float64(row[k])
                    row[k] = old + g[k] * val
                    new = np.float64(row[k])
                    a[k] += new * new - old * old
            sq = sqnorm[u0:u1]
            for k in range(m):
                sq[k] += a[k]
        else:
            for q in range(n1):
                if ahead > 0 and q + ahead < n1:
                    prefetch(raw, pi1[q + ahead], u0, u1)
                row = raw[pi1[q], u0:u1]
                val = pv1[q]
                for k in range(m):
                    row[k] += g[k] * val
    if do_act:
        activate(raw, scale, pi0, pv0, n0, ahead, k0, k1, acc, h)


@njit(cache=True)
def _buffers(k_units, n_pairs, ny):
    """Work arrays of one training call: pair lists of both views, per-unit scratch."""
    return (
        np.empty(ny, dtype=np.int64),  # jb: kept y indices
        np.empty(n_pairs, dtype=np.int64),  # pi0, pv0: pairs of view 0
        np.empty(n_pairs),
        np.empty(n_pairs, dtype=np.int64),  # pi1, pv1: pairs of view 1
        np.empty(n_pairs),
        np.empty(k_units),  # h: activations
        np.zeros(k_units),  # ea: eps * neighbourhood
        np.empty(k_units),  # gain
        np.empty(k_units),  # acc
        np.empty(k_units),  # t1, t2: winner scratch
        np.empty(k_units),
    )


# left unformatted: its arguments in rows, as its calls pass them
@njit(cache=True, parallel=True)
def _train(
    raw, scale, sqnorm, x0, y0, x1, y1, sigmas, eps, gates, dims, strides, map_periodic, rule,
    cut, tol, out, track, threads, ahead,
):  # fmt: skip
    """The training driver: iterations in order; ``threads``: update the units in parallel
    chunks of :data:`CHUNK` (same arithmetic per unit, so the same result), else in one call
    (no parallel region is entered, so no thread is woken).

    ``gates`` ``(T, K)`` scales iteration ``t``'s neighbourhood per unit (reward-gated
    plasticity); an empty array (:data:`NO_GATES`) is the ungated rule. Truncation keeps the
    ungated threshold, ``tol`` times the winner's ``eps a``; a gated unit below it gets only
    its (exact) decay."""
    k_units = raw.shape[1]
    jb, pi0, pv0, pi1, pv1, h, ea, gain, acc, t1, t2 = _buffers(k_units, raw.shape[0], y0.shape[1])
    # typed int64 and bool, not literals: a constant passed straight to _unit_chunk is typed
    # as a literal, and numba compiles it once per mix of literals at its calls (16 in all)
    zero, yes = np.int64(0), np.bool_(True)
    n_chunks = (k_units + CHUNK - 1) // CHUNK
    n_iter = x0.shape[0]
    if n_iter == 0:
        return
    n0 = _pairs(x0[0], y0[0], tol, jb, pi0, pv0)
    if threads:
        for c in prange(n_chunks):
            # left unformatted: the arguments in the rows of the kernel's signature
            _unit_chunk(raw, scale, sqnorm, c * CHUNK, min(k_units, (c + 1) * CHUNK), ea, 1.0,
                        zero, zero, pi1, pv1, zero, pi0, pv0, n0, yes, track, h, gain, acc,
                        ahead)  # fmt: skip
    else:
        # left unformatted: the arguments in the rows of the kernel's signature
        _unit_chunk(raw, scale, sqnorm, zero, k_units, ea, 1.0, zero, zero,
                    pi1, pv1, zero, pi0, pv0, n0, yes, track, h, gain, acc, ahead)  # fmt: skip
    for t in range(n_iter):
        w = _winner(h, scale, sqnorm, rule, sigmas[t], cut, dims, strides, map_periodic, t1, t2)
        out[t] = w
        lo, hi = _neighbourhood(w, sigmas[t], eps[t], tol, dims, strides, map_periodic, ea)
        thr = tol * ea[w]
        if gates.shape[0] > 0:
            for k in range(k_units):
                ea[k] = ea[k] * gates[t, k]
        n1 = _pairs(x1[t], y1[t], tol, jb, pi1, pv1)
        more = t + 1 < n_iter
        if more:
            n0 = _pairs(x0[t + 1], y0[t + 1], tol, jb, pi0, pv0)
        if threads:
            for c in prange(n_chunks):
                # left unformatted: the arguments in the rows of the kernel's signature
                _unit_chunk(raw, scale, sqnorm, c * CHUNK, min(k_units, (c + 1) * CHUNK), ea,
                            thr, lo, hi, pi1, pv1, n1, pi0, pv0, n0, more, track, h, gain,
                            acc, ahead)  # fmt: skip
        else:
            # left unformatted: the arguments in the rows of the kernel's signature
            _unit_chunk(raw, scale, sqnorm, zero, k_units, ea, thr, lo, hi,
                        pi1, pv1, n1, pi0, pv0, n0, more, track, h, gain, acc, ahead)  # fmt: skip


# ---------------------------------------------------------------------------- public interface


@functools.lru_cache(maxsize=16)
def _grid(map_shape: tuple[int, ...], k_units: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Sizes and flat-index strides of the map's axes (read-only; cached: every call needs them)."""
    dims = np.asarray(map_shape, dtype=np.int64)
    if int(np.prod(dims)) != k_units:
        raise ValueError(
            f"the map {map_shape} holds {int(np.prod(dims))} units, the state {k_units}"
        )
    strides = np.ones_like(dims)
    for ax in range(len(map_shape) - 2, -1, -1):
        strides[ax] = strides[ax + 1] * dims[ax + 1]
    dims.flags.writeable = False
    strides.flags.writeable = False
    return dims, strides


def _run(
    state: FastState, rule: WinnerRule, steps: int, threads: bool
) -> tuple[NDArray[np.int64], bool, bool]:
    """What a training driver needs besides the data: the winners' array, whether it tracks
    the norms (the only rule that reads them keeps them current; the others leave them stale)
    and whether it uses threads (``threads`` asked, the map large enough,
    :data:`PARALLEL_MIN_WORK`, and numba has more than one)."""
    track = rule.needs_norms
    if track:
        state.refresh_norms()
    elif steps > 0:
        state.norms_valid = False
    k_units, nx, ny = state.shape
    big = k_units * nx * ny >= PARALLEL_MIN_WORK
    return (
        np.empty(steps, dtype=np.int64),
        track,
        bool(threads and big and numba.get_num_threads() > 1),
    )


def _codes(a: NDArray[np.floating], n: int, name: str) -> NDArray[np.float64]:
    arr = np.ascontiguousarray(a, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != n:
        raise ValueError(f"{name} must have shape (B, {n}), got {arr.shape}")
    return arr


class _Steps(NamedTuple):
    """The checked inputs of a learning driver (:func:`_steps`)."""

    rule: WinnerRule
    code: int
    dims: NDArray[np.int64]
    strides: NDArray[np.int64]
    codes: list[NDArray[np.float64]]
    sigmas: NDArray[np.float64]
    eps: NDArray[np.float64]
    n: int


def _steps(
    state: FastState,
    geometry: MapGeometry,
    winner_rule: WinnerRule | str,
    sigmas: NDArray[np.floating],
    eps: NDArray[np.floating],
    gates: NDArray[np.floating] | None = None,
    **codes: NDArray[np.floating],
) -> _Steps:
    """The map's grid, the rule and its code, and ``codes`` (named ``x...`` ``(n, n_x)``, the
    others ``(n, n_y)``), ``sigmas`` and ``eps`` (and ``gates``) checked for ``n`` steps."""
    k_units, nx, ny = state.shape
    dims, strides = _grid(geometry.shape, k_units)
    rule, code = _rule_code(winner_rule, "winner_rule")
    n = check_codes(state.shape, **codes)
    check_steps(n, k_units, sigmas=sigmas, eps=eps, gates=gates)
    arrays = [_codes(a, nx if k.startswith("x") else ny, k) for k, a in codes.items()]
    sg = np.ascontiguousarray(sigmas, dtype=np.float64)
    ep = np.ascontiguousarray(eps, dtype=np.float64)
    return _Steps(rule, code, dims, strides, arrays, sg, ep, n)


def _rows_of(
    state: FastState, x: NDArray[np.floating], y: NDArray[np.floating]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    _, nx, ny = state.shape
    xa = _codes(x, nx, "x")
    ya = _codes(y, ny, "y")
    if xa.shape[0] != ya.shape[0]:
        raise ValueError(
            f"x and y must have the same number of rows, got {xa.shape[0]}, {ya.shape[0]}"
        )
    return xa, ya


def _peak_order(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.int64]:
    """Rows sorted by the peaks of their codes (rows that share weight rows come together)."""
    return np.lexsort((np.argmax(np.abs(y), axis=1), np.argmax(np.abs(x), axis=1)))


# ---------------------------------------------------------------------------- stream learning

_trace_step: Any = njit(cache=True, nogil=True)(trace_rule.trace_step)
"""The trace rule's step, compiled from :func:`sigmapi.rules.trace.trace_step`."""


# left unformatted: its arguments in rows, as its calls pass them
@njit(cache=True, parallel=True)
def _train_stream(
    raw, scale, sqnorm, x, y, trace, primed, sigmas, eps, lam, dims, strides, map_periodic,
    rule, cut, tol, out, track, threads, ahead,
):  # fmt: skip
    """The stream driver (:meth:`~sigmapi.kernels.reference.ReferenceKernel.train_stream`):
    per frame, the Kohonen update with ``eps[t] * trace`` towards the frame (if ``primed``),
    the frame's activation on the updated weights (one pass over the units,
    :func:`_unit_chunk`), its winner and neighbourhood, then the trace in place. Units with
    ``eps trace_k`` at most ``tol`` of the largest get no additive update. Returns whether the
    trace now exists."""
    k_units = raw.shape[1]
    jb, pi, pv, _, _, h, ea, gain, acc, t1, t2 = _buffers(k_units, raw.shape[0], y.shape[1])
    # typed int64 and bool, not literals: a constant passed straight to _unit_chunk is typed
    # as a literal, and numba compiles it once per mix of literals at its calls (16 in all)
    zero, yes = np.int64(0), np.bool_(True)
    a = np.empty(k_units)
    n_chunks = (k_units + CHUNK - 1) // CHUNK
    for t in range(x.shape[0]):
        n = _pairs(x[t], y[t], tol, jb, pi, pv)
        lo = k_units
        hi = zero
        thr = 1.0
        n1 = zero
        if primed:
            top = 0.0
            for k in range(k_units):
                ea[k] = eps[t] * trace[k]
                top = max(top, ea[k])
            thr = tol * top
            for k in range(k_units):
                if ea[k] > thr:
                    lo = min(lo, k)
                    hi = np.int64(k + 1)
            n1 = n
        else:
            for k in range(k_units):
                ea[k] = 0.0
        if threads:
            for c in prange(n_chunks):
                # left unformatted: the arguments in the rows of the kernel's signature
                _unit_chunk(raw, scale, sqnorm, c * CHUNK, min(k_units, (c + 1) * CHUNK), ea,
                            thr, lo, hi, pi, pv, n1, pi, pv, n, yes, track, h, gain, acc,
                            ahead)  # fmt: skip
        else:
            # left unformatted: the arguments in the rows of the kernel's signature
            _unit_chunk(raw, scale, sqnorm, zero, k_units, ea, thr, lo, hi,
                        pi, pv, n1, pi, pv, n, yes, track, h, gain, acc, ahead)  # fmt: skip
        w = _winner(h, scale, sqnorm, rule, sigmas[t], cut, dims, strides, map_periodic, t1, t2)
        out[t] = w
        _neighbourhood(w, sigmas[t], 1.0, tol, dims, strides, map_periodic, a)
        if primed:
            for k in range(k_units):
                trace[k] = _trace_step(trace[k], a[k], lam)
        else:
            for k in range(k_units):
                trace[k] = a[k]
            primed = True
    return primed


# ---------------------------------------------------------------------------- refinement


@njit(cache=True, nogil=True)
def _refine_sums(sums, mass, a, x1, y1, tol, jb, pi, pv):  # pragma: no cover - compiled
    """``sums[k, p] += a[b, k] * (x1_i y1_j)`` for the sparse pairs ``p = i n_y + j`` of
    every row ``b`` in order and the units with ``a[b, k] > tol max_k a[b, k]``; ``mass +=
    a[b]`` (the reference's arithmetic, :meth:`sigmapi.rules.BatchMean.accumulate`)."""
    k_units = a.shape[1]
    units = np.empty(k_units, dtype=np.int64)
    for b in range(a.shape[0]):
        top = 0.0
        for k in range(k_units):
            top = max(top, a[b, k])
        thr = tol * top
        nu = 0
        for k in range(k_units):
            if a[b, k] > thr:
                units[nu] = k
                nu += 1
        n = _pairs(x1[b], y1[b], tol, jb, pi, pv)
        for r in range(nu):
            k = units[r]
            ak = a[b, k]
            row = sums[k]
            for q in range(n):
                row[pi[q]] += ak * pv[q]
        for k in range(k_units):
            mass[k] += a[b, k]


# ---------------------------------------------------------------------------- the kernel


class FastKernel(KernelBase[FastState]):
    """The fast CPU kernel: a :class:`FastState` per map, the compiled drivers above, the
    generic scores of :class:`~sigmapi.kernels.base.KernelBase` (vectorised over a batch, as
    in the reference kernel) for :meth:`scores` and :meth:`winners`.

    Options: ``device="cpu"``; ``dtype`` None only (the storage follows ``tol``: float32,
    float64 in the exact mode ``tol = 0``).
    """

    NAME = NAME
    DTYPES = ()
    COMPILES = True

    def supports(self, rule: WinnerRule | str) -> bool:
        """Whether this kernel has the compiled form of winner rule ``rule`` (an object or
        name, :data:`COMPILED`)."""
        name = rule.name if isinstance(rule, WinnerRule) else rule
        return name in COMPILED

    # ------------------------------------------------------------------ state

    def prepare(self, weights: NDArray[np.float64], tol: float = 1e-6) -> FastState:
        """Backend state from dense weights ``(K, n_x, n_y)``; ``tol``: the relative
        truncation tolerance in [0, 1), 0 the exact mode (float64 storage)."""
        tol = _check_tol(tol)
        w = np.asarray(weights, dtype=np.float64)
        if w.ndim != 3:
            raise ValueError(f"weights must have shape (K, n_x, n_y), got {w.shape}")
        k, nx, ny = w.shape
        raw = np.ascontiguousarray(w.reshape(k, nx * ny).T, dtype=_storage_dtype(tol))
        return FastState(raw, np.ones(k), columns.sqnorms(raw), tol, (k, nx, ny))

    def memory_bytes(self, shape: tuple[int, int, int], tol: float = 1e-6) -> int:
        """Bytes of the state of weights of ``shape``: ``raw`` in float32 (float64 when
        exact)."""
        itemsize = np.dtype(_storage_dtype(_check_tol(tol))).itemsize
        return itemsize * int(np.prod(shape, dtype=np.int64))

    def export(self, state: FastState) -> NDArray[np.float64]:
        """Dense float64 weights ``(K, n_x, n_y)``: ``scale[k] * raw[:, k]``."""
        return columns.columns_to_dense(state.raw, state.scale, state.shape)

    def max_abs(self, state: FastState) -> float:
        """Largest ``|w_kij| = scale_k |raw[p, k]|``, without forming the dense weights."""
        return columns.columns_top(state.raw, state.scale, state.shape)

    def file_arrays(self, state: FastState) -> FileArrays:
        """What a model file stores: ``state_raw``, ``state_scale`` and, if current,
        ``state_sqnorm`` (:mod:`sigmapi.kernels.columns`), so that a saved model continues
        bit for bit on this backend."""
        sq = state.sqnorm if state.norms_valid else None
        return columns.to_file(state.raw, state.scale, sq)

    def file_weights(self, shape: tuple[int, int, int], arrays: FileArrays) -> NDArray[np.float64]:
        """Dense float64 weights of what :meth:`file_arrays` wrote (``raw x scale``)."""
        return columns.file_weights(shape, arrays)

    def weight_columns(
        self, shape: tuple[int, int, int], arrays: FileArrays
    ) -> tuple[NDArray[np.floating], NDArray[np.float64]]:
        """The columns :meth:`file_arrays` wrote, as they are."""
        raw, scale, _ = columns.read_file(shape, arrays)
        return raw, scale

    def pair_cutoff(self, tol: float) -> float:
        """``tol``: the sparse codes keep the values above ``tol`` times the largest."""
        return float(tol)

    def from_file_arrays(
        self, shape: tuple[int, int, int], arrays: FileArrays, tol: float = 1e-6
    ) -> FastState:
        """The state :meth:`file_arrays` wrote, for weights of ``shape`` ``(K, n_x, n_y)``
        (also from a version-1 file, whose ``weights`` must agree with ``raw x scale``).

        Raises ``ValueError`` if the arrays are missing, do not fit ``shape`` and ``tol``, or
        are not finite (scales must be > 0; ``sqnorm`` must agree with ``raw`` to 1e-6
        relative).
        """
        tol = _check_tol(tol)
        raw, scale, sq = columns.read_file(shape, arrays)
        dtype = _storage_dtype(tol)
        if raw.dtype != dtype:
            raise ValueError(f"raw must be {np.dtype(dtype).name} for tol={tol}, got {raw.dtype}")
        exact = columns.sqnorms(raw)
        if sq is None:
            sq = exact
        elif not np.allclose(sq, exact, rtol=1e-6, atol=1e-12 * float(exact.max(initial=0.0))):
            raise ValueError("sqnorm disagrees with raw")
        k, nx, ny = shape
        return FastState(
            np.ascontiguousarray(raw, dtype=dtype),
            np.ascontiguousarray(scale, dtype=np.float64),
            np.ascontiguousarray(sq, dtype=np.float64),
            tol,
            (int(k), int(nx), int(ny)),
            True,
        )

    def sqnorms(self, state: FastState) -> NDArray[np.float64]:
        """``|w_k|^2 = scale_k^2 sqnorm_k`` of every unit, ``(K,)``, from the tracked norms."""
        state.refresh_norms()
        return np.asarray(state.scale**2 * state.sqnorm)

    # ------------------------------------------------------------------ inference

    def activation(
        self, state: FastState, x: NDArray[np.floating], y: NDArray[np.floating]
    ) -> NDArray[np.float64]:
        """Sigma-Pi activations ``h[b, k] = x_b^T W_k y_b`` of a batch; ``(B, K)``.

        Sparse equivalent of the matrix product ``vec(x_b y_b^T) @ W^T``: each row costs
        ``K x (number of kept pairs)`` multiply-adds. Up to :data:`SERIAL_ROWS` rows run in
        the caller's thread; larger batches in parallel over rows (the same numbers either
        way).
        """
        xa, ya = _rows_of(state, x, y)
        h = np.empty((xa.shape[0], state.shape[0]))
        ahead = _ahead(state, PREFETCH_AHEAD)
        if xa.shape[0] <= SERIAL_ROWS:
            jb, pi, pv, acc, *_ = state.scratch()
            _rows.respond_rows(state.raw, state.scale, xa, ya, state.tol, ahead, jb, pi, pv, acc, h)
        else:
            _rows.respond_rows_parallel(
                state.raw, state.scale, xa, ya, state.tol, ahead, _peak_order(xa, ya), h
            )
        return h

    def winners_of(
        self,
        state: FastState,
        x: NDArray[np.floating],
        y: NDArray[np.floating],
        geometry: MapGeometry,
        rule: WinnerRule | str,
        sigma: float,
    ) -> NDArray[np.int64]:
        """Winning unit of each pair ``(x_b, y_b)``; ``(B,)``: activation and winner in one
        pass.

        The same winners as ``winners(state, activation(state, x, y), ...)`` (the compiled
        winner rule of training), without forming the ``(B, K)`` activations; serial up to
        :data:`SERIAL_ROWS` rows, else parallel over rows.
        """
        xa, ya = _rows_of(state, x, y)
        dims, strides = _grid(geometry.shape, state.shape[0])
        r, code = _rule_code(rule)
        if r.needs_norms:
            state.refresh_norms()
        out = np.empty(xa.shape[0], dtype=np.int64)
        # left unformatted: the arguments in the rows of the kernel's signature
        args = (state.raw, state.scale, state.sqnorm, xa, ya, state.tol,
                _ahead(state, PREFETCH_AHEAD), code,
                float(sigma), geometry.soft_cut, dims, strides, geometry.periodic)  # fmt: skip
        if xa.shape[0] <= SERIAL_ROWS:
            jb, pi, pv, acc, h, t1, t2 = state.scratch()
            _rows.winners_rows(*args, jb, pi, pv, acc, h, t1, t2, out)
        else:
            _rows.winners_rows_parallel(*args, _peak_order(xa, ya), out)
        return out

    # ------------------------------------------------------------------ learning

    def train_block(
        self,
        state: FastState,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        sigmas: NDArray[np.floating],
        eps: NDArray[np.floating],
        *,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        gates: NDArray[np.floating] | None = None,
        threads: bool = False,
    ) -> NDArray[np.int64]:
        """Run ``len(x0)`` learning iterations in order, updating ``state`` in place (as
        :meth:`sigmapi.kernels.reference.ReferenceKernel.train_block`, gates included:
        iteration ``t`` updates unit ``k`` with ``eps[t] gates[t, k] a_k``). Returns the
        winners ``(T,)``.

        ``threads``: update the units on numba's threads (the same result) when the map is
        large enough (:data:`PARALLEL_MIN_WORK`) and numba has more than one thread.
        """
        st = _steps(state, geometry, winner_rule, sigmas, eps, gates, x0=x0, y0=y0, x1=x1, y1=y1)
        gt = NO_GATES if gates is None else np.ascontiguousarray(gates, dtype=np.float64)
        out, track, parallel = _run(state, st.rule, st.n, threads)
        driver: Any = _train  # a numba dispatcher (its stubs do not know the signature)
        # left unformatted: the arguments in the rows of the kernel's signature
        driver(state.raw, state.scale, state.sqnorm, *st.codes, st.sigmas, st.eps, gt, st.dims,
               st.strides, geometry.periodic, st.code, geometry.soft_cut, state.tol, out, track,
               bool(parallel), _ahead(state, TRAIN_PREFETCH_AHEAD))  # fmt: skip
        return out

    def train_stream(
        self,
        state: FastState,
        x: NDArray[np.floating],
        y: NDArray[np.floating],
        trace: NDArray[np.floating] | None,
        sigmas: NDArray[np.floating],
        eps: NDArray[np.floating],
        *,
        lam: float,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        threads: bool = False,
    ) -> tuple[NDArray[np.int64], NDArray[np.float64] | None]:
        """Learn the frames of a stream in order under the trace rule, updating ``state`` in
        place (as :meth:`sigmapi.kernels.reference.ReferenceKernel.train_stream`). Returns
        the winners ``(T,)`` and the trace ``(K,)`` after the last frame (None if there is
        none yet). ``threads``: as :meth:`train_block` (the same result on any number of
        threads).
        """
        st = _steps(state, geometry, winner_rule, sigmas, eps, x=x, y=y)
        k_units = state.shape[0]
        tr = np.zeros(k_units) if trace is None else np.array(trace, dtype=np.float64)
        if tr.shape != (k_units,):
            raise ValueError(f"trace must have shape ({k_units},), got {tr.shape}")
        out, track, parallel = _run(state, st.rule, st.n, threads)
        driver: Any = _train_stream  # a numba dispatcher
        # left unformatted: the arguments in the rows of the kernel's signature
        primed = driver(state.raw, state.scale, state.sqnorm, *st.codes, tr, trace is not None,
                        st.sigmas, st.eps, float(lam), st.dims, st.strides, geometry.periodic,
                        st.code, geometry.soft_cut, state.tol, out, track, bool(parallel),
                        _ahead(state, TRAIN_PREFETCH_AHEAD))  # fmt: skip
        return out, (tr if primed else None)

    # ------------------------------------------------------------------ refinement

    def refine_start(self, state: FastState, *, tol: float = 0.0) -> Sums:
        """Empty accumulators: sums ``(K, n_x * n_y)`` (a unit's pairs contiguous, unlike the
        weights' layout: a pair adds to few units), mass ``(K,)``. ``tol > 0`` (the config's
        ``refine_tol``; not in exact mode): the fast path, its sums float32."""
        k, nx, ny = state.shape
        fast_path = tol > 0 and state.tol > 0
        sums = np.zeros((k, nx * ny), dtype=np.float32 if fast_path else np.float64)
        return Sums(sums, np.zeros(k), tol=float(tol) if fast_path else 0.0)

    def _refine_winners(
        self,
        state: FastState,
        acc: Sums,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
    ) -> NDArray[np.int64]:
        """The winners of :meth:`winners_of` (at sigma 0), by the round's bounds
        (:mod:`sigmapi.kernels._refining`) where the rule allows: the index is made from the
        round's fixed weights on first use and kept in ``acc`` (it holds a copy of the weights
        by unit and tile, so a round holds the weights twice, beside its float64 sums). The
        exact mode (``tol = 0``) and the smoothing rules search in full."""
        _, code = _rule_code(winner_rule)
        if state.tol == 0 or code not in _refining.RULES:
            return self.winners_of(state, x0, y0, geometry, winner_rule, 0.0)
        xa, ya = _rows_of(state, x0, y0)
        _grid(geometry.shape, state.shape[0])  # checks the map holds the state's units
        state.refresh_norms()
        index = acc.index
        if not (isinstance(index, _refining.SearchIndex) and index.fits(state.raw, state.scale)):
            _, nx, ny = state.shape
            index = acc.index = _refining.build(
                state.raw, state.scale, acc.code_shapes or ((nx,), (ny,))
            )
        if acc.tol > 0:  # the fast path: its own cut, the best float32 score
            tol = max(state.tol, acc.tol)
            return _refining.search(index, state.raw, state.sqnorm, xa, ya, tol, code, False)
        return _refining.search(index, state.raw, state.sqnorm, xa, ya, state.tol, code)

    def refine_block(
        self,
        state: FastState,
        acc: Sums,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        *,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        sigma: float,
    ) -> NDArray[np.int64]:
        """Add ``len(x0)`` pairs to ``acc`` in order (as
        :meth:`sigmapi.kernels.reference.ReferenceKernel.refine_block`): winners of view 0 on
        the fixed state, then the sparse outer products of view 1 (pairs and units below
        ``tol`` of their peak skipped) added one pair after another, on one thread (the same
        sums for any blocks)."""
        _, nx, ny = state.shape
        k = self._refine_winners(state, acc, x0, y0, geometry, winner_rule)
        x1a, y1a = _codes(x1, nx, "x1"), _codes(y1, ny, "y1")
        tol = max(state.tol, acc.tol)  # acc.tol > 0: the fast path's own cut
        if sigma == 0:
            ncol = acc.code_shapes[1][-1] if acc.code_shapes else ny
            _refining.hard_sums(acc.sums, acc.mass, k, x1a, y1a, tol, ncol)
        else:
            a = assignment(k, geometry, float(sigma))
            jb, pi, pv = state.scratch()[:3]
            driver: Any = _refine_sums  # a numba dispatcher
            driver(acc.sums, acc.mass, np.ascontiguousarray(a), x1a, y1a, tol, jb, pi, pv)
        acc.pairs += int(x1a.shape[0])
        return k

    def refine_finish(self, state: FastState, acc: Sums) -> FastState:
        """The state of the new weights (:meth:`sigmapi.rules.BatchMean.finish`: ``sums /
        mass`` per unit that won, the weights kept elsewhere), stored as :meth:`prepare`
        stores weights (scales 1), computed in the kernel's layout."""
        raw = _refining.finish(state.raw, state.scale, acc.sums, acc.mass)
        return FastState(raw, np.ones(state.shape[0]), columns.sqnorms(raw), state.tol, state.shape)


KERNEL = FastKernel()
"""The fast kernel (what :data:`sigmapi.kernels.REGISTRY` holds as ``"fast"``)."""
