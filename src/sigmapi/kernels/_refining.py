# Over 500 lines: one compiled search (the index of tiles, the bounds, the exact scores of near
# ties, the hard sums and the finish), its numba steps read in the order a round runs them.
"""Compiled helpers of the fast kernel's refinement: the winner search by bounds (scores for
a few units only) and the sums of the hard assignment.

A refinement round searches the winners of many pairs on weights that stay fixed for the
whole round (:mod:`sigmapi.rules.refinement`), so it pays to prepare the weights once per
round (:class:`SearchIndex`, :func:`build`):

- the pair grid ``(x, y)`` is cut into **tiles** of :data:`TILE` grid points along every axis
  of both codes (a 2-D code pair: tiles of ``TILE**4`` input pairs), and for every unit and
  tile the norm of the unit's weights on that tile is kept (``norms[t, k] = scale_k
  |raw[tile t, k]|``, float32 rounded up), and for every group of :data:`GROUP` units the
  largest of its units' norms;
- a copy of the weights by unit and tile, ``blocks`` ``(K, tiles, points per tile)``: a
  unit's weights on one tile are contiguous.

A pair's kept input pairs (the same ones as :func:`sigmapi.kernels._rows.activate` sums,
``_rows._pairs``) fall in a few tiles (about 38 of 625 on paper-2d); its products there are
laid out as the blocks (:func:`_products`, zeros where ``_pairs`` drops a pair). By
Cauchy-Schwarz on every tile, ``|h_k| <= sum_t |v_t| norms[t, k]`` with ``|v_t|`` the norm of
the pair's outer product on tile ``t``: an upper bound of a unit's score, or of every score of
a group. The groups' bounds come first; the units' bounds of a group only where the group's
bound reaches a score some unit has (about 5 of 29 groups on paper-2d). A unit whose bound
reaches the best score so far is scored: its products summed tile by tile in float32 in any
order, the compiler's vectors (:func:`_approx`), which lands within a rounding slack
(:func:`slack`) of the float64 sum in the order of ``_rows.activate``; only where two units'
scores lie within their slacks are those units summed again in that order (:func:`_exact`).
So the winners are those of :meth:`sigmapi.kernels.fast.FastKernel.winners_of`, bit for bit,
ties to the lowest index.
For the rules whose score is a unit's own activation (``argmax``, ``min_distance``: the hard
rules); the smoothing rules keep the full search.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from sigmapi.kernels._rows import ARGMAX, MIN_DISTANCE

__all__ = [
    "GROUP",
    "RULES",
    "TILE",
    "SearchIndex",
    "build",
    "finish",
    "hard_sums",
    "search",
    "slack",
]

TILE = 3
"""Grid points per tile along every axis of the codes (paper-2d: about 36 tiles per pair)."""

RULES = (ARGMAX, MIN_DISTANCE)
"""The compiled rules (codes of ``_rows._winner``) this search serves."""

MARGIN = 1e-9
"""Relative slack of the bounds: a unit is skipped only if its bound, so widened, is below
the best exact score (the float64 sums of about 1,000 terms round by about 1e-13)."""

ROWS = 16
"""Pairs per parallel work item."""

GROUP = 8
"""Units per group of the first bounds (consecutive units: mostly neighbours on the map)."""

F32_EPS = 2.0**-23
"""float32's relative spacing: the bounds' float32 sums widen by it per term."""


@dataclass
class SearchIndex:
    """What a round's searches read: ``tile_x`` ``(n_x,)`` and ``tile_y`` ``(n_y,)``, the
    tile of every grid point of each code (input pair ``(i, j)`` lies in tile
    ``tile_x[i] * tiles_y + tile_y[j]``); ``members_x`` ``(tiles_x, TX)`` and ``members_y``
    ``(tiles_y, TY)``, the grid points of every tile (ascending, -1 where a tile at the
    grid's edge has fewer); ``norms`` ``(tiles_x * tiles_y, K)`` float32 (rounded up);
    ``blocks`` ``(K, tiles_x * tiles_y, TX * TY)`` the weights by unit and tile, a tile's
    input pairs ``(members_x[a, u], members_y[b, v])`` at ``u * TY + v`` (zeros where a
    tile has fewer); ``scale``, the state's scales it was made from (a changed state needs a
    new index)."""

    tile_x: NDArray[np.int64]
    tile_y: NDArray[np.int64]
    members_x: NDArray[np.int64]
    members_y: NDArray[np.int64]
    norms: NDArray[np.float32]
    group_norms: NDArray[np.float32]
    blocks: NDArray[np.floating]
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
        n = self.tile_x.size * self.tile_y.size
        fit = raw.shape == (n, self.blocks.shape[0]) and raw.dtype == self.blocks.dtype
        return fit and np.array_equal(self.scale, scale)


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


def _members(tiles: NDArray[np.int64], count: int) -> NDArray[np.int64]:
    """The grid points of every tile ``(count, most)``, ascending, -1 where fewer."""
    most = int(np.bincount(tiles, minlength=count).max())
    out = np.full((count, most), -1, dtype=np.int64)
    order = np.argsort(tiles, kind="stable")
    first = np.searchsorted(tiles[order], np.arange(count))
    slot = np.arange(tiles.size) - first[tiles[order]]
    out[tiles[order], slot] = order
    return out


@njit(cache=True, parallel=True)
def _to_blocks(raw, tile, slot, blocks):  # pragma: no cover - compiled
    """``blocks[k, tile[p], slot[p]] = raw[p, k]``, parallel over blocks of 32 units."""
    n_pairs, k_units = raw.shape
    for c in prange((k_units + 31) // 32):
        for p in range(n_pairs):
            t = tile[p]
            e = slot[p]
            for k in range(c * 32, min(k_units, c * 32 + 32)):
                blocks[k, t, e] = raw[p, k]


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
    mx, my = _members(tx, ntx), _members(ty, nty)
    at_x = np.empty(tx.size, dtype=np.int64)  # a grid point's place in its tile
    at_x[mx[mx >= 0]] = np.nonzero(mx >= 0)[1]
    at_y = np.empty(ty.size, dtype=np.int64)
    at_y[my[my >= 0]] = np.nonzero(my >= 0)[1]
    tiles = (tx[:, None] * nty + ty[None, :]).ravel()
    slot = (at_x[:, None] * my.shape[1] + at_y[None, :]).ravel()
    blocks = np.zeros((raw.shape[1], ntx * nty, mx.shape[1] * my.shape[1]), dtype=raw.dtype)
    copy: Any = _to_blocks  # a numba dispatcher
    copy(raw, tiles, slot, blocks)
    n_groups = -(-raw.shape[1] // GROUP)
    group = np.zeros((norms.shape[0], n_groups * GROUP), dtype=np.float32)
    group[:, : raw.shape[1]] = norms
    group = np.ascontiguousarray(group.reshape(norms.shape[0], n_groups, GROUP).max(axis=2))
    return SearchIndex(tx, ty, mx, my, norms, group, blocks, scale.copy())


@njit(cache=True, nogil=True)
def _cut(x, y, tol):  # pragma: no cover - compiled
    """``max|x|``, ``max|y|`` and the cut ``tol max|x| max|y|`` of ``_rows._pairs`` (a product
    ``x_i y_j`` is kept where its magnitude exceeds the cut)."""
    mx = _top(x)
    my = _top(y)
    return mx, my, tol * mx * my


@njit(cache=True, nogil=True)
def _top(v):  # pragma: no cover - compiled
    """``max |v_i|`` (0 for an empty ``v``) in four running maxima: one chain of compares
    waits on each step, four overlap (a maximum is exact in any order)."""
    m0 = m1 = m2 = m3 = 0.0
    n = v.shape[0]
    end = n - n % 4
    for i in range(0, end, 4):
        m0 = max(m0, abs(v[i]))
        m1 = max(m1, abs(v[i + 1]))
        m2 = max(m2, abs(v[i + 2]))
        m3 = max(m3, abs(v[i + 3]))
    for i in range(end, n):
        m0 = max(m0, abs(v[i]))
    return max(max(m0, m1), max(m2, m3))


@njit(cache=True, nogil=True)
def _kept(x, y, tol, ib, jb):  # pragma: no cover - compiled
    """The prefilter of ``_rows._pairs``: the ``i`` with ``|x_i| max|y| > cut`` into ``ib``,
    the ``j`` with ``|y_j| max|x| > cut`` into ``jb``; returns their counts and the cut."""
    mx, my, thr = _cut(x, y, tol)
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
def _exact(raw, scale, sqnorm, rule, cand, m, x, y, ib, ni, jb, nj, thr, score):
    """Scores of units ``cand[:m]`` (m <= 4) into ``score[:m]``: the sums of
    ``_rows.activate`` and the score of ``_rows._winner``, four independent sums per pass.

    The pass runs over the prefiltered grid of :func:`_kept` in the order of ``_rows._pairs``
    and adds ``raw * v`` where ``_pairs`` keeps ``v = x_i y_j`` and ``raw * 0`` (a zero) where
    it does not: adding a zero leaves a sum that started at +0 unchanged, so the sums are
    those of the kept pairs, bit for bit, without a branch or a list."""  # pragma: no cover
    ny = y.shape[0]
    c0, c1, c2, c3 = cand[0], cand[min(1, m - 1)], cand[min(2, m - 1)], cand[min(3, m - 1)]
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
            a0 += raw[p, c0] * v
            a1 += raw[p, c1] * v
            a2 += raw[p, c2] * v
            a3 += raw[p, c3] * v
    sums = (a0, a1, a2, a3)
    for g in range(m):
        k = cand[g]
        h = scale[k] * sums[g]
        if rule == MIN_DISTANCE:
            score[g] = 2.0 * h - scale[k] * scale[k] * sqnorm[k]
        else:
            score[g] = h


@njit(cache=True, nogil=True)
def _spans(x, y, tol, ncol, ib, j0, jn, top):  # pragma: no cover - compiled
    """The prefilter of :func:`_kept` as spans: the ``i`` with ``|x_i| max|y| > cut`` into
    ``ib``; per row of ``ncol`` columns of y's grid that holds a ``j`` with ``|y_j| max|x| >
    cut``, the columns from its first to its last such ``j`` (start ``j0``, length ``jn``)
    and their largest ``|y_j|`` (``top``); returns the counts of both and the cut. A span may
    hold a ``j`` the prefilter drops (a row's kept columns need not be adjacent): its
    products are below the cut, since ``|x_i y_j| <= max|x| |y_j|`` holds in rounded
    arithmetic too (rounding is monotone), and count as zeros."""
    mx, my, thr = _cut(x, y, tol)
    ni = 0
    for i in range(x.shape[0]):  # without a branch: stored, and kept by counting it
        ib[ni] = i
        ni += abs(x[i]) * my > thr
    nr = 0
    for r in range(y.shape[0] // ncol):
        first = ncol
        last = -1
        t = 0.0
        for c in range(ncol):
            a = abs(y[r * ncol + c])
            if a * mx > thr:
                last = c
                first = min(first, c)
                t = max(t, a)
        if last >= 0:
            j0[nr] = r * ncol + first
            jn[nr] = last - first + 1
            top[nr] = t
            nr += 1
    return ni, nr, thr


@njit(cache=True, nogil=True)
def _by_tile(x, members, xv, top, sq):  # pragma: no cover - compiled
    """A code by tile: ``xv[a, u] = x[members[a, u]]`` (0 where a tile has fewer points),
    ``top[a]`` its largest ``|x_i|`` and ``sq[a]`` its sum of squares; returns the code's
    largest ``|x_i|``."""
    m = 0.0
    for a in range(members.shape[0]):
        t = 0.0
        q = 0.0
        for u in range(members.shape[1]):
            i = members[a, u]
            v = x[i] if i >= 0 else 0.0
            xv[a, u] = v
            t = max(t, abs(v))
            q += v * v
        top[a] = t
        sq[a] = q
        m = max(m, t)
    return m


@njit(cache=True, nogil=True)
def _spread(v, n_mx, n_my, axis, out):  # pragma: no cover - compiled
    """A tile's values ``v`` of one code spread to a block's layout ``u * n_my + e``:
    ``out[u * n_my + e] = v[u]`` (``axis`` 0, x's tile) or ``v[e]`` (``axis`` 1, y's)."""
    for u in range(n_mx):
        for e in range(n_my):
            out[u * n_my + e] = v[u] if axis == 0 else v[e]


@njit(cache=True, nogil=True)
def _products(x, y, tol, members_x, members_y, xv, yv, xt, yt, xs, ys, xe, ye, tl, sv, vb):
    """The pair's tiles and products: the tiles ``a * tiles_y + b`` whose largest ``|x_i
    y_j|`` passes the cut of ``_rows._pairs`` into ``tl``, the norm of the pair's outer
    product on each ``|x_a| |y_b|`` (float32, rounded up) into ``sv``, and on row ``q`` of
    ``vb`` (laid out as a block of :class:`SearchIndex`) the products of tile ``tl[q]``:
    ``x_i y_j`` (rounded to ``vb``'s float32) where ``_pairs`` keeps it, else a zero. Every
    kept pair lies in such a tile (rounding is monotone: ``|x_i y_j| <= max_tile |x|
    max_tile |y|`` holds rounded too).
    ``xv, yv, xt, yt, xs, ys``: scratch of :func:`_by_tile`; ``xe`` ``(width,)`` and ``ye``
    ``(tiles_y, width)``: the codes' tiles spread to a block's layout (:func:`_spread`), so
    that a tile's products are one run. Returns the tile count; fills nothing if ``vb`` has
    fewer rows (call again with more)."""
    n_tx, n_ty = members_x.shape[0], members_y.shape[0]  # pragma: no cover - compiled
    n_mx, n_my = members_x.shape[1], members_y.shape[1]
    mx = _by_tile(x, members_x, xv, xt, xs)
    my = _by_tile(y, members_y, yv, yt, ys)
    thr = tol * mx * my
    n = 0
    for a in range(n_tx):
        if xt[a] * my <= thr:
            continue
        for b in range(n_ty):
            n += xt[a] * yt[b] > thr
    if n > vb.shape[0]:
        return n
    width = n_mx * n_my
    for b in range(n_ty):  # y's tiles that can pass, spread to a block's layout
        if yt[b] * mx > thr:
            _spread(yv[b], n_mx, n_my, np.int64(1), ye[b])  # not literals: one compilation
    n = 0
    for a in range(n_tx):
        if xt[a] * my <= thr:
            continue
        _spread(xv[a], n_mx, n_my, np.int64(0), xe)
        for b in range(n_ty):
            if xt[a] * yt[b] <= thr:
                continue
            yb = ye[b]
            row = vb[n]
            for e in range(width):  # one run of a block's width: the compiler's vectors
                v = xe[e] * yb[e]
                row[e] = v if abs(v) > thr else 0.0
            norm = np.sqrt(xs[a] * ys[b])
            n32 = np.float32(norm)
            sv[n] = n32 if n32 >= norm else np.nextafter(n32, np.float32(np.inf))
            tl[n] = a * n_ty + b
            n += 1
    return n


@njit(cache=True, nogil=True)
def _bounds(norms, tl, sv, n, k0, k1, c, rule, s, ub):  # pragma: no cover - compiled
    """``ub[k0:k1]``: upper bounds of the scores of units (or groups) ``k0 .. k1 - 1`` from
    the pair's tiles ``tl[:n]`` and norms ``sv`` (:func:`_products`) and the columns
    ``k0:k1`` of ``norms`` (``c``: the units' ``scale^2 |w|^2``, a group's least). The kept
    part of ``x y^T`` on a tile has a norm of at most ``|x_a| |y_b|``, so by Cauchy-Schwarz
    ``|h_k| <= sum_t |x_a| |y_b| norms[t, k]``; summed in float32 (eight a vector), ``n``
    positive terms within ``gamma_n < (n + 1) 2^-23`` of their exact sum, widened by that and
    :data:`MARGIN`."""
    m = k1 - k0
    ss = s[k0:k1]  # slices indexed from 0: no wrap-around check, vectors
    for k in range(m):
        ss[k] = 0.0
    for q in range(n):
        row = norms[tl[q], k0:k1]
        v = sv[q]
        for k in range(m):
            ss[k] += v * row[k]
    up = 1.0 + MARGIN + (n + 2) * F32_EPS
    if rule == MIN_DISTANCE:
        down = 1.0 - MARGIN
        for k in range(m):
            ub[k0 + k] = 2.0 * ss[k] * up - c[k0 + k] * down
    else:
        for k in range(m):
            ub[k0 + k] = ss[k] * up


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _approx(blocks, tl, n, vb):  # pragma: no cover - compiled
    """``sum_p w_p v_p`` over the tiles ``tl[:n]`` of one unit's ``blocks`` and the products
    ``vb`` of :func:`_products` (float32): each tile's sum in float32 in any order (the
    compiler's vectors, eight products a step), the tiles' sums in float64; within
    :func:`slack` of the sum in the order of ``_rows._pairs``."""
    acc = 0.0
    for q in range(n):
        w = blocks[tl[q]]
        v = vb[q]
        part = np.float32(0.0)
        for e in range(w.shape[0]):
            part += w[e] * v[e]
        acc += np.float64(part)
    return acc


def slack(width: int) -> float:
    """Relative slack of a score summed by :func:`_approx` (blocks of ``width`` input pairs,
    float32) against the score summed in the order of ``_rows._pairs`` (float64). A tile's
    float32 sum of ``width`` products, each a float32 weight times a product rounded to
    float32, in any order, lies within ``gamma_{width + 1}`` (float32) of its exact value
    relative to the sum of the magnitudes ``A_t``; the float64 sums within ``gamma_n A``
    (``n <= 50,625``: 6e-12 A). ``scale_k A`` is at most the unit's tile bound, and
    ``|bound| + 2 scale_k^2 |w_k|^2`` at least twice that, so the slack ``slack (|bound| +
    |score| + 2 scale_k^2 |w_k|^2)`` covers a min-distance score's ``2 scale_k`` times that
    error with room (paper-2d: blocks of 81, a slack of 1e-5; 3.5 pairs in 10,000 then sum
    some units again)."""
    return (width + 2) * F32_EPS + 1e-10


@njit(cache=True, nogil=True)
def _score(blocks, scale, sqnorm, rule, k, tl, n, vb):  # pragma: no cover - compiled
    """Unit ``k``'s score for the pair, summed in any order (:func:`_approx`)."""
    h = scale[k] * _approx(blocks[k], tl, n, vb)
    return 2.0 * h - scale[k] * scale[k] * sqnorm[k] if rule == MIN_DISTANCE else h


@njit(cache=True, nogil=True)
def _settle_row(index, raw, scale, sqnorm, c, x, y, tol, rule, rel, tl, sv, n, vb, work, cands):
    """The winner of one pair from its tiles and products (``tl[:n]``, ``sv``, ``vb``,
    :func:`_products`): the bounds of the groups of :data:`GROUP` units first; the group
    of the best bound gets its units' bounds and the unit of the best of those is scored
    (:func:`_approx`, with the slack of :func:`slack`); then, best group first, every group
    whose bound reaches the largest lower end of a score so far gets its units' bounds, and
    every unit of it whose bound reaches that is scored. If more than one unit's score may
    reach the best one's, those few are summed again in the order of ``_rows._pairs``
    (:func:`_exact`) and the best of them wins, ties to the lowest index. A unit left out
    has a bound below a score some unit reaches, and a unit outscored beyond both slacks
    cannot win: the winners of the full search, bit for bit. ``index``: the
    :class:`SearchIndex` arrays ``(blocks, norms, group_norms, group_c)``; ``work``: float
    scratch ``(6, K)``; ``cands``: int64 scratch ``(K,)``."""  # pragma: no cover - compiled
    blocks, norms, gnorms, gc = index
    k_units = blocks.shape[0]
    ub, ubg, cand, near, done = work[0], work[1], work[2], work[3], work[4]
    s32 = work[5].view(np.float32)
    n_groups = gnorms.shape[1]
    _bounds(gnorms, tl, sv, n, np.int64(0), n_groups, gc, rule, s32, ubg)  # not a literal
    m = 0  # units scored: done[:m] (as floats), their scores cand[:m] and slacks near[:m]
    low = -np.inf  # the largest lower end of a score so far
    best = 0  # the position in done of the best score
    first = -1
    nc = 0  # the candidates: units whose bound reaches low, group by group
    while True:
        g = 0
        for j in range(1, n_groups):
            if ubg[j] > ubg[g]:
                g = j
        if ubg[g] == -np.inf or ubg[g] < low:
            break
        ubg[g] = -np.inf
        k0 = g * GROUP
        k1 = min(k_units, k0 + GROUP)
        _bounds(norms, tl, sv, n, k0, k1, c, rule, s32, ub)
        if first < 0:  # the best bound of the best group: scored first, for a first low
            first = k0
            for k in range(k0 + 1, k1):
                if ub[k] > ub[first]:
                    first = k
            a = _score(blocks, scale, sqnorm, rule, first, tl, n, vb)
            d = rel * (abs(ub[first]) + abs(a) + 2.0 * c[first])
            done[0] = first
            cand[0] = a
            near[0] = d
            m = 1
            low = a - d
        for k in range(k0, k1):
            if k != first and ub[k] >= low:
                cands[nc] = k
                nc += 1
    while True:  # the candidates, best bound first, while their bound reaches low
        q = -1
        for t in range(nc):
            if cands[t] >= 0 and (q < 0 or ub[cands[t]] > ub[cands[q]]):
                q = t
        if q < 0 or ub[cands[q]] < low:
            break
        k = cands[q]
        cands[q] = -1
        a = _score(blocks, scale, sqnorm, rule, k, tl, n, vb)
        d = rel * (abs(ub[k]) + abs(a) + 2.0 * c[k])
        done[m] = k
        cand[m] = a
        near[m] = d
        if a > cand[best]:
            best = m
        low = max(low, a - d)
        m += 1
    lo = cand[best] - near[best]
    units = np.empty(m, dtype=np.int64)
    nn = np.int64(0)  # not a literal: one compilation of _exact_best
    for q in range(m):
        if cand[q] + near[q] >= lo:
            units[nn] = int(done[q])
            nn += 1
    if nn == 1:
        return units[0]
    return _exact_best(raw, scale, sqnorm, rule, x, y, tol, units, nn)


@njit(cache=True, nogil=True)
def _exact_best(raw, scale, sqnorm, rule, x, y, tol, units, nu):  # pragma: no cover
    """The best of units ``units[:nu]`` by their scores in the order of ``_rows._pairs``
    (:func:`_exact`, four at a time); ties to the lowest index."""
    ib = np.empty(x.shape[0], dtype=np.int64)
    jb = np.empty(y.shape[0], dtype=np.int64)
    cand = np.empty(4, dtype=np.int64)
    score = np.empty(4)
    ni, nj, thr = _kept(x, y, tol, ib, jb)
    best = -np.inf
    win = -1
    for s in range(0, nu, 4):
        m = min(4, nu - s)
        for g in range(m):
            cand[g] = units[s + g]
        _exact(raw, scale, sqnorm, rule, cand, m, x, y, ib, ni, jb, nj, thr, score)
        for g in range(m):
            if score[g] > best or (score[g] == best and cand[g] < win):
                best = score[g]
                win = cand[g]
    return win


@njit(cache=True, parallel=True)
def _peaks(x, y, tile_x, tile_y, key):  # pragma: no cover - compiled
    """``key[b]``: the tiles of the peaks of ``|x_b|`` and ``|y_b|`` (``tile_x[i] * tiles_y +
    tile_y[j]``): pairs of one key read mostly the same tiles of mostly the same units."""
    ny = y.shape[1]
    n_ty = tile_y.max() + 1
    for b in prange(x.shape[0]):
        i = 0
        for t in range(1, x.shape[1]):
            if abs(x[b, t]) > abs(x[b, i]):
                i = t
        j = 0
        for t in range(1, ny):
            if abs(y[b, t]) > abs(y[b, j]):
                j = t
        key[b] = tile_x[i] * n_ty + tile_y[j]


@njit(cache=True, parallel=True)
def _settle_rows(
    index, raw, scale, sqnorm, c, members_x, members_y, x, y, tol, rule, rel, order, out
):  # pragma: no cover - compiled
    """:func:`_settle_row` for every row, in parallel blocks of :data:`ROWS` rows visited in
    ``order``."""
    n_rows = x.shape[0]
    k_units = raw.shape[1]
    n_tx, n_ty = members_x.shape[0], members_y.shape[0]
    width = members_x.shape[1] * members_y.shape[1]
    for ch in prange((n_rows + ROWS - 1) // ROWS):
        xv = np.empty(members_x.shape)
        yv = np.empty(members_y.shape)
        xt = np.empty(n_tx)
        yt = np.empty(n_ty)
        xs = np.empty(n_tx)
        ys = np.empty(n_ty)
        tl = np.empty(n_tx * n_ty, dtype=np.int64)
        sv = np.empty(n_tx * n_ty, dtype=np.float32)
        xe = np.empty(width)
        ye = np.empty((n_ty, width))
        vb = np.empty((64, width), dtype=np.float32)
        work = np.empty((6, k_units))
        cands = np.empty(k_units, dtype=np.int64)
        for r in range(ch * ROWS, min(n_rows, (ch + 1) * ROWS)):
            b = order[r]
            # left unformatted: the arguments in the rows of the kernel's signature
            n = _products(x[b], y[b], tol, members_x, members_y, xv, yv, xt, yt, xs, ys, xe,
                          ye, tl, sv, vb)  # fmt: skip
            if n > vb.shape[0]:
                vb = np.empty((n, width), dtype=np.float32)
                n = _products(x[b], y[b], tol, members_x, members_y, xv, yv, xt, yt, xs, ys,
                              xe, ye, tl, sv, vb)  # fmt: skip
            out[b] = _settle_row(index, raw, scale, sqnorm, c, x[b], y[b], tol, rule, rel, tl,
                                 sv, n, vb, work, cands)  # fmt: skip


def search(
    index: SearchIndex,
    raw: NDArray[np.floating],
    sqnorm: NDArray[np.float64],
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    tol: float,
    rule: int,
    exact: bool = True,
) -> NDArray[np.int64]:
    """Winners ``(B,)`` of the pairs ``(x_b, y_b)`` under the compiled rule ``rule`` (one of
    :data:`RULES`) on the weights ``raw`` of ``index`` (with their exact ``sqnorm``): the
    bounds of all pairs first, then the scores of the units that can win, with the pairs
    ordered by their likely winner (so that pairs reading the same units come together).
    ``exact`` False (the refinement's fast path): the best of the float32 scores, no slack
    and no exact re-check (only scores equal to the last bit are summed again)."""
    n_rows = x.shape[0]
    c = index.scale * index.scale * sqnorm
    k_units, n_groups = c.size, index.group_norms.shape[1]
    gc = np.full(n_groups * GROUP, np.inf)
    gc[:k_units] = c
    gc = gc.reshape(n_groups, GROUP).min(axis=1)  # a group's least scale^2 |w|^2
    key = index.work("key", n_rows, 0, np.int64)
    peaks: Any = _peaks  # numba dispatchers
    settle: Any = _settle_rows
    peaks(x, y, index.tile_x, index.tile_y, key)
    order = np.argsort(key, kind="stable")
    out = np.empty(n_rows, dtype=np.int64)
    arrays = (index.blocks, index.norms, index.group_norms, gc)
    # left unformatted: the arguments in the rows of the kernel's signature
    rel = slack(index.blocks.shape[2]) if exact else 0.0
    settle(arrays, raw, index.scale, sqnorm, c, index.members_x, index.members_y, x, y,
           float(tol), int(rule), rel, order, out)  # fmt: skip
    return out


@njit(cache=True, parallel=True)
def _hard_sums(sums, mass, order, starts, x1, y1, tol, ncol):  # pragma: no cover - compiled
    """``sums[k, p] += v_p`` over the kept pairs ``p`` of view 1 of every pair that unit
    ``k`` won and ``mass[k] += 1`` per such pair; ``order[starts[k]:starts[k + 1]]``: those
    pairs in their order. Parallel over units (each unit's sums on one thread, its pairs in
    order). Runs over the spans of :func:`_spans` (adjacent columns of a row of y's grid, so
    that the compiler adds several at once; a span none of whose products with ``x_i``
    passes the cut is skipped) and adds a zero where ``_rows._pairs`` drops a
    pair (a sum that started at +0 is unchanged by it), without a branch or a list."""
    k_units = sums.shape[0]
    ny = y1.shape[1]
    for c in prange((k_units + 15) // 16):
        ib = np.empty(x1.shape[1], dtype=np.int64)
        j0 = np.empty(ny, dtype=np.int64)
        jn = np.empty(ny, dtype=np.int64)
        top = np.empty(ny)
        for k in range(c * 16, min(k_units, c * 16 + 16)):
            row = sums[k]
            for r in range(starts[k], starts[k + 1]):
                b = order[r]
                x = x1[b]
                y = y1[b]
                ni, nr, thr = _spans(x, y, tol, ncol, ib, j0, jn, top)
                for u in range(ni):
                    i = ib[u]
                    xi = x[i]
                    ax = abs(xi)
                    base = i * ny
                    for q in range(nr):
                        if ax * top[q] <= thr:  # no product of the span passes the cut
                            continue
                        m = jn[q]
                        ys = y[j0[q] : j0[q] + m]  # from 0: no wrap-around check, vectors
                        rs = row[base + j0[q] : base + j0[q] + m]
                        for t in range(m):
                            v = xi * ys[t]
                            rs[t] += v if abs(v) > thr else 0.0
                mass[k] += 1.0


def hard_sums(
    sums: NDArray[np.floating],
    mass: NDArray[np.float64],
    winners: NDArray[np.int64],
    x1: NDArray[np.float64],
    y1: NDArray[np.float64],
    tol: float,
    ncol: int = 0,
) -> None:
    """Add the pairs ``(x1_b, y1_b)`` to the sums ``(K, n_x n_y)`` and ``mass`` of their
    winners, each unit's pairs in order: the arithmetic of
    :meth:`sigmapi.rules.BatchMean.accumulate` at ``sigma = 0`` (a unit's sums gain
    ``1 * v = v``, the others' a zero), bit for bit, on the kernel's sparse pairs (float32
    ``sums``, the refinement's fast path: each sum rounded to float32). ``ncol``: the columns
    of a row of y's grid (0: y a line)."""
    order = np.argsort(winners, kind="stable")
    starts = np.searchsorted(winners[order], np.arange(sums.shape[0] + 1))
    driver: Any = _hard_sums  # a numba dispatcher
    driver(sums, mass, order, starts, x1, y1, float(tol), int(ncol or y1.shape[1]))


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
    sums: NDArray[np.floating],
    mass: NDArray[np.float64],
) -> NDArray[np.floating]:
    """The new unscaled weights ``(n_x n_y, K)`` (scales 1) in ``raw``'s type: what
    ``prepare(BATCH_MEAN.finish(export(state), sums))`` stores, bit for bit, without the
    dense float64 copies."""
    out = np.empty_like(raw)
    driver: Any = _finish  # a numba dispatcher
    driver(raw, scale, sums, mass, out)
    return out
