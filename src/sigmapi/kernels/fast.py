# Over 400 lines: one kernel (its compiled helpers, two training drivers, public functions).
"""Fast CPU kernel: numba, sparse codes, lazy decay, parallel over map units.

Computes the same learning iteration as :mod:`sigmapi.kernels.reference` (the definition),
using the structure of the problem:

- **Sparse codes.** The codes are Gaussian hills, so the outer product ``x y^T`` of a view has
  few non-negligible entries. Entries with ``|x_i y_j| <= tol * max|x| * max|y|`` are skipped,
  in the activation and in the update (a 4-D ball of pairs around the peak; about 235 of
  50,625 pairs for 15x15 codes of width 0.5 at ``tol = 1e-6``, about 2,500 for width 1).
- **Lazy decay.** Unit ``k`` stores ``W_k = s_k V_k`` with a scale ``s_k``. The Kohonen update
  ``W_k <- (1 - eps a_k) W_k + eps a_k x' y'^T`` becomes ``s_k <- s_k (1 - eps a_k)`` (O(1))
  plus the sparse ``V_k <- V_k + (eps a_k / s_k) x' y'^T``. Before ``s_k`` falls below
  ``2**-50`` the decay is folded into ``V_k`` and ``s_k`` reset to 1.
- **Sparse neighbourhood.** Units with ``a_k <= tol * max_k a_k`` get no additive update
  (their decay, being O(1), is still applied exactly).
- **float32 storage** of ``V`` (accumulation in float64), laid out ``(n_x * n_y, K)`` so that
  one input pair touches the weights of all units contiguously.
- **Parallel over units**, in fixed chunks: every unit's arithmetic is the same whatever the
  number of threads, so results do not depend on it (no reductions across units).

``tol = 0`` is the exact mode: no truncation and float64 storage, matching the reference to
float64 rounding (used by the tests). What larger ``tol`` costs in winners and weights is
measured in ``benchmarks/README.md`` (kernel tolerance table).

State (:class:`FastState`): ``raw`` ``(n_x * n_y, K)`` (float32, or float64 when exact),
``scale`` ``(K,)`` and ``sqnorm`` ``(K,)`` = ``sum_p raw[p, k]**2`` (tracked incrementally for
the ``min_distance`` rule; ``|w_k|^2 = scale_k^2 sqnorm_k``). :func:`state_arrays` returns all
three, so a saved model continues bit for bit on this backend.

References
----------
C. Weber and S. Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007)
2552-2560.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.kernels import reference
from sigmapi.kernels.base import WINNER_RULES

__all__ = [
    "NAME",
    "FastState",
    "activation",
    "export",
    "from_state_arrays",
    "prepare",
    "state_arrays",
    "train_block",
    "winners",
]

NAME = "fast"

RENORM = 2.0**-50
"""A unit's scale is folded into its stored weights before it falls below this."""

CHUNK = 32
"""Map units per parallel work item (a multiple of 16: whole cache lines of float32)."""

PARALLEL_MIN_WORK = 1 << 18
"""With ``threads=True`` (``SOMConfig.threads``), training uses threads when ``K * n_x * n_y``
is at least this; below it, synchronising the threads costs more than it saves.

Off by default: one learning step is ~0.1-1 ms of work with two synchronisations, and on a
shared 2-core machine a descheduled worker thread stalls every step (measured: 62 it/s with
2 threads vs 390 it/s with 1 on paper-2d under a load average of 5). The batched
:func:`activation` (one synchronisation per call) always uses all threads.
"""

