"""Compiled helpers of the fast kernel's refinement: the winner search by bounds (exact sums
for a few units only) and the sums of the hard assignment.

A refinement round searches the winners of many pairs on weights that stay fixed for the
whole round (:mod:`sigmapi.rules.refinement`), so it pays to prepare the weights once per
round (:class:`SearchIndex`, :func:`build`):

- the pair grid ``(x, y)`` is cut into **tiles** of :data:`TILE` grid points along every axis
  of both codes (a 2-D code pair: tiles of ``TILE**4`` input pairs), and for every unit and
  tile the norm of the unit's weights on that tile is kept (``norms[t, k] = scale_k
  |raw[tile t, k]|``, float32 rounded up);
- a transposed copy of the weights, ``raw_t`` ``(K, n_x n_y)``, holds one unit's weights
  contiguously.

A pair's kept input pairs (the same ones as :func:`sigmapi.kernels._rows.activate` sums,
``_rows._pairs``) fall in a few tiles; by Cauchy-Schwarz on every tile, ``|h_k| <= sum_t
|v_t| norms[t, k]`` with ``|v_t|`` the norm of the pair's outer product on tile ``t``: an upper
bound of every unit's score for the cost of ``tiles x K`` multiply-adds (about 36 tiles
instead of about 1,000 kept pairs on paper-2d). The units are then summed exactly, best bound
first, a few at a time, until no bound left reaches the best exact score. A unit whose bound
lies below that score cannot win (the bounds carry a relative margin of 1e-9, far above the
rounding of the sums), and a unit that is summed gets the very arithmetic of
``_rows.activate`` and ``_rows._winner`` (the kept pairs in their order, float64): the
winners are those of :meth:`sigmapi.kernels.fast.FastKernel.winners_of`, bit for bit, ties
to the lowest index. For the rules whose score is a unit's own activation (``argmax``,
``min_distance``: the hard rules); the smoothing rules keep the full search.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from sigmapi.kernels._rows import ARGMAX, MIN_DISTANCE

__all__ = ["RULES", "TILE", "SearchIndex", "build", "finish", "hard_sums", "search"]

TILE = 3
"""Grid points per tile along every axis of the codes (paper-2d: about 36 tiles per pair)."""

RULES = (ARGMAX, MIN_DISTANCE)
"""The compiled rules (codes of ``_rows._winner``) this search serves."""

MARGIN = 1e-9
"""Relative slack of the bounds: a unit is skipped only if its bound, so widened, is below
the best exact score (the float64 sums of about 1,000 terms round by about 1e-13)."""

ROWS = 16
"""Pairs per parallel work item."""


@dataclass
class SearchIndex:
    """What a round's searches read: ``tile_x`` ``(n_x,)`` and ``tile_y`` ``(n_y,)``, the
    tile of every grid point of each code (input pair ``(i, j)`` lies in tile
    ``tile_x[i] * tiles_y + tile_y[j]``); ``norms`` ``(tiles_x * tiles_y, K)`` float32 (rounded
    up); ``raw_t`` ``(K, n_x n_y)`` the weights transposed; ``scale``, the state's scales it
    was made from (a changed state needs a new index)."""

    tile_x: NDArray[np.int64]
    tile_y: NDArray[np.int64]
    norms: NDArray[np.float32]
    raw_t: NDArray[np.floating]
    scale: NDArray[np.float64]
    scratch: dict[str, NDArray[Any]] = field(default_factory=dict, repr=False)
    """Work arrays of the searches, kept for the next one (a round searches its pairs in
    calls of the same size: the same memory, not fresh pages every call)."""

    def work(self, name: str, rows: int, cols: int, dtype: type) -> NDArray[Any]:
        """A work array ``(rows, cols)`` (``cols = 0``: ``(rows,)``) of ``dtype``, reused."""
        have = self.scratch.get(name)
        if have is None or have.shape[0] < rows:
            have = self.scratch[name] = np.empty((rows, cols) if cols else rows, dtype=dtype)
        return have[:rows]

    def fits(self, raw: NDArray[np.floating], scale: NDArray[np.float64]) -> bool:
        """Whether this index was made from weights of this shape and these scales."""
        return self.raw_t.shape == raw.shape[::-1] and np.array_equal(self.scale, scale)


def _tiles(shape: tuple[int, ...], tile: int) -> tuple[NDArray[np.int64], int]:
    """Tile of every grid point of a code of ``shape`` (flat, row-major) and the tile count."""
    counts = tuple(-(-n // tile) for n in shape)
    coords = np.indices(shape).reshape(len(shape), -1) // tile
    tiles = np.asarray(np.ravel_multi_index(tuple(coords), counts), dtype=np.int64)
    return tiles, int(np.prod(counts))


@njit(cache=True, parallel=True)
def _tile_sq(raw, tile_x, tile_y, n_ty, n_tiles):  # pragma: no cover - compiled
    """``out[t, k] = sum_{p in tile t} raw[p, k]**2`` in float64, parallel over units."""
    n_pairs, k_units = raw.shape
    ny = tile_y.shape[0]
    out = np.zeros((n_tiles, k_units))
    n_chunks = (k_units + 31) // 32
    for c in prange(n_chunks):
        k0 = c * 32
        k1 = min(k_units, k0 + 32)
        for p in range(n_pairs):
            t = tile_x[p // ny] * n_ty + tile_y[p % ny]
            for k in range(k0, k1):
                v = np.float64(raw[p, k])
                out[t, k] += v * v
    return out


def build(
    raw: NDArray[np.floating],
    scale: NDArray[np.float64],
    code_shapes: tuple[tuple[int, ...], tuple[int, ...]],
    tile: int = TILE,
) -> SearchIndex:
    """The index of weights ``raw`` ``(n_x n_y, K)`` with ``scale`` ``(K,)`` for codes of
    ``code_shapes`` (x's grid, y's grid)."""
    tx, ntx = _tiles(tuple(code_shapes[0]), tile)
    ty, nty = _tiles(tuple(code_shapes[1]), tile)
    if tx.size * ty.size != raw.shape[0]:
        raise ValueError(f"code shapes {code_shapes} do not fit {raw.shape[0]} input pairs")
    sq: Any = _tile_sq  # a numba dispatcher
    exact = np.sqrt(sq(raw, tx, ty, nty, ntx * nty)) * scale[None, :]
    norms = exact.astype(np.float32)
    low = norms < exact  # round up, so that the float32 norms still bound
    norms[low] = np.nextafter(norms[low], np.float32(np.inf))
    return SearchIndex(tx, ty, norms, np.ascontiguousarray(raw.T), scale.copy())


@njit(cache=True, nogil=True)
def _code_tiles(x, tile_x, n_tiles, sq, top):  # pragma: no cover - compiled
    """Per tile of one code: ``sq`` the sum of squares, ``top`` the largest ``|x_i|``;
    returns the largest ``|x_i|`` of the code."""
    for t in range(n_tiles):
        sq[t] = 0.0
        top[t] = 0.0
    m = 0.0
    for i in range(x.shape[0]):
        t = tile_x[i]
        a = abs(x[i])
        sq[t] += a * a
        top[t] = max(top[t], a)
        m = max(m, a)
    return m


@njit(cache=True, nogil=True)
def _bound_row(
    norms, scale, sqnorm, tile_x, tile_y, x, y, tol, rule, xs, xt, ys, yt, s, ub
):  # pragma: no cover - compiled
    """``ub[k]``: an upper bound of unit ``k``'s score for the pair ``(x, y)``.

    The kept input pairs of ``_rows._pairs`` lie in the tiles whose largest ``|x_i| |y_j|``
    exceeds the cut ``tol max|x| max|y|``; on such a tile the kept part of ``x y^T`` has a
    norm of at most ``|x_tile| |y_tile|``, so ``|h_k| <= sum_t |x_tx| |y_ty| norms[t, k]``."""
    k_units = norms.shape[1]
    n_ty = ys.shape[0]
    mx = _code_tiles(x, tile_x, xs.shape[0], xs, xt)
    my = _code_tiles(y, tile_y, n_ty, ys, yt)
    thr = tol * mx * my
    for k in range(k_units):
        s[k] = 0.0
    for a in range(xs.shape[0]):
        if xt[a] * my <= thr:
            continue
        for b in range(n_ty):
            if xt[a] * yt[b] <= thr:
                continue
            sv = np.sqrt(xs[a] * ys[b])
            row = norms[a * n_ty + b]
            for k in range(k_units):
                s[k] += sv * row[k]
    up = 1.0 + MARGIN
    if rule == MIN_DISTANCE:
        down = 1.0 - MARGIN
        for k in range(k_units):
            ub[k] = 2.0 * s[k] * up - scale[k] * scale[k] * sqnorm[k] * down
    else:
        for k in range(k_units):
            ub[k] = s[k] * up


@njit(cache=True, parallel=True)
def _bound_rows(norms, scale, sqnorm, tile_x, tile_y, n_tx, n_ty, x, y, tol, rule, ub, guess):
    """:func:`_bound_row` for every row into ``ub`` ``(B, K)``, and ``guess[b]``, the unit of
    the largest bound (the likely winner), in parallel blocks of :data:`ROWS` rows."""
    n_rows = x.shape[0]  # pragma: no cover - compiled
    k_units = norms.shape[1]
    for c in prange((n_rows + ROWS - 1) // ROWS):
        xs = np.empty(n_tx)
        xt = np.empty(n_tx)
        ys = np.empty(n_ty)
        yt = np.empty(n_ty)
        s = np.empty(k_units)
        for b in range(c * ROWS, min(n_rows, (c + 1) * ROWS)):
            u = ub[b]
            _bound_row(
                norms, scale, sqnorm, tile_x, tile_y, x[b], y[b], tol, rule, xs, xt, ys, yt, s, u
            )
            g = 0
            for k in range(1, k_units):
                if u[k] > u[g]:
                    g = k
            guess[b] = g


@njit(cache=True, nogil=True)
def _kept(x, y, tol, ib, jb):  # pragma: no cover - compiled
    """The prefilter of ``_rows._pairs``: the ``i`` with ``|x_i| max|y| > cut`` into ``ib``,
    the ``j`` with ``|y_j| max|x| > cut`` into ``jb``; returns their counts and the cut."""
    mx = 0.0
    for i in range(x.shape[0]):
        mx = max(mx, abs(x[i]))
    my = 0.0
    for j in range(y.shape[0]):
        my = max(my, abs(y[j]))
    thr = tol * mx * my
    ni = 0
    for i in range(x.shape[0]):
        if abs(x[i]) * my > thr:
            ib[ni] = i
            ni += 1
    nj = 0
    for j in range(y.shape[0]):
        if abs(y[j]) * mx > thr:
            jb[nj] = j
            nj += 1
    return ni, nj, thr


@njit(cache=True, nogil=True)
def _exact(raw_t, scale, sqnorm, rule, cand, m, x, y, ib, ni, jb, nj, thr, score):
    """Scores of units ``cand[:m]`` (m <= 4) into ``score[:m]``: the sums of
    ``_rows.activate`` and the score of ``_rows._winner``, four independent sums per pass.

    The pass runs over the prefiltered grid of :func:`_kept` in the order of ``_rows._pairs``
    and adds ``raw * v`` where ``_pairs`` keeps ``v = x_i y_j`` and ``raw * 0`` (a zero) where
    it does not: adding a zero leaves a sum that started at +0 unchanged, so the sums are
    those of the kept pairs, bit for bit, without a branch or a list."""  # pragma: no cover
    ny = y.shape[0]
    r0, r1 = raw_t[cand[0]], raw_t[cand[min(1, m - 1)]]
    r2, r3 = raw_t[cand[min(2, m - 1)]], raw_t[cand[min(3, m - 1)]]
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    a3 = 0.0
    for u in range(ni):
        i = ib[u]
        xi = x[i]
        base = i * ny
        for w in range(nj):
            j = jb[w]
            v = xi * y[j]
            v = v if abs(v) > thr else 0.0
            p = base + j
            a0 += r0[p] * v
            a1 += r1[p] * v
            a2 += r2[p] * v
            a3 += r3[p] * v
    sums = (a0, a1, a2, a3)
    for g in range(m):
        k = cand[g]
        h = scale[k] * sums[g]
        if rule == MIN_DISTANCE:
            score[g] = 2.0 * h - scale[k] * scale[k] * sqnorm[k]
        else:
            score[g] = h


@njit(cache=True, nogil=True)
def _settle_row(raw_t, scale, sqnorm, x, y, tol, rule, ub, ib, jb, cand, score):
    """The winner of one pair from its bounds ``ub`` (overwritten): the units summed
    exactly, best bound first and four at a time, until no bound left reaches the best
    score; ties to the lowest index."""  # pragma: no cover - compiled
    k_units = ub.shape[0]
    ni, nj, thr = _kept(x, y, tol, ib, jb)
    best = -np.inf
    win = -1
    while True:
        m = 0
        for g in range(4):
            c = 0
            for k in range(1, k_units):
                if ub[k] > ub[c]:
                    c = k
            if ub[c] == -np.inf or ub[c] < best:
                break
            cand[g] = c
            ub[c] = -np.inf
            m += 1
        if m == 0:
            return win
        _exact(raw_t, scale, sqnorm, rule, cand, m, x, y, ib, ni, jb, nj, thr, score)
        for g in range(m):
            if score[g] > best or (score[g] == best and cand[g] < win):
                best = score[g]
                win = cand[g]


@njit(cache=True, parallel=True)
def _settle_rows(raw_t, scale, sqnorm, x, y, tol, rule, ub, order, out):
    """:func:`_settle_row` for every row, in parallel blocks of :data:`ROWS` rows visited in
    ``order``."""  # pragma: no cover - compiled
    n_rows = x.shape[0]
    for c in prange((n_rows + ROWS - 1) // ROWS):
        ib = np.empty(x.shape[1], dtype=np.int64)
        jb = np.empty(y.shape[1], dtype=np.int64)
        cand = np.empty(4, dtype=np.int64)
        score = np.empty(4)
        for r in range(c * ROWS, min(n_rows, (c + 1) * ROWS)):
            b = order[r]
            out[b] = _settle_row(
                raw_t, scale, sqnorm, x[b], y[b], tol, rule, ub[b], ib, jb, cand, score
            )


def search(
    index: SearchIndex,
    sqnorm: NDArray[np.float64],
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    tol: float,
    rule: int,
) -> NDArray[np.int64]:
    """Winners ``(B,)`` of the pairs ``(x_b, y_b)`` under the compiled rule ``rule`` (one of
    :data:`RULES`) on the weights of ``index`` (with their exact ``sqnorm``): the bounds of
    all pairs first, then the exact sums with the pairs ordered by their likely winner (so
    that pairs summing the same units come together)."""
    n_rows, k_units = x.shape[0], index.norms.shape[1]
    n_tx, n_ty = int(index.tile_x.max()) + 1, int(index.tile_y.max()) + 1
    ub = index.work("ub", n_rows, k_units, np.float64)
    guess = index.work("guess", n_rows, 0, np.int64)
    bound: Any = _bound_rows  # numba dispatchers
    settle: Any = _settle_rows
    # left unformatted: the arguments in the rows of the kernel's signature
    bound(index.norms, index.scale, sqnorm, index.tile_x, index.tile_y, n_tx, n_ty, x, y,
          float(tol), int(rule), ub, guess)  # fmt: skip
    out = np.empty(n_rows, dtype=np.int64)
    order = np.argsort(guess, kind="stable")
    settle(index.raw_t, index.scale, sqnorm, x, y, float(tol), int(rule), ub, order, out)
    return out


@njit(cache=True, parallel=True)
def _hard_sums(sums, mass, order, starts, x1, y1, tol):  # pragma: no cover - compiled
    """``sums[k, p] += v_p`` over the kept pairs ``p`` of view 1 of every pair that unit
    ``k`` won and ``mass[k] += 1`` per such pair; ``order[starts[k]:starts[k + 1]]``: those
    pairs in their order. Parallel over units (each unit's sums on one thread, its pairs in
    order). Runs over the prefiltered grid of :func:`_kept` and adds a zero where
    ``_rows._pairs`` drops a pair (a sum that started at +0 is unchanged by it), without a
    branch or a list."""
    k_units = sums.shape[0]
    ny = y1.shape[1]
    for c in prange((k_units + 15) // 16):
        ib = np.empty(x1.shape[1], dtype=np.int64)
        jb = np.empty(ny, dtype=np.int64)
        for k in range(c * 16, min(k_units, c * 16 + 16)):
            row = sums[k]
            for r in range(starts[k], starts[k + 1]):
                b = order[r]
                x = x1[b]
                y = y1[b]
                ni, nj, thr = _kept(x, y, tol, ib, jb)
                for u in range(ni):
                    i = ib[u]
                    xi = x[i]
                    base = i * ny
                    for w in range(nj):
                        j = jb[w]
                        v = xi * y[j]
                        row[base + j] += v if abs(v) > thr else 0.0
                mass[k] += 1.0


def hard_sums(
    sums: NDArray[np.float64],
    mass: NDArray[np.float64],
    winners: NDArray[np.int64],
    x1: NDArray[np.float64],
    y1: NDArray[np.float64],
    tol: float,
) -> None:
    """Add the pairs ``(x1_b, y1_b)`` to the sums ``(K, n_x n_y)`` and ``mass`` of their
    winners, each unit's pairs in order: the arithmetic of
    :meth:`sigmapi.rules.BatchMean.accumulate` at ``sigma = 0`` (a unit's sums gain
    ``1 * v = v``, the others' a zero), bit for bit, on the kernel's sparse pairs."""
    order = np.argsort(winners, kind="stable")
    starts = np.searchsorted(winners[order], np.arange(sums.shape[0] + 1))
    driver: Any = _hard_sums  # a numba dispatcher
    driver(sums, mass, order, starts, x1, y1, float(tol))


@njit(cache=True, parallel=True)
def _finish(raw, scale, sums, mass, out):  # pragma: no cover - compiled
    """``out[p, k] = sums[k, p] / mass[k]`` where ``mass[k] > 0``, else ``scale[k] *
    raw[p, k]`` (float64, then stored in ``out``'s type), in blocks of 64 input pairs."""
    n_pairs, k_units = raw.shape
    for c in prange((n_pairs + 63) // 64):
        p0 = c * 64
        p1 = min(n_pairs, p0 + 64)
        for k in range(k_units):
            if mass[k] > 0:
                for p in range(p0, p1):
                    out[p, k] = sums[k, p] / mass[k]
            else:
                for p in range(p0, p1):
                    out[p, k] = np.float64(raw[p, k]) * scale[k]


def finish(
    raw: NDArray[np.floating],
    scale: NDArray[np.float64],
    sums: NDArray[np.float64],
    mass: NDArray[np.float64],
) -> NDArray[np.floating]:
    """The new unscaled weights ``(n_x n_y, K)`` (scales 1) in ``raw``'s type: what
    ``prepare(BATCH_MEAN.finish(export(state), sums))`` stores, bit for bit, without the
    dense float64 copies."""
    out = np.empty_like(raw)
    driver: Any = _finish  # a numba dispatcher
    driver(raw, scale, sums, mass, out)
    return out
