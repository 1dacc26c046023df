"""Relations z = f(x, y) and the two-view sampler that feeds the Sigma-Pi SOM.

Per iteration and per dimension (docs/algorithm.md): draw z uniformly over the relation's z range;
draw one view by choosing x or y uniformly with probability 1/2 each and solving the relation
for the other; reject and redraw the view until both lie in [0, 1]. Draw a second view of the
same z the same way. The authors' relation is the mean ``z = (x + y) / 2``, which keeps z on
the same [0, 1] axis as x and y.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError

__all__ = [
    "RELATIONS",
    "Batch",
    "Frames",
    "Relation",
    "TwoViewSampler",
    "get_relation",
    "kronecker",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Relation:
    """A relation ``z = forward(x, y)`` with its two inverses, elementwise on positions.

    Parameters
    ----------
    name : str
        Identifier stored in model files (custom relations cannot be restored by name).
    forward : callable
        ``z = forward(x, y)``.
    solve_y : callable
        ``y = solve_y(z, x)``: the y that gives z with this x.
    solve_x : callable
        ``x = solve_x(z, y)``: the x that gives z with this y.
    z_range : (float, float)
        Interval z is drawn from uniformly.
    x_bounds, y_bounds : callable, optional
        ``(lo, hi) = x_bounds(z)``: the x in [0, 1] that have a y in [0, 1] for this z (and
        likewise for y). Given for the built-in relations, so that the rare z whose views are
        hard to hit by rejection (z within a hair of the border) are drawn from the same
        distribution directly instead of after millions of rejections.
    circular : bool
        z is an angle, a fraction of a turn in [0, 1) where 0 and 1 are the same place (for
        periodic codes): the metrics measure z the shorter way round the circle.

    Examples
    --------
    >>> rel = Relation("shift", lambda x, y: x - y + 0.5, lambda z, x: x + 0.5 - z,
    ...                lambda z, y: z + y - 0.5, (0.0, 1.0))
    >>> round(float(rel.forward(0.7, 0.4)), 12)
    0.8
    """

    name: str
    forward: Callable[[Array, Array], Array]
    solve_y: Callable[[Array, Array], Array]
    solve_x: Callable[[Array, Array], Array]
    z_range: tuple[float, float] = (0.0, 1.0)
    x_bounds: Callable[[Array], tuple[Array, Array]] | None = None
    y_bounds: Callable[[Array], tuple[Array, Array]] | None = None
    circular: bool = False


def _clip01(lo: Array, hi: Array) -> tuple[Array, Array]:
    return np.maximum(lo, 0.0), np.minimum(hi, 1.0)


def _whole_turn(z: Array) -> tuple[Array, Array]:
    """Bounds of a circular relation: every angle in [0, 1) has a partner for every z."""
    return np.zeros_like(z), np.ones_like(z)


RELATIONS: dict[str, Relation] = {
    "mean": Relation(
        "mean",
        lambda x, y: (x + y) / 2,
        lambda z, x: 2 * z - x,
        lambda z, y: 2 * z - y,
        (0.0, 1.0),
        lambda z: _clip01(2 * z - 1, 2 * z),
        lambda z: _clip01(2 * z - 1, 2 * z),
    ),
    "sum": Relation(
        "sum",
        lambda x, y: x + y,
        lambda z, x: z - x,
        lambda z, y: z - y,
        (0.0, 2.0),
        lambda z: _clip01(z - 1, z),
        lambda z: _clip01(z - 1, z),
    ),
    "difference": Relation(
        "difference",
        lambda x, y: x - y,
        lambda z, x: x - z,
        lambda z, y: z + y,
        (-1.0, 1.0),
        lambda z: _clip01(z, 1 + z),
        lambda z: _clip01(-z, 1 - z),
    ),
    "sum_mod": Relation(
        "sum_mod",
        lambda x, y: (x + y) % 1.0,
        lambda z, x: (z - x) % 1.0,
        lambda z, y: (z - y) % 1.0,
        (0.0, 1.0),
        _whole_turn,
        _whole_turn,
        circular=True,
    ),
}
"""Built-in relations: the paper's ``mean``, the plain ``sum``, the ``difference`` x - y, and
``sum_mod``, z = (x + y) mod 1, for angles as fractions of a turn (a head direction from the
body's direction and the head-on-body angle; needs periodic codes): every x goes with every
z, so the sampler accepts each view at its first draw."""


def get_relation(relation: str | Relation) -> Relation:
    """Look up a built-in relation by name, or pass a :class:`Relation` through."""
    if isinstance(relation, Relation):
        return relation
    try:
        return RELATIONS[relation]
    except (KeyError, TypeError):
        raise _validate.fail(
            "relation", f"one of {sorted(RELATIONS)} or a sigmapi.Relation", relation
        ) from None


class Batch(NamedTuple):
    """Two views of the same body-centred positions, as codes and as positions.

    Codes have shape ``(B, n_x)`` / ``(B, n_y)``; positions ``(B, d)``.
    """

    x0: Array
    y0: Array
    x1: Array
    y1: Array
    z: Array
    px0: Array
    py0: Array
    px1: Array
    py1: Array


class Frames(NamedTuple):
    """A stream of views in time order (:meth:`TwoViewSampler.stream`).

    Codes ``x`` ``(T, n_x)``, ``y`` ``(T, n_y)``; positions ``z``, ``px``, ``py`` ``(T, d)``;
    ``moved`` ``(T,)``: frame t shows the object at a new position (frame 0 does). A learner
    reads the codes only.
    """

    x: Array
    y: Array
    z: Array
    px: Array
    py: Array
    moved: NDArray[np.bool_]


_REJECTION_ROUNDS = 8
_MAX_ROUNDS = 1_000_000


def _check_rows(n: int, each: int, fix: str) -> None:
    """The memory check of ``n`` rows of ``each`` bytes (:func:`sigmapi._memory.check_count`),
    skipped below 64 MiB: a training block's draw costs no read of the system's memory."""
    if n * each > 1 << 26:
        _memory.check_count("n", n, each, fix)


def _numpy_encode(code: PopulationCode, p: Array, out: Array | None = None) -> Array:
    codes = code.encode(p)
    if out is None:
        return codes
    out[...] = codes
    return out


@functools.cache
def _encoder() -> Callable[[PopulationCode, Array, Array | None], Array]:
    """``code.encode`` (into ``out`` when given), compiled where numba imports
    (:mod:`sigmapi.kernels._codes`, the same codes bit for bit, a tenth of the CPU time on
    2-D codes), else NumPy's."""
    try:
        from sigmapi.kernels._codes import encode
    except ImportError:  # numba missing or broken here: NumPy's encode
        return _numpy_encode
    return encode


@functools.cache
def _fast_encoder() -> Callable[[PopulationCode, Array, Array | None], Array]:
    """The refinement's encoder within rounding (:func:`sigmapi.kernels._codes.encode_fast`)
    where numba imports, else NumPy's."""
    try:
        from sigmapi.kernels._codes import encode_fast
    except ImportError:  # numba missing or broken here: NumPy's encode
        return _numpy_encode
    return encode_fast


@functools.cache
def _kronecker_step(dims: int) -> Array:
    """The R_d sequence's step in ``dims`` dimensions: the powers ``1/g, 1/g^2, ...`` of the
    root ``g > 1`` of ``g^(dims + 1) = g + 1`` (the golden ratio for ``dims = 1``)."""
    g = 2.0
    for _ in range(64):  # the fixed point iteration converges to float64 precision
        g = (1.0 + g) ** (1.0 / (dims + 1))
    return np.asarray((1.0 / g) ** np.arange(1, dims + 1), dtype=np.float64)


def kronecker(first: int, n: int, shift: Array) -> Array:
    """Points ``first .. first + n - 1`` of a randomly shifted Kronecker sequence in the unit
    cube of ``len(shift)`` dimensions, ``(n, d)``: point ``i`` is
    ``frac(shift + (i + 1) * alpha)`` with ``alpha`` the R_d sequence's step (Roberts 2018,
    "The unreasonable effectiveness of quasirandom sequences"), a low-discrepancy sequence;
    ``shift`` uniform in the cube (a Cranley-Patterson rotation) makes every point uniform
    and the set's means unbiased. Any stretch of the sequence is computed on its own, so a
    draw cut into blocks is the same points.

    Examples
    --------
    >>> p = kronecker(0, 4, np.zeros(1))
    >>> np.round(p[:, 0], 3).tolist()
    [0.618, 0.236, 0.854, 0.472]
    >>> bool(np.array_equal(kronecker(2, 2, np.zeros(1)), p[2:]))
    True
    """
    shift = np.asarray(shift, dtype=np.float64)
    i = np.arange(first + 1, first + n + 1, dtype=np.float64)[:, None]
    return np.asarray((shift + i * _kronecker_step(shift.size)) % 1.0, dtype=np.float64)


class TwoViewSampler:
    """Draws batches of two views (x0, y0), (x1, y1) of the same z.

    Parameters
    ----------
    relation : str or Relation
        ``"mean"`` (the paper), ``"sum"``, ``"difference"``, ``"sum_mod"`` (angles) or a
        custom :class:`Relation`.
    x_code, y_code : PopulationCode
        Codes of the retinal position x and the gaze direction y; same number of dimensions.

    Examples
    --------
    >>> from sigmapi.codes import PopulationCode
    >>> s = TwoViewSampler("mean", PopulationCode((15,)), PopulationCode((15,)))
    >>> b = s.sample(4, np.random.default_rng(0))
    >>> b.x0.shape, b.z.shape
    ((4, 15), (4, 1))
    >>> bool(np.allclose((b.px0 + b.py0) / 2, b.z) and np.allclose((b.px1 + b.py1) / 2, b.z))
    True
    """

    def __init__(self, relation: str | Relation, x_code: PopulationCode, y_code: PopulationCode):
        if x_code.ndim != y_code.ndim:
            raise ConfigError(
                f"x_code and y_code must have the same number of dimensions, got "
                f"{x_code.ndim} and {y_code.ndim}"
            )
        self.relation = get_relation(relation)
        self.x_code = x_code
        self.y_code = y_code
        self.ndim = x_code.ndim

    def sample_z(self, n: int, rng: np.random.Generator) -> Array:
        _check_rows(n, 8 * self.ndim, "draw fewer positions")
        lo, hi = self.relation.z_range
        return rng.uniform(lo, hi, size=(n, self.ndim))

    def sample_view(self, z: Array, rng: np.random.Generator) -> tuple[Array, Array]:
        """One view (x, y) in [0, 1] per entry of ``z`` (shape ``(B, d)``), by rejection.

        As the authors did: pick x or y with probability 1/2, draw it uniformly in [0, 1],
        solve the relation for the other, and redraw unless both lie in [0, 1] (the first 8
        rounds are drawn for all entries at once and the first accepted one kept). Entries still
        rejected after 8 rounds (z very near a border, acceptance ~ 2 z) are drawn from the
        distribution rejection converges to: the coin weighted by the lengths of the feasible
        intervals, then uniform within the interval (for relations that give bounds).
        """
        rel = self.relation
        # the first 8 rounds of rejection for every entry at once: (B, d, rounds)
        zz = np.broadcast_to(z[..., None], (*z.shape, _REJECTION_ROUNDS))
        pick_x = rng.random(zz.shape) < 0.5
        u = rng.random(zz.shape)
        xx = np.where(pick_x, u, rel.solve_x(zz, u))
        yy = np.where(pick_x, rel.solve_y(zz, u), u)
        ok = (xx >= 0) & (xx <= 1) & (yy >= 0) & (yy <= 1)
        first = np.argmax(ok, axis=-1)[..., None]  # the first accepted round
        x = np.take_along_axis(xx, first, axis=-1)[..., 0]
        y = np.take_along_axis(yy, first, axis=-1)[..., 0]
        todo = np.asarray(~ok.any(axis=-1), dtype=bool)
        if not todo.any():
            return x, y
        if rel.x_bounds is not None and rel.y_bounds is not None:
            self._direct(z, np.nonzero(todo), x, y, rng)
            return x, y
        for _ in range(_MAX_ROUNDS):  # custom relation without bounds: keep rejecting
            idx = np.nonzero(todo)
            m = idx[0].size
            if m == 0:
                return x, y
            zr = z[idx]
            px = rng.random(m) < 0.5
            ur = rng.random(m)
            xr = np.where(px, ur, rel.solve_x(zr, ur))
            yr = np.where(px, rel.solve_y(zr, ur), ur)
            good = (xr >= 0) & (xr <= 1) & (yr >= 0) & (yr <= 1)
            x[idx[0][good], idx[1][good]] = xr[good]
            y[idx[0][good], idx[1][good]] = yr[good]
            todo[idx[0][good], idx[1][good]] = False
        raise ConfigError(
            f"relation {rel.name!r}: no view with x, y in [0, 1] found for some z after "
            f"{_MAX_ROUNDS} draws; check its z_range and inverses"
        )

    def _direct(
        self,
        z: Array,
        idx: tuple[NDArray[np.intp], ...],
        x: Array,
        y: Array,
        rng: np.random.Generator,
    ) -> None:
        rel = self.relation
        assert rel.x_bounds is not None and rel.y_bounds is not None
        zz = z[idx]
        xlo, xhi = rel.x_bounds(zz)
        ylo, yhi = rel.y_bounds(zz)
        lx = np.maximum(xhi - xlo, 0.0)
        ly = np.maximum(yhi - ylo, 0.0)
        total = lx + ly
        pick_x = rng.random(zz.size) * np.where(total > 0, total, 1.0) < lx
        u = rng.random(zz.size)
        xx = np.where(pick_x, xlo + u * lx, 0.0)
        yy = np.where(pick_x, 0.0, ylo + u * ly)
        xx = np.where(pick_x, xx, rel.solve_x(zz, yy))
        yy = np.where(pick_x, rel.solve_y(zz, xx), yy)
        x[idx] = np.clip(xx, 0.0, 1.0)
        y[idx] = np.clip(yy, 0.0, 1.0)

    def stream(self, n: int, dwell: int, rng: np.random.Generator) -> Frames:
        """``n`` frames of the gaze-and-reach world as a robot sees them: the object stays at
        one body-centred position ``z`` for ``dwell`` saccades, then moves to a fresh ``z``
        (uniform, as :meth:`sample_z`); every saccade is a fresh view ``(x, y)`` of the
        current ``z`` (:meth:`sample_view`). The moves fall on frames ``0, dwell, 2 dwell, ...``
        and nothing in the codes marks them.

        Examples
        --------
        >>> from sigmapi.codes import PopulationCode
        >>> s = TwoViewSampler("mean", PopulationCode((15,)), PopulationCode((15,)))
        >>> f = s.stream(6, 3, np.random.default_rng(0))
        >>> f.x.shape, f.moved.tolist()
        ((6, 15), [True, False, False, True, False, False])
        >>> bool(np.allclose((f.px + f.py) / 2, f.z) and np.all(f.z[0] == f.z[2]))
        True
        """
        n = _validate.integer("n", n, 0)
        dwell = _validate.integer("dwell", dwell, 1, fix="saccades per object position")
        each = 8 * (2 * (self.x_code.size + self.y_code.size) + 3 * len(self.x_code.shape) + 1)
        _check_rows(n, each, "fewer frames")  # codes, views, z and the encoding
        segments = self.sample_z(-(-n // dwell), rng)
        z = np.repeat(segments, min(dwell, n), axis=0)[:n]  # a dwell past n: one position
        px, py = self.sample_view(z, rng)
        moved = np.arange(n) % dwell == 0
        enc = _encoder()
        return Frames(enc(self.x_code, px, None), enc(self.y_code, py, None), z, px, py, moved)

    def sample(
        self,
        n: int,
        rng: np.random.Generator,
        z: Array | None = None,
        out: tuple[Array, Array, Array, Array] | None = None,
        exact: bool = True,
    ) -> Batch:
        """``n`` pairs of views of ``n`` body-centred positions (drawn unless ``z`` is given).

        ``out``: four C-contiguous float64 arrays ``(n, n_x)``, ``(n, n_y)``, ``(n, n_x)``,
        ``(n, n_y)`` to write the codes ``x0, y0, x1, y1`` into (the batch holds them), for a
        caller that draws many batches into the same memory. ``exact`` False: the same
        positions, their codes within rounding of ``encode``'s rather than bit for bit
        (normalised hills multiplied out: the refinement's fast path, ``refine_tol > 0``)."""
        each = 8 * (2 * (self.x_code.size + self.y_code.size) + 5 * self.ndim)
        _check_rows(len(z) if z is not None else n, each, "draw fewer pairs")
        if z is None:
            z = self.sample_z(n, rng)
        return self._batch(z, self.sample_view(z, rng), self.sample_view(z, rng), out, exact)

    def sample_at(
        self,
        u: Array,
        out: tuple[Array, Array, Array, Array] | None = None,
        exact: bool = True,
    ) -> Batch:
        """The pairs at points ``u`` ``(n, 3 d)`` of the unit cube (e.g. :func:`kronecker`'s):
        ``z`` from the first ``d`` columns (uniform over the relation's range), view 0 from
        the next ``d`` and view 1 from the last ``d`` (:meth:`view_at`). Uniform ``u`` gives
        the distribution of :meth:`sample`; evenly spread ``u`` (a low-discrepancy sequence)
        gives means over the pairs that converge faster. ``out`` and ``exact`` as in
        :meth:`sample`."""
        u = np.asarray(u, dtype=np.float64)
        d = self.ndim
        if u.ndim != 2 or u.shape[1] != 3 * d:
            raise ConfigError(
                f"u must have shape (n, {3 * d}) (z, view 0, view 1: {d} columns each), got "
                f"{u.shape}; draw points in {3 * d} dimensions"
            )
        _check_rows(
            u.shape[0], 8 * (2 * (self.x_code.size + self.y_code.size) + 8 * d), "draw fewer pairs"
        )
        lo, hi = self.relation.z_range
        z = lo + u[:, :d] * (hi - lo)
        return self._batch(
            z, self.view_at(z, u[:, d : 2 * d]), self.view_at(z, u[:, 2 * d :]), out, exact
        )

    def view_at(self, z: Array, u: Array) -> tuple[Array, Array]:
        """The view (x, y) of each entry of ``z`` ``(B, d)`` at ``u`` ``(B, d)`` in [0, 1):
        the inverse of the distribution :meth:`sample_view`'s rejection converges to (x's
        feasible interval with probability its share of both intervals' lengths, uniform
        within it, else y's). Needs the relation's bounds (the built-in relations give them)."""
        rel = self.relation
        if rel.x_bounds is None or rel.y_bounds is None:
            raise ConfigError(
                f"relation {rel.name!r} has no x_bounds and y_bounds, which views at given "
                "points need; give the Relation its bounds or draw views at random (sample)"
            )
        xlo, xhi = rel.x_bounds(z)
        ylo, yhi = rel.y_bounds(z)
        lx = np.maximum(xhi - xlo, 0.0)
        ly = np.maximum(yhi - ylo, 0.0)
        t = u * (lx + ly)  # [0, lx): along x's interval; [lx, lx + ly): along y's
        pick_x = t < lx
        x = np.where(pick_x, xlo + t, rel.solve_x(z, ylo + (t - lx)))
        y = np.where(pick_x, rel.solve_y(z, xlo + t), ylo + (t - lx))
        return np.clip(x, 0.0, 1.0), np.clip(y, 0.0, 1.0)

    def _batch(
        self,
        z: Array,
        view0: tuple[Array, Array],
        view1: tuple[Array, Array],
        out: tuple[Array, Array, Array, Array] | None,
        exact: bool,
    ) -> Batch:
        """The batch of two views' positions, encoded (into ``out`` when given)."""
        (px0, py0), (px1, py1) = view0, view1
        enc = _encoder() if exact else _fast_encoder()
        dest = out if out is not None else (None, None, None, None)
        return Batch(
            enc(self.x_code, px0, dest[0]),
            enc(self.y_code, py0, dest[1]),
            enc(self.x_code, px1, dest[2]),
            enc(self.y_code, py1, dest[3]),
            z,
            px0,
            py0,
            px1,
            py1,
        )