_RULES = {rule: code for code, rule in enumerate(WINNER_RULES)}
"""Rule codes of the compiled :func:`_winner`: 0 soft, 1 argmax, 2 min_distance."""


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
        ``sum_p raw[p, k]**2`` (float64): exact after :func:`prepare`, tracked through updates
        while training with the ``min_distance`` rule (the only rule that needs it).
    norms_valid : bool
        Whether ``sqnorm`` is current; if not, it is recomputed when needed.
    tol : float
        Relative truncation tolerance of codes and neighbourhoods (0 = exact).
    shape : tuple of int
        ``(K, n_x, n_y)``.
    """

    raw: NDArray[np.floating]
    scale: NDArray[np.float64]
    sqnorm: NDArray[np.float64]
    tol: float
    shape: tuple[int, int, int]
    norms_valid: bool = True

    def refresh_norms(self) -> None:
        """Recompute ``sqnorm`` exactly from ``raw`` if it is stale."""
        if not self.norms_valid:
            self.sqnorm[:] = _sqnorms(self.raw)
            self.norms_valid = True


# ---------------------------------------------------------------------------- state


def _storage_dtype(tol: float) -> type[np.floating]:
    return np.float64 if tol == 0 else np.float32


def _check_tol(tol: float) -> float:
    return _validate.number("tol", tol, 0.0, 1.0, hi_open=True, fix="0 is the exact mode")


def prepare(weights: NDArray[np.float64], tol: float = 1e-6) -> FastState:
    """Backend state from dense weights ``(K, n_x, n_y)``.

    Parameters
    ----------
    weights : ndarray, shape (K, n_x, n_y)
        Sigma-Pi weights.
    tol : float
        Relative truncation tolerance in [0, 1); 0 is the exact mode (float64 storage).
    """
    tol = _check_tol(tol)
    w = np.asarray(weights, dtype=np.float64)
    if w.ndim != 3:
        raise ValueError(f"weights must have shape (K, n_x, n_y), got {w.shape}")
    k, nx, ny = w.shape
    raw = np.ascontiguousarray(w.reshape(k, nx * ny).T, dtype=_storage_dtype(tol))
    return FastState(raw, np.ones(k), _sqnorms(raw), tol, (k, nx, ny))


def _sqnorms(raw: NDArray[np.floating]) -> NDArray[np.float64]:
    """``sum_p raw[p, k]**2`` in float64, in blocks of rows (no full float64 copy)."""
    sq = np.zeros(raw.shape[1])
    for s in range(0, raw.shape[0], 4096):
        r = raw[s : s + 4096].astype(np.float64)
        sq += np.einsum("pk,pk->k", r, r)
    return sq


def export(state: FastState) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)``: ``scale[k] * raw[:, k]``."""
    k, nx, ny = state.shape
    w = state.raw.T.astype(np.float64) * state.scale[:, None]
    return np.ascontiguousarray(w.reshape(k, nx, ny))


def state_arrays(state: FastState) -> dict[str, NDArray[np.floating]]:
    """Arrays that restore ``state`` exactly: ``raw``, ``scale`` and, if current, ``sqnorm``."""
    out = {"raw": state.raw.copy(), "scale": state.scale.copy()}
    if state.norms_valid:
        out["sqnorm"] = state.sqnorm.copy()
    return out


def from_state_arrays(
    weights: NDArray[np.float64], arrays: dict[str, NDArray[np.floating]], tol: float = 1e-6
) -> FastState:
    """Inverse of :func:`state_arrays`; ``weights`` ``(K, n_x, n_y)`` give the shapes.

    Raises ``ValueError`` if the arrays are missing or do not fit the weights and ``tol``.
    """
    tol = _check_tol(tol)
    k, nx, ny = np.shape(weights)
    missing = {"raw", "scale"} - set(arrays)
    if missing:
        raise ValueError(f"fast state needs arrays raw and scale; missing {sorted(missing)}")
    raw, scale = arrays["raw"], arrays["scale"]
    valid = "sqnorm" in arrays
    sq = arrays["sqnorm"] if valid else np.zeros(k)
    dtype = _storage_dtype(tol)
    if raw.shape != (nx * ny, k) or raw.dtype != dtype:
        raise ValueError(
            f"raw must be {np.dtype(dtype).name} of shape {(nx * ny, k)} for tol={tol}, "
            f"got {raw.dtype} {raw.shape}"
        )
    if scale.shape != (k,) or sq.shape != (k,):
        raise ValueError(f"scale and sqnorm must have shape ({k},), got {scale.shape}, {sq.shape}")
    if np.any(scale <= 0):
        raise ValueError("scale must be > 0")
    return FastState(
        np.ascontiguousarray(raw, dtype=dtype),
        np.ascontiguousarray(scale, dtype=np.float64),
        np.ascontiguousarray(sq, dtype=np.float64),
        tol,
        (int(k), int(nx), int(ny)),
        valid,
    )


# ---------------------------------------------------------------------------- numba helpers


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
            j = jbuf[q]
            v = xi * y[j]
            if abs(v) > thr:
                pidx[n] = base + j
                pval[n] = v
                n += 1
    return n


