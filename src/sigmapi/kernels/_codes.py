"""The compiled end of :meth:`sigmapi.codes.PopulationCode.encode`: the outer product of the
hills, the height and the L2 normalisation in one pass over every code, bit for bit.

``encode`` builds a code in NumPy temporaries: the outer product of the 1-D hills (the
exponentials, ``PopulationCode.hills``), times the height, over its L2 norm
(``np.linalg.norm``: the square root of NumPy's pairwise sum of the squares). Here the hills
stay NumPy's (its ``exp``; a compiled ``exp`` may differ in the last bit), and the rest runs
compiled with the same operations in the same order: the products ``a_i h_j``, ``height *
c``, the squares summed as NumPy's ``add.reduce`` sums a contiguous row (eight running sums
over blocks of at most 128, halves of multiples of eight above; ``tests/kernels/
test_encode.py`` compares it with NumPy on many lengths), its square root and one division
per unit. The two-view sampler encodes its four views per pair so
(:class:`sigmapi.tasks.TwoViewSampler`).

:func:`encode_fast` is the refinement's fast path (``refine_tol > 0``): the norm of an outer
product is the product of its factors' norms, so every hill is normalised on its own (a
handful of values per axis) and the code is the outer product of the normalised hills, one
multiply a unit; within a few float64 roundings of :func:`encode`, not bit for bit.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from sigmapi.codes import PopulationCode

__all__ = ["encode", "encode_fast"]

_BLOCK = 128
"""NumPy's ``PW_BLOCKSIZE``: the longest run its pairwise sum adds with eight sums."""


@njit(cache=True, nogil=True)
def _leaf(a, lo, n):  # pragma: no cover - compiled
    """NumPy's pairwise sum of a run ``a[lo:lo + n]`` of at most ``_BLOCK`` values."""
    if n < 8:
        res = -0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = lo + 8
    end = lo + n - n % 8
    while i < end:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < lo + n:
        res += a[i]
        i += 1
    return res


@njit(cache=True, nogil=True)
def _pairwise(a, lo, n):  # pragma: no cover - compiled
    """NumPy's pairwise sum of ``a[lo:lo + n]`` (``pairwise_sum`` of its loops): runs of at
    most ``_BLOCK`` by :func:`_leaf`, longer ones the sum of their halves (the first half a
    multiple of eight long). Its recursion unrolled on a stack (numba's cache does not keep
    recursive functions)."""
    if n <= _BLOCK:
        return _leaf(a, lo, n)
    half = n // 2 - (n // 2) % 8
    if n - half <= _BLOCK:  # two runs (a 15x15 code: 112 and 113)
        return _leaf(a, lo, half) + _leaf(a, lo + half, n - half)
    at = np.empty(64, dtype=np.int64)  # a frame: its start, length, step, left half's sum
    size = np.empty(64, dtype=np.int64)
    step = np.zeros(64, dtype=np.int64)
    left = np.empty(64)
    at[0], size[0], step[0] = lo, n, 0
    top = 0
    val = 0.0
    while top >= 0:
        m = size[top]
        half = m // 2 - (m // 2) % 8
        if m <= _BLOCK or step[top] == 2:
            val = _leaf(a, at[top], m) if m <= _BLOCK else left[top] + val
            top -= 1
            if top >= 0:
                if step[top] == 1:
                    left[top] = val
                continue
        elif step[top] == 0:  # the first half
            step[top] = 1
            top += 1
            at[top], size[top], step[top] = at[top - 1], half, 0
        else:  # the second half
            step[top] = 2
            top += 1
            at[top], size[top], step[top] = at[top - 1] + half, m - half, 0
    return val


@njit(cache=True, nogil=True)
def _outer(a, h, height, normalize, out):  # pragma: no cover - compiled
    """``out[b] = height * (a[b] (x) h[b])`` (C order), over its L2 norm if ``normalize``."""
    rows, m = a.shape
    n = h.shape[1]
    sq = np.empty(m * n)
    for b in range(rows):
        row = out[b]
        for i in range(m):
            ai = a[b, i]
            for j in range(n):
                row[i * n + j] = height * (ai * h[b, j])
        if normalize:
            for u in range(m * n):
                sq[u] = row[u] * row[u]
            norm = np.sqrt(0.0 + _pairwise(sq, np.int64(0), m * n))  # not a literal
            for u in range(m * n):
                row[u] = row[u] / norm


@njit(cache=True, nogil=True)
def _outer_fast(a, h, out):  # pragma: no cover - compiled
    """``out[b] = a[b] (x) h[b]`` (C order), the factors already scaled."""
    rows, m = a.shape
    n = h.shape[1]
    for b in range(rows):
        row = out[b]
        hb = h[b]
        for i in range(m):
            ai = a[b, i]
            seg = row[i * n : (i + 1) * n]  # from 0: no wrap-around check, vectors
            for j in range(n):
                seg[j] = ai * hb[j]


def _out(out: NDArray[np.float64] | None, shape: tuple[int, int]) -> NDArray[np.float64]:
    """``out`` checked to be C-contiguous float64 of ``shape``, or a fresh array of it."""
    if out is None:
        return np.empty(shape)
    if out.shape != shape or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise ValueError(f"out must be C-contiguous float64 of shape {shape}, got {out.shape}")
    return out


def encode_fast(
    code: PopulationCode, p: ArrayLike, out: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """``code.encode(p)`` within rounding (module docstring), into ``out`` when given (as
    :func:`encode`): each hill over its own L2 norm (times ``height`` on the first axis
    unless normalised), then their outer product."""
    hills = code.hills(p)
    if code.normalize:
        hills = [h / np.sqrt(np.einsum("ij,ij->i", h, h))[:, None] for h in hills]
    elif code.height != 1.0:
        hills[0] = hills[0] * code.height
    shape = (hills[0].shape[0], int(np.prod([h.shape[1] for h in hills])))
    out = _out(out, shape)
    if len(hills) == 1:
        out[...] = hills[0]
        return out
    a = hills[0]
    driver: Any = _outer_fast  # a numba dispatcher
    for hill in hills[1:-1]:  # the outer products of all axes but the last
        nxt = np.empty((a.shape[0], a.shape[1] * hill.shape[1]))
        driver(a, hill, nxt)
        a = nxt
    driver(a, hills[-1], out)
    return out


def encode(
    code: PopulationCode, p: ArrayLike, out: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """``code.encode(p)``, bit for bit, compiled (module docstring); written into ``out``
    (C-contiguous float64 ``(B, n)``) when given, so that a caller drawing many batches
    reuses its memory instead of asking the system for fresh pages every time."""
    hills = code.hills(p)
    a = np.ones((hills[0].shape[0], 1))
    driver: Any = _outer  # a numba dispatcher
    for hill in hills[:-1]:  # the outer products of all axes but the last, unscaled
        nxt = np.empty((a.shape[0], a.shape[1] * hill.shape[1]))
        driver(a, hill, 1.0, False, nxt)
        a = nxt
    shape = (a.shape[0], a.shape[1] * hills[-1].shape[1])
    out = _out(out, shape)
    driver(a, hills[-1], float(code.height), bool(code.normalize), out)
    return out
