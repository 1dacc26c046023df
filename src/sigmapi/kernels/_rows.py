"""Compiled helpers of the fast kernel that work on one input pair (one row) at a time.

- :func:`_pairs`: the sparse outer product ``x y^T`` of one view (the kept input pairs);
- :func:`_winner`: the winning unit of one activation vector under a winner rule (the
  compiled forms of the rules of :mod:`sigmapi.rules.winners`, by the codes below);
- :func:`prefetch`, :func:`prefetch_row`: ask the CPU to start loading weights before they are
  needed;
- the inference drivers: activations and winners of a batch of rows, serial (for one pair or
  a few: no thread start-up, scratch memory passed in) or parallel over blocks of rows.

The weights are the fast kernel's ``raw`` ``(n_x * n_y, K)`` with per-unit ``scale`` ``(K,)``
(:class:`sigmapi.kernels.fast.FastState`); one input pair's weights for all units are one
contiguous row. Every row's arithmetic is the same in the serial and the parallel drivers, so
batched and single calls give the same numbers, bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from sigmapi.rules import neighbourhood

__all__ = [
    "ARGMAX",
    "BLOCK_ROWS",
    "MIN_DISTANCE",
    "SOFT",
    "SOFT_MEAN",
    "axis_distance",
    "gaussian",
    "prefetch",
    "prefetch_row",
    "respond_rows",
    "respond_rows_parallel",
    "winners_rows",
    "winners_rows_parallel",
]

BLOCK_ROWS = 16
"""Rows per parallel work item of the batched drivers."""

SOFT, ARGMAX, MIN_DISTANCE, SOFT_MEAN = 0, 1, 2, 3
"""Codes of the winner rules :func:`_winner` computes (``sigmapi.kernels.fast.COMPILED`` maps
the rule objects to them); compiled in as constants."""

gaussian: Any = njit(cache=True, nogil=True)(neighbourhood.gaussian)
"""The map's Gaussian profile, compiled from :func:`sigmapi.rules.neighbourhood.gaussian`."""
axis_distance: Any = njit(cache=True, nogil=True)(neighbourhood.axis_distance)
"""Distance along a map axis, compiled from :func:`sigmapi.rules.neighbourhood.axis_distance`."""


