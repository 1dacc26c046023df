"""Metrics of maps of angles: z on a circle, a map that may be a ring (docs/algorithm.md).

For a relation whose z is circular (``Relation.circular``, e.g. ``"sum_mod"``), z is a
fraction of a turn in ``[0, 1)`` per axis, and 0.99 lies as near 0.01 as 0.03 does. The
linear metrics of :mod:`sigmapi.metrics` would call that distance 0.98, so for such relations
:func:`circular_metrics` gives:

- **z error**: the decoded z of a unit is the *circular* mean of its wins on the calibration
  set (units that never win there: the ring fit below); the error is the difference the
  shorter way round, RMSE in input grid spacings (as for bounded maps).
- **circular order** ``order_circular``: a ring of ``K`` units ordered by angle puts unit
  ``k`` at ``z = (s k / K + c) mod 1``, ``s = +1`` or ``-1``. Per z axis the fit picks the
  map axis and the sign that best explain the calibration z (largest mean resultant length
  of the residual angles) and ``c`` is the circular mean residual; the score on the test set
  is ``1 - mean(wrap(z - fit)^2) / mean(wrap(z - circular mean z)^2)``, the circular
  analogue of order R^2 (1: ordered once round the ring; about 0 or below: a map that winds
  twice, folds, or is scrambled; a rotated or mirrored ring is not penalised).
- **seam**: where z wraps from 1 to 0, an ordered ring has two neighbouring units, each
  winning its share. ``seam_jump``: the largest difference (the shorter way round, input grid
  spacings) between the decoded z of two grid-neighbouring units that both win (the
  wrap-around pair of a periodic map included): one grid spacing per map unit on an ordered
  15-unit ring of 15-unit codes, more at a seam or a fold. ``seam_gap``: the largest map
  distance (Chebyshev, the shorter way round on a periodic map) between two winning units
  whose decoded z lie within ``NEAR_STEPS`` steps of each other (the shorter way round): 1
  on an ordered ring; ``K - 1`` on a bounded map, whose two ends decode neighbouring angles
  (wherever on the circle the map's ends lie, not only at z = 0). ``seam_units_win``:
  along every z axis some unit decodes z within ``NEAR_STEPS`` steps of the wrap on each
  side, and every unit there (units that never win included, placed by the ring fit) wins
  often enough not to be starved (:func:`sigmapi.metrics.starved_mask`). ``seamless``:
  ``seam_units_win``, ``seam_gap <= 1`` and ``seam_jump`` at most ``SEAM_JUMP_STEPS`` (2)
  ideal steps (a map unit's share of the turn in grid spacings: 1 for 15 units on 15-unit
  codes).

A step is ``1 / K_a`` of a turn, ``K_a`` the units along the map axis fitted to z axis ``a``.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "CIRCULAR_KEYS",
    "NEAR_STEPS",
    "RingFit",
    "circular_means",
    "circular_metrics",
    "map_distance",
    "ring_fit",
    "seam",
    "wrap",
]

Array = NDArray[np.float64]

SEAM_JUMP_STEPS = 2.0
"""``seamless`` needs ``seam_jump`` within this many ideal steps (one map unit's share of
the turn, in input grid spacings)."""

NEAR_STEPS = 1.5
"""Two units decode z near each other when their decoded z differ by at most this many steps
(``1 / K`` of a turn) along every z axis: neighbours on an ordered ring differ by one."""

CIRCULAR_KEYS = ("order_circular", "seam_jump", "seam_gap", "seam_units_win", "seamless")
"""The metrics :func:`circular_metrics` adds for maps of angles (beside a circular z error)."""


def wrap(d: Array) -> Array:
    """Angle differences (fractions of a turn) the shorter way round: into ``[-0.5, 0.5]``."""
    return np.asarray(d - np.round(d))


def circular_means(
    groups: NDArray[np.int64], z: Array, n_groups: int
) -> tuple[Array, NDArray[np.float64]]:
    """Circular mean of the rows of ``z`` ``(N, d)`` in each group; ``(n_groups, d)`` in
    ``[0, 1)`` and the count of each group ``(n_groups,)`` (groups without rows: 0, count 0)."""
    counts = np.bincount(groups, minlength=n_groups).astype(np.float64)
    ang = 2.0 * np.pi * z
    c = np.zeros((n_groups, z.shape[1]))
    s = np.zeros((n_groups, z.shape[1]))
    np.add.at(c, groups, np.cos(ang))
    np.add.at(s, groups, np.sin(ang))
    return np.arctan2(s, c) / (2.0 * np.pi) % 1.0, counts


class RingFit:
    """``z_a = (sign_a coords[:, axis_a] / size_a + offset_a) mod 1`` per z axis ``a``.

    Built by :func:`ring_fit`; ``axes[a] = -1`` where no map axis is left for z axis ``a``
    (a map of fewer dimensions than z): that axis is predicted by ``offset_a`` alone.
    """

    def __init__(self, axes: list[int], signs: list[float], offsets: Array, sizes: Array):
        self.axes, self.signs, self.offsets, self.sizes = axes, signs, offsets, sizes

    def predict(self, coords: Array) -> Array:
        """Fitted z ``(N, d)`` in ``[0, 1)`` of map coordinates ``(N, map_ndim)``."""
        out = np.empty((coords.shape[0], len(self.axes)))
        for a, (ax, s) in enumerate(zip(self.axes, self.signs, strict=True)):
            lin = s * coords[:, ax] / self.sizes[ax] if ax >= 0 else 0.0
            out[:, a] = (lin + self.offsets[a]) % 1.0
        return out

    def step(self) -> Array:
        """Fraction of a turn between neighbouring units along each z axis's map axis."""
        return np.array([1.0 / self.sizes[ax] if ax >= 0 else 1.0 for ax in self.axes])