@njit(cache=True, nogil=True)
def _winner(h, scale, sqnorm, rule, sigma, cut, dims, strides, tmp, tmp2):
    """Winning unit of one activation vector ``h`` (K,); ties to the lowest index."""
    k_units = h.shape[0]
    if rule == 0 or rule == 3:  # soft: separable Gaussian smoothing over the map, window +-cut
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
                wts[d] = np.exp(-(d * d) / (2.0 * sigma * sigma))
            for k in range(k_units):
                c = (k // st) % n
                acc = 0.0
                norm = 0.0
                for c2 in range(max(0, c - m), min(n - 1, c + m) + 1):
                    acc += cur[k + (c2 - c) * st] * wts[abs(c2 - c)]
                    norm += wts[abs(c2 - c)]
                nxt[k] = acc / norm if rule == 3 else acc
            cur, nxt = nxt, cur
        best = 0
        for k in range(1, k_units):
            if cur[k] > cur[best]:
                best = k
        return best
    if rule == 1:
        best = 0
        for k in range(1, k_units):
            if h[k] > h[best]:
                best = k
        return best
    best = 0
    bval = 2.0 * h[0] - scale[0] * scale[0] * sqnorm[0]
    for k in range(1, k_units):
        v = 2.0 * h[k] - scale[k] * scale[k] * sqnorm[k]
        if v > bval:
            best = k
            bval = v
    return best


@njit(cache=True, nogil=True)
def _neighbourhood(winner, sigma, eps, tol, dims, strides, ea):
    """``ea[k] = eps * a_k`` (L2-normalised Gaussian around ``winner``).

    Returns the flat index range ``[lo, hi)`` holding every unit with ``a_k > tol max a``.
    """
    k_units = ea.shape[0]
    ssq = 0.0
    for k in range(k_units):
        d2 = 0.0
        for ax in range(dims.shape[0]):
            c = (k // strides[ax]) % dims[ax]
            cw = (winner // strides[ax]) % dims[ax]
            d2 += float(c - cw) ** 2
        a = np.exp(-d2 / (2.0 * sigma * sigma))
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


@njit(cache=True, nogil=True)
def _unit_chunk(
    raw, scale, sqnorm, k0, k1, ea, thr, lo, hi,
    pi1, pv1, n1, pi0, pv0, n0, do_act, track, h, gain, acc,
):  # fmt: skip
    """Units ``[k0, k1)``: Kohonen update with pairs 1, then activation of pairs 0 into ``h``.

    ``ea[k] = eps a_k``; units in ``[lo, hi)`` with ``ea[k] > thr`` get the additive update.
    ``track``: keep ``sqnorm`` up to date. Touches only indices ``[k0, k1)`` of the per-unit
    arrays, so chunks can run in parallel.
    """
    n_pairs = raw.shape[0]
    for k in range(k0, k1):
        sn = scale[k] * (1.0 - ea[k])
        if sn < RENORM:  # fold the decay into the stored weights
            ss = 0.0
            for p in range(n_pairs):
                raw[p, k] = raw[p, k] * sn
                v = float(raw[p, k])
                ss += v * v
            sqnorm[k] = ss
            sn = 1.0
        scale[k] = sn
        gain[k] = ea[k] / sn if (ea[k] > thr and lo <= k < hi) else 0.0
    u0 = max(lo, k0)
    u1 = min(hi, k1)
    if u0 < u1 and n1 > 0:
        if track:
            for k in range(u0, u1):
                acc[k] = 0.0
            for q in range(n1):
                row = raw[pi1[q]]
                val = pv1[q]
                for k in range(u0, u1):
                    old = float(row[k])
                    row[k] = old + gain[k] * val
                    new = float(row[k])
                    acc[k] += new * new - old * old
            for k in range(u0, u1):
                sqnorm[k] += acc[k]
        else:
            for q in range(n1):
                row = raw[pi1[q]]
                val = pv1[q]
                for k in range(u0, u1):
                    row[k] += gain[k] * val
    if do_act:
        for k in range(k0, k1):
            acc[k] = 0.0
        for q in range(n0):
            row = raw[pi0[q]]
            val = pv0[q]
            for k in range(k0, k1):
                acc[k] += row[k] * val
        for k in range(k0, k1):
            h[k] = scale[k] * acc[k]


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


@njit(cache=True, parallel=True)
def _train(
    raw, scale, sqnorm, x0, y0, x1, y1, sigmas, eps, dims, strides, rule, cut, tol, out, track,
    threads,
):  # fmt: skip
    """The training driver: iterations in order; ``threads``: update the units in parallel
    chunks of :data:`CHUNK` (same arithmetic per unit, so the same result), else in one call
    (no parallel region is entered, so no thread is woken)."""
    k_units = raw.shape[1]
    jb, pi0, pv0, pi1, pv1, h, ea, gain, acc, t1, t2 = _buffers(k_units, raw.shape[0], y0.shape[1])
    n_chunks = (k_units + CHUNK - 1) // CHUNK
    n_iter = x0.shape[0]
    if n_iter == 0:
        return
    n0 = _pairs(x0[0], y0[0], tol, jb, pi0, pv0)
    if threads:
        for c in prange(n_chunks):
            _unit_chunk(raw, scale, sqnorm, c * CHUNK, min(k_units, (c + 1) * CHUNK), ea, 1.0,
                        0, 0, pi1, pv1, 0, pi0, pv0, n0, True, track, h, gain, acc)  # fmt: skip
    else:
        _unit_chunk(raw, scale, sqnorm, 0, k_units, ea, 1.0, 0, 0,
                    pi1, pv1, 0, pi0, pv0, n0, True, track, h, gain, acc)  # fmt: skip
    for t in range(n_iter):
        w = _winner(h, scale, sqnorm, rule, sigmas[t], cut, dims, strides, t1, t2)
        out[t] = w
        lo, hi = _neighbourhood(w, sigmas[t], eps[t], tol, dims, strides, ea)
        thr = tol * ea[w]
        n1 = _pairs(x1[t], y1[t], tol, jb, pi1, pv1)
        more = t + 1 < n_iter
        if more:
            n0 = _pairs(x0[t + 1], y0[t + 1], tol, jb, pi0, pv0)
        if threads:
            for c in prange(n_chunks):
                _unit_chunk(raw, scale, sqnorm, c * CHUNK, min(k_units, (c + 1) * CHUNK), ea,
                            thr, lo, hi, pi1, pv1, n1, pi0, pv0, n0, more, track, h, gain,
                            acc)  # fmt: skip
        else:
            _unit_chunk(raw, scale, sqnorm, 0, k_units, ea, thr, lo, hi,
                        pi1, pv1, n1, pi0, pv0, n0, more, track, h, gain, acc)  # fmt: skip


@njit(cache=True, parallel=True)
def _activation_batch(raw, scale, x, y, tol, order, h):
    """``h[b, k] = scale_k sum_p raw[p, k] (x_b y_b^T)_p`` over the kept pairs.

    Rows are visited in ``order`` (rows with nearby code peaks together, so that the weight
    rows they share stay in cache); blocks of rows run in parallel. Each row's arithmetic
    does not depend on the order or the thread.
    """
    n_rows = x.shape[0]
    n_pairs = raw.shape[0]
    k_units = raw.shape[1]
    rows = 16
    n_blocks = (n_rows + rows - 1) // rows
    for c in prange(n_blocks):
        jb = np.empty(y.shape[1], dtype=np.int64)
        pi = np.empty(n_pairs, dtype=np.int64)
        pv = np.empty(n_pairs)
        acc = np.empty(k_units)
        for r in range(c * rows, min(n_rows, (c + 1) * rows)):
            b = order[r]
            n = _pairs(x[b], y[b], tol, jb, pi, pv)
            for k in range(k_units):
                acc[k] = 0.0
            for q in range(n):
                row = raw[pi[q]]
                val = pv[q]
                for k in range(k_units):
                    acc[k] += row[k] * val
            for k in range(k_units):
                h[b, k] = scale[k] * acc[k]


# ---------------------------------------------------------------------------- public interface


def _grid(map_shape: tuple[int, ...], k_units: int) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    dims = np.asarray(map_shape, dtype=np.int64)
    if int(np.prod(dims)) != k_units:
        raise ValueError(f"map_shape {map_shape} does not hold the state's {k_units} units")
    strides = np.ones_like(dims)
    for ax in range(len(map_shape) - 2, -1, -1):
        strides[ax] = strides[ax + 1] * dims[ax + 1]
    return dims, strides


def _rule_code(rule: str) -> int:
    try:
        return _RULES[rule]
    except KeyError:
        raise ValueError(f"rule must be one of {WINNER_RULES}, got {rule!r}") from None


def _codes(a: NDArray[np.floating], n: int, name: str) -> NDArray[np.float64]:
    arr = np.ascontiguousarray(a, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != n:
        raise ValueError(f"{name} must have shape (B, {n}), got {arr.shape}")
    return arr


def activation(
    state: FastState, x: NDArray[np.floating], y: NDArray[np.floating]
) -> NDArray[np.float64]:
    """Sigma-Pi activations ``h[b, k] = x_b^T W_k y_b`` of a batch; ``(B, K)``.

    Sparse equivalent of the matrix product ``vec(x_b y_b^T) @ W^T``: each row costs
    ``K x (number of kept pairs)`` multiply-adds; rows run in parallel.
    """
    k_units, nx, ny = state.shape
    xa = _codes(x, nx, "x")
    ya = _codes(y, ny, "y")
    if xa.shape[0] != ya.shape[0]:
        raise ValueError(
            f"x and y must have the same number of rows, got {xa.shape[0]}, {ya.shape[0]}"
        )
    h = np.empty((xa.shape[0], k_units))
    order = np.lexsort((np.argmax(np.abs(ya), axis=1), np.argmax(np.abs(xa), axis=1)))
    _activation_batch(state.raw, state.scale, xa, ya, state.tol, order, h)
    return h


def winners(
    state: FastState,
    h: NDArray[np.floating],
    map_shape: tuple[int, ...],
    rule: str,
    sigma: float,
    cut: int,
) -> NDArray[np.int64]:
    """Winning unit per row of activations ``h`` ``(B, K)``; ``(B,)``, ties to the lowest index.

    Rules as :func:`sigmapi.kernels.reference.winners`; ``min_distance`` uses the tracked
    norms ``|w_k|^2 = scale_k^2 sqnorm_k``. Vectorised over the batch.
    """
    _rule_code(rule)
    if rule == "min_distance":
        state.refresh_norms()
        wn = state.scale**2 * state.sqnorm
        return np.argmax(2.0 * np.asarray(h, dtype=np.float64) - wn[None, :], axis=1)
    return reference.winners(np.empty((0, 0, 0)), h, map_shape, rule, sigma, cut)


def train_block(
    state: FastState,
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
    """Run ``len(x0)`` learning iterations in order, updating ``state`` in place.

    Iteration ``t`` finds the winner of view ``(x0[t], y0[t])`` at width ``sigmas[t]`` and
    learns view ``(x1[t], y1[t])`` with rate ``eps[t]`` (as
    :func:`sigmapi.kernels.reference.train_block`). Returns the winners ``(T,)``.

    ``threads``: update the units on numba's threads (the same result) when the map is large
    enough (:data:`PARALLEL_MIN_WORK`) and numba has more than one thread.
    """
    k_units, nx, ny = state.shape
    dims, strides = _grid(tuple(map_shape), k_units)
    code = _rule_code(winner_rule)
    xs = [
        _codes(a, n, nm)
        for a, n, nm in ((x0, nx, "x0"), (y0, ny, "y0"), (x1, nx, "x1"), (y1, ny, "y1"))
    ]
    n_iter = xs[0].shape[0]
    sg = np.ascontiguousarray(sigmas, dtype=np.float64)
    ep = np.ascontiguousarray(eps, dtype=np.float64)
    if any(a.shape[0] != n_iter for a in xs) or sg.shape != (n_iter,) or ep.shape != (n_iter,):
        raise ValueError("x0, y0, x1, y1, sigmas and eps must have the same length")
    out = np.empty(n_iter, dtype=np.int64)
    track = code == _RULES["min_distance"]
    if track:
        state.refresh_norms()
    elif n_iter > 0:
        state.norms_valid = False
    parallel = threads and k_units * nx * ny >= PARALLEL_MIN_WORK and numba.get_num_threads() > 1
    driver: Any = _train  # a numba dispatcher (its stubs do not know the signature)
    driver(state.raw, state.scale, state.sqnorm, *xs, sg, ep, dims, strides, code,
           int(soft_cut), state.tol, out, track, bool(parallel))  # fmt: skip
    return out