@intrinsic
def _prefetch(typingctx: Any, arr: Any, row: Any, c0: Any, c1: Any) -> Any:
    """``prefetch(a, i, c0, c1)``: prefetch the cache lines of ``a[i, c0:c1]`` (2-D ``a``).

    A hint (LLVM's ``llvm.prefetch``, read, high locality): it changes no value. The weight
    rows of the kept input pairs are scattered over the weight matrix, so the hardware
    prefetcher cannot guess them; asking for the rows a few pairs ahead keeps several memory
    reads in flight instead of one.
    """
    sig = types.void(arr, row, c0, c1)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        intp = context.get_value_type(types.intp)
        first = context.cast(builder, args[2], signature.args[2], types.intp)
        stop = context.cast(builder, args[3], signature.args[3], types.intp)
        ptr = cgutils.get_item_pointer(context, builder, aryty, ary, [args[1], first])
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch")
        base = builder.bitcast(ptr, i8p)
        itemsize = ir.Constant(intp, aryty.dtype.bitwidth // 8)
        nbytes = builder.mul(builder.sub(stop, first), itemsize)
        zero, step = ir.Constant(intp, 0), ir.Constant(intp, 64)
        with cgutils.for_range_slice(builder, zero, nbytes, step) as (off, _):
            builder.call(fn, [builder.gep(base, [off]), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()

    return sig, codegen


prefetch: Any = _prefetch  # compiled code calls it as prefetch(a, i, c0, c1)


@njit(cache=True, nogil=True, inline="always")
def prefetch_row(raw, i):
    """Prefetch the whole row ``i`` of ``raw``."""
    prefetch(raw, i, 0, raw.shape[1])


@njit(cache=True, nogil=True)
def _pairs(x, y, tol, jbuf, pidx, pval):
    """Sparse outer product: pairs ``p = i * n_y + j`` with ``|x_i y_j| > tol max|x| max|y|``.

    Fills ``pidx``/``pval`` (length >= n_x n_y) and returns the count. ``jbuf``: scratch (n_y,).
    """
    nx = x.shape[0]
    ny = y.shape[0]
    mx = 0.0
    for i in range(nx):
        mx = max(mx, abs(x[i]))
    my = 0.0
    for j in range(ny):
        my = max(my, abs(y[j]))
    thr = tol * mx * my
    nj = 0
    for j in range(ny):
        if abs(y[j]) * mx > thr:
            jbuf[nj] = j
            nj += 1
    n = 0
    for i in range(nx):
        xi = x[i]
        if abs(xi) * my <= thr:
            continue
        base = i * ny
        for q in range(nj):
            # written without a branch (a pair is stored, and kept by counting it): whether
            # a pair passes the cut is hard to predict, and mispredictions cost more than
            # the stores; pidx and pval hold n_x n_y entries, so the store at n fits
            j = jbuf[q]
            v = xi * y[j]
            pidx[n] = base + j
            pval[n] = v
            n += abs(v) > thr
    return n


@njit(cache=True, nogil=True)
def _winner(h, scale, sqnorm, rule, sigma, cut, dims, strides, map_periodic, tmp, tmp2):
    """Winning unit of one activation vector ``h`` (K,) under the rule of code ``rule``;
    ties to the lowest index. The compiled forms of the reference rules (same units).

    ``map_periodic``: the map's axes are rings; the smoothing window wraps around and holds
    every unit once (offsets ``-(n-1)//2 .. n//2`` at most), at its distance the shorter way
    round.
    """
    k_units = h.shape[0]
    if rule == SOFT or rule == SOFT_MEAN:  # separable Gaussian smoothing, window +-cut
        for k in range(k_units):
            tmp[k] = h[k]
        cur = tmp
        nxt = tmp2
        for ax in range(dims.shape[0]):
            n = dims[ax]
            st = strides[ax]
            m = min(cut, n - 1)
            wts = np.empty(m + 1)
            for d in range(m + 1):
                wts[d] = gaussian(d * d, sigma)
            for k in range(k_units):
                c = (k // st) % n
                acc = 0.0
                norm = 0.0
                if map_periodic:
                    for o in range(-min(cut, (n - 1) // 2), min(cut, n // 2) + 1):
                        c2 = (c + o) % n
                        acc += cur[k + (c2 - c) * st] * wts[abs(o)]
                        norm += wts[abs(o)]
                else:
                    for c2 in range(max(0, c - m), min(n - 1, c + m) + 1):
                        acc += cur[k + (c2 - c) * st] * wts[abs(c2 - c)]
                        norm += wts[abs(c2 - c)]
                nxt[k] = acc / norm if rule == SOFT_MEAN else acc
            cur, nxt = nxt, cur
        best = 0
        for k in range(1, k_units):
            if cur[k] > cur[best]:
                best = k
        return best
    if rule == ARGMAX:
        best = 0
        for k in range(1, k_units):
            if h[k] > h[best]:
                best = k
        return best
    best = 0  # MIN_DISTANCE: argmax of 2 h_k - |w_k|^2
    bval = 2.0 * h[0] - scale[0] * scale[0] * sqnorm[0]
    for k in range(1, k_units):
        v = 2.0 * h[k] - scale[k] * scale[k] * sqnorm[k]
        if v > bval:
            best = k
            bval = v
    return best


@njit(cache=True, nogil=True)
def _respond_row(raw, scale, x, y, tol, ahead, jb, pi, pv, acc, h):
    """``h[k] = scale[k] sum_p raw[p, k] (x y^T)_p`` over the kept pairs ``p`` of one view.

    ``ahead``: prefetch the weight row of the pair this many pairs ahead (0: none).
    ``jb``, ``pi``, ``pv``, ``acc``: scratch for :func:`_pairs` and the float64 sums.
    """
    n = _pairs(x, y, tol, jb, pi, pv)
    activate(raw, scale, pi, pv, n, ahead, np.int64(0), raw.shape[1], acc, h)  # not a literal


@njit(cache=True, nogil=True)
def activate(raw, scale, pi, pv, n, ahead, k0, k1, acc, h):
    """Units ``[k0, k1)``: ``h[k] = scale[k] sum_q raw[pi[q], k] pv[q]`` over the ``n`` kept
    pairs, summed in float64 in ``acc``; prefetching the row ``ahead`` pairs on (0: none).
    Serves inference (:func:`_respond_row`) and training (``fast._unit_chunk``).

    Written for the vectoriser: the loops over units run over slices from index 0 (a loop from
    ``k0`` indexes with possibly negative numbers, whose wrap-around check keeps LLVM from
    vectorising it; ``benchmarks/README.md``), and each pass takes four pairs,
    so that a unit's sum stays in a register for four products. The sum is still taken pair
    after pair, ``(((acc + r0 v0) + r1 v1) + r2 v2) + r3 v3``: the same result, bit for bit,
    as one pair per pass.
    """
    a = acc[k0:k1]
    m = k1 - k0
    for k in range(m):
        a[k] = 0.0
    for q in range(min(ahead, n)):
        prefetch_row(raw, pi[q])
    q = 0
    while q + 4 <= n:
        if ahead > 0:
            for d in range(q + ahead, min(q + ahead + 4, n)):
                prefetch_row(raw, pi[d])
        r0, r1 = raw[pi[q], k0:k1], raw[pi[q + 1], k0:k1]
        r2, r3 = raw[pi[q + 2], k0:k1], raw[pi[q + 3], k0:k1]
        v0, v1, v2, v3 = pv[q], pv[q + 1], pv[q + 2], pv[q + 3]
        for k in range(m):
            a[k] = (((a[k] + r0[k] * v0) + r1[k] * v1) + r2[k] * v2) + r3[k] * v3
        q += 4
    for r in range(q, n):
        row = raw[pi[r], k0:k1]
        val = pv[r]
        for k in range(m):
            a[k] += row[k] * val
    hs = h[k0:k1]
    sc = scale[k0:k1]
    for k in range(m):
        hs[k] = sc[k] * a[k]


@njit(cache=True)
def _scratch(n_pairs, ny, k_units):
    """Scratch of one row at a time: ``jb, pi, pv`` for the pairs, ``acc, t1, t2`` per unit."""
    return (
        np.empty(ny, dtype=np.int64),
        np.empty(n_pairs, dtype=np.int64),
        np.empty(n_pairs),
        np.empty(k_units),
        np.empty(k_units),
        np.empty(k_units),
    )


@njit(cache=True)
def respond_rows(raw, scale, x, y, tol, ahead, jb, pi, pv, acc, h):
    """Serial activations ``h`` ``(B, K)`` of the rows of ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``."""
    for b in range(x.shape[0]):
        _respond_row(raw, scale, x[b], y[b], tol, ahead, jb, pi, pv, acc, h[b])


@njit(cache=True, parallel=True)
def respond_rows_parallel(raw, scale, x, y, tol, ahead, order, h):
    """:func:`respond_rows` in parallel blocks of :data:`BLOCK_ROWS` rows, visited in ``order``
    (rows with nearby code peaks together, so that the weight rows they share stay in cache)."""
    n_rows = x.shape[0]
    n_blocks = (n_rows + BLOCK_ROWS - 1) // BLOCK_ROWS
    for c in prange(n_blocks):
        jb, pi, pv, acc, _, _ = _scratch(raw.shape[0], y.shape[1], raw.shape[1])
        for r in range(c * BLOCK_ROWS, min(n_rows, (c + 1) * BLOCK_ROWS)):
            b = order[r]
            _respond_row(raw, scale, x[b], y[b], tol, ahead, jb, pi, pv, acc, h[b])


# left unformatted: its arguments in rows, as its calls pass them
@njit(cache=True)
def winners_rows(
    raw, scale, sqnorm, x, y, tol, ahead, rule, sigma, cut, dims, strides, map_periodic,
    jb, pi, pv, acc, h, t1, t2, out,
):  # fmt: skip
    """Serial winners ``out`` ``(B,)`` of the rows of ``x``, ``y`` (``h``: one row of scratch)."""
    for b in range(x.shape[0]):
        _respond_row(raw, scale, x[b], y[b], tol, ahead, jb, pi, pv, acc, h)
        out[b] = _winner(h, scale, sqnorm, rule, sigma, cut, dims, strides, map_periodic, t1, t2)


# left unformatted: its arguments in rows, as its calls pass them
@njit(cache=True, parallel=True)
def winners_rows_parallel(
    raw, scale, sqnorm, x, y, tol, ahead, rule, sigma, cut, dims, strides, map_periodic, order,
    out,
):  # fmt: skip
    """:func:`winners_rows` in parallel blocks of rows, visited in ``order``."""
    n_rows = x.shape[0]
    n_blocks = (n_rows + BLOCK_ROWS - 1) // BLOCK_ROWS
    for c in prange(n_blocks):
        jb, pi, pv, acc, t1, t2 = _scratch(raw.shape[0], y.shape[1], raw.shape[1])
        h = np.empty(raw.shape[1])
        for r in range(c * BLOCK_ROWS, min(n_rows, (c + 1) * BLOCK_ROWS)):
            b = order[r]
            _respond_row(raw, scale, x[b], y[b], tol, ahead, jb, pi, pv, acc, h)
            out[b] = _winner(
                h, scale, sqnorm, rule, sigma, cut, dims, strides, map_periodic, t1, t2
            )