def ring_fit(coords: Array, z: Array, map_shape: tuple[int, ...]) -> RingFit:
    """The :class:`RingFit` of winners' map coordinates ``(N, map_ndim)`` to z ``(N, d)``.

    Tries every assignment of map axes to z axes and both signs per axis; keeps the one with
    the largest summed mean resultant length of ``z - sign coords / size``.
    """
    sizes = np.asarray(map_shape, dtype=np.float64)
    d, m = z.shape[1], coords.shape[1]
    best: tuple[float, RingFit] | None = None
    for perm in itertools.permutations(range(m), min(m, d)):
        axes = [*perm, *([-1] * (d - len(perm)))]
        for signs in itertools.product((1.0, -1.0), repeat=d):
            fit = RingFit(axes, list(signs), np.zeros(d), sizes)
            resid = 2.0 * np.pi * (z - fit.predict(coords))
            c, s = np.cos(resid).mean(axis=0), np.sin(resid).mean(axis=0)
            length = float(np.hypot(c, s).sum())
            if best is None or length > best[0]:
                fit.offsets = np.arctan2(s, c) / (2.0 * np.pi) % 1.0
                best = (length, fit)
    assert best is not None
    return best[1]


def _neighbour_pairs(map_shape: tuple[int, ...], periodic: bool) -> NDArray[np.int64]:
    """Flat indices ``(P, 2)`` of the grid-neighbour pairs (one step along one axis)."""
    idx = np.arange(int(np.prod(map_shape))).reshape(map_shape)
    pairs = []
    for ax, n in enumerate(map_shape):
        if n < 2:
            continue
        nxt = np.roll(idx, -1, axis=ax)
        a, b = idx, nxt
        if not periodic or n == 2:  # drop the wrap-around pair (n == 2: it repeats the other)
            keep = [slice(None)] * len(map_shape)
            keep[ax] = slice(0, n - 1)
            a, b = idx[tuple(keep)], nxt[tuple(keep)]
        pairs.append(np.stack([a.ravel(), b.ravel()], axis=1))
    return np.concatenate(pairs) if pairs else np.empty((0, 2), dtype=np.int64)


def map_distance(
    coords: Array,
    a: NDArray[np.int64],
    b: NDArray[np.int64],
    map_shape: tuple[int, ...],
    periodic: bool,
) -> Array:
    """Chebyshev distance on the map grid between units ``a`` and ``b``, the shorter way
    round on a ``periodic`` map of ``map_shape``; ``(len(a),)``."""
    diff = np.abs(coords[a] - coords[b])
    if periodic:
        diff = np.minimum(diff, np.asarray(map_shape, dtype=np.float64) - diff)
    return np.asarray(diff.max(axis=1, initial=0.0))


def seam(
    table: Array,
    won: NDArray[np.bool_],
    starved: NDArray[np.bool_],
    fit: RingFit,
    coords: Array,
    map_shape: tuple[int, ...],
    periodic: bool,
    spacing: Array,
) -> dict[str, Any]:
    """``seam_jump``, ``seam_gap``, ``seam_units_win`` and ``seamless`` (module docstring).

    ``table`` ``(K, d)``: decoded z of every unit; ``won``: units that win on the calibration
    set; ``starved``: units below their share of the test views; ``spacing`` ``(d,)``: input
    grid spacings per turn.
    """
    step = fit.step()
    pairs = _neighbour_pairs(map_shape, periodic)
    pairs = pairs[won[pairs[:, 0]] & won[pairs[:, 1]]]
    jumps = np.sqrt(((wrap(table[pairs[:, 0]] - table[pairs[:, 1]]) * spacing) ** 2).sum(axis=1))
    seam_jump = float(jumps.max(initial=0.0))

    units = np.flatnonzero(won)
    a, b = (g.ravel() for g in np.meshgrid(units, units, indexing="ij"))
    diff = table[a] - table[b]
    near = np.all(np.abs(wrap(diff)) <= NEAR_STEPS * step, axis=1)
    dist = map_distance(coords, a[near], b[near], map_shape, periodic)
    seam_gap = float(dist.max(initial=0.0))

    units_win = True
    for ax in range(table.shape[1]):
        low = table[:, ax] <= NEAR_STEPS * step[ax]
        high = table[:, ax] >= 1.0 - NEAR_STEPS * step[ax]
        if not (low.any() and high.any()) or starved[low | high].any():
            units_win = False
    ideal = float(np.sqrt(((step * spacing) ** 2).sum()))
    return {
        "seam_jump": seam_jump,
        "seam_gap": seam_gap,
        "seam_units_win": units_win,
        "seamless": bool(units_win and seam_gap <= 1.0 and seam_jump <= SEAM_JUMP_STEPS * ideal),
    }


def circular_metrics(
    wc: NDArray[np.int64],
    z_cal: Array,
    w0: NDArray[np.int64],
    z_test: Array,
    coords: Array,
    map_shape: tuple[int, ...],
    periodic: bool,
    spacing: Array,
    starved: NDArray[np.bool_],
) -> dict[str, Any]:
    """Metrics of a map of angles (module docstring): ``z_error`` (circular) and the extra
    keys ``order_circular``, ``seam_jump``, ``seam_gap``, ``seam_units_win``, ``seamless``.

    ``wc``: winners of the calibration views, ``z_cal`` their z ``(N, d)`` in [0, 1);
    ``w0``: winners of test view 0, ``z_test`` their z; ``coords`` ``(K, map_ndim)``: map
    grid coordinates; ``periodic``: the map wraps around; ``spacing`` ``(d,)``: input grid
    spacings per turn (the code's units along each axis); ``starved`` ``(K,)``: the starved
    units (:func:`sigmapi.metrics.starved_mask` of both test views).
    """
    k = coords.shape[0]
    fit = ring_fit(coords[wc], z_cal, map_shape)
    table, counts = circular_means(wc, z_cal, k)
    won = counts > 0
    table[~won] = fit.predict(coords[~won])
    err = wrap(table[w0] - z_test) * spacing
    z_error = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))

    resid = wrap(z_test - fit.predict(coords[w0]))
    mean_z, _ = circular_means(np.zeros(len(z_test), dtype=np.int64), z_test, 1)
    spread = float(np.sum(wrap(z_test - mean_z) ** 2))
    order = 1.0 - float(np.sum(resid**2)) / spread if spread > 0 else float("nan")

    out = {"z_error": z_error, "order_circular": order}
    out.update(seam(table, won, starved, fit, coords, map_shape, periodic, spacing))
    return out
