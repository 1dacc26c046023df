"""Ordering procedures: how a map starts so that it unfolds on every seed (docs/algorithm.md,
"Ordering procedures", which also holds what each step was measured to change).

With the paper's random initial weights and a wide first neighbourhood, a Sigma-Pi map stays
mirror-symmetric until the neighbourhood has shrunk to about a quarter of the map; the symmetry
then breaks on rounding noise, and in 2-D different patches break it in different directions
and lock in as a twist. ``ordering="crossview"`` removes the symmetry before training starts,
from the two-view data alone (never z):

1. **Cross-view components.** Two views of one z share z and nothing else, so the directions
   of the data space along which the two views of a pair co-vary are functions of z. The
   procedure takes the leading eigenvectors of the symmetrised cross-covariance
   ``(C01 + C10) / 2`` of the outer products ``x y^T`` of view 0 and view 1. The outer
   products are first expressed in a smooth basis (the leading eigenvectors of a Gaussian
   kernel of width ``blur`` on each input axis) so that near positions give near features;
   without it the components of narrow codes follow z only loosely.
2. **Orientation.** Within the span of the ``d`` leading components (``d`` = map
   dimensions), the combination that best predicts each axis of the retinal position (the
   centre of mass of the x code) is taken for the matching map axis. This fixes the sign,
   the order and, where eigenvalues tie (a square 2-D problem), the rotation: map axis ``a``
   grows with retinal axis ``a``, on every seed and backend.
3. **Initial weights.** Each sample pair gets map coordinates from the ranks of its scores;
   unit ``k`` starts as the neighbourhood-weighted mean of the outer products ``x1 y1^T``
   of the pairs placed near it (one batch step of the cost function, docs/algorithm.md),
   summed over the tiles of the pair grid where the pair's outer product reaches
   :data:`INIT_CUT` of its largest.

Training then runs the configured schedule with the neighbourhood capped at
``ordering_sigma`` (:meth:`Crossview.cap_sigma`): the wide start of the paper's schedule
exists to order a random map, and a neighbourhood as wide as the map would erase any start
long before it narrows.

4. **Border-normalised soft winner** (:meth:`Crossview.training_rule`). The paper's soft
   winner sums the Gaussian-weighted activations of a unit's neighbours; a unit at the map's
   border has fewer neighbours, so while sigma is below one unit the second unit from an end
   can win the inputs that belong to the end unit and the two ends swap. With an ordering
   procedure the soft winner takes the weighted *mean* over the window inside the map (rule
   ``"soft_mean"``); away from the borders the two rules pick the same unit.
5. **A ring** (a periodic 1-D map, ``SOMConfig.map_periodic``). On angles the cross-view
   components come in pairs: the two leading ones are about ``cos`` and ``sin`` of the angle
   z (the shared cause is a point on a circle). ``atan2`` of the two scores places each pair
   round the ring, and the neighbourhood that averages the outer products wraps around. The
   smooth basis wraps around too when the codes are periodic. On a **torus** (a periodic
   2-D map) the four leading components are ``cos`` and ``sin`` of both angles, mixed where
   their eigenvalues tie; :func:`torus_angles` separates the two angles' planes by the one
   property they have (the length of a pair's projection onto either plane is the same for
   every pair) and places each pair by the two ``atan2``. Periodic maps of three or more
   dimensions have no such start: use ``ordering="none"`` there.

A procedure is an :class:`Ordering` object in :data:`ORDERINGS` (``SOMConfig.ordering``
looks up there): it owns the initial weights, the sigma cap and the rule training uses.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import ClassVar, Protocol

import numpy as np
from numpy.random import Generator
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from sigmapi.codes import grid_coordinates
from sigmapi.errors import ConfigError
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import axis_distance, gaussian
from sigmapi.rules.winners import WinnerRule

__all__ = [
    "CROSSVIEW",
    "INIT_PAIRS",
    "NONE",
    "ORDERINGS",
    "Crossview",
    "NoOrdering",
    "Ordering",
    "OrderingSettings",
    "check_periodic_map",
    "crossview_init",
    "crossview_scores",
    "smooth_basis",
    "torus_angles",
]

INIT_PAIRS = 1000
"""View pairs the cross-view start is computed from."""

BLUR_FRACTION = 0.2
"""Width of the smoothing kernel as a fraction of the longest input axis (3 units of 15)."""

KEEP = 0.03
"""Smooth-basis modes kept per axis: kernel eigenvalues >= KEEP x the largest."""

INIT_CUT = 1e-8
"""A pair's outer product enters the initial weights only on the tiles (:data:`INIT_TILE`)
where some product reaches ``INIT_CUT`` times the pair's largest: the Gaussian codes leave
the rest below it (on ``paper-2d`` about 87 of 625 tiles a pair, the weights within 1e-8 of
their largest entry of the sum over every product; docs/guide/ceiling.md, "Time")."""

INIT_TILE = 3
"""Grid points per code axis of a tile of the initial weights' sum."""

MAX_FEATURES = 1024
"""Upper bound on the outer-product features (modes of x times modes of y); it caps the
modes per axis so that the eigenproblem stays small (5 per axis for 2-D inputs)."""


def smooth_basis(
    shape: tuple[int, ...], width: float, max_modes: int | None = None, periodic: bool = False
) -> NDArray[np.float64]:
    """Smooth features of codes on grid ``shape``: ``(n, r)``, C order over the axes.

    Per axis, the eigenvectors of the Gaussian kernel matrix ``exp(-(i - j)^2 / (2 width^2))``
    with eigenvalue at least ``KEEP`` times the largest (at most ``max_modes``), scaled by their
    eigenvalues; axes are combined by Kronecker products. ``codes @ basis`` is the code
    blurred by the kernel, expressed in its ``r`` leading modes. ``periodic``: the code's axes
    are rings, ``|i - j|`` is taken the shorter way round.
    """
    basis = np.ones((1, 1))
    for n in shape:
        c = np.arange(n, dtype=np.float64)
        d = np.abs(c[:, None] - c[None, :])
        if periodic:
            d = np.minimum(d, n - d)
        gram = np.exp(-(d**2) / (2.0 * width**2))
        vals, vecs = np.linalg.eigh(gram)
        keep = vals >= KEEP * vals[-1]
        if max_modes is not None:
            keep[: max(0, n - max_modes)] = False
        axis = vecs[:, keep][:, ::-1] * vals[keep][::-1]
        # a deterministic sign per mode, whatever LAPACK returned
        axis *= np.where(axis[np.argmax(np.abs(axis), axis=0), range(axis.shape[1])] < 0, -1, 1)
        basis = np.kron(basis, axis)
    return basis


def _centroid(codes: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.float64]:
    """Centre of mass of each code's positive part, in grid coordinates: ``(B, d)``."""
    w = np.maximum(codes, 0.0)
    total = w.sum(axis=1, keepdims=True)
    total[total == 0] = 1.0
    return np.asarray((w @ grid_coordinates(shape)) / total)


def crossview_scores(
    views: tuple[NDArray[np.float64], ...],
    x_shape: tuple[int, ...],
    y_shape: tuple[int, ...],
    n_components: int,
    blur: float | None = None,
    periodic: bool = False,
) -> NDArray[np.float64]:
    """Oriented cross-view component scores of each view pair: ``(B, n_components)``.

    Column ``a`` is a function of the pair's shared cause (z) that grows with retinal axis
    ``a`` (steps 1 and 2 of the module docstring). Reads the views only. ``periodic``: the
    codes' axes are rings (the smooth basis wraps around).
    """
    x0, y0, x1, y1 = views
    width = blur if blur is not None else BLUR_FRACTION * max(max(x_shape), max(y_shape))
    per_axis = int(MAX_FEATURES ** (1.0 / (len(x_shape) + len(y_shape))))
    bx = smooth_basis(x_shape, width, per_axis, periodic)
    by = smooth_basis(y_shape, width, per_axis, periodic)

    def features(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
        a, b = x @ bx, y @ by
        return (a[:, :, None] * b[:, None, :]).reshape(x.shape[0], -1)

    f0, f1 = features(x0, y0), features(x1, y1)
    mean = 0.5 * (f0.mean(axis=0) + f1.mean(axis=0))
    f0 -= mean
    f1 -= mean
    cross = f0.T @ f1
    cross = (cross + cross.T) / (2.0 * x0.shape[0])
    _, vecs = np.linalg.eigh(cross)
    lead = vecs[:, ::-1][:, :n_components]
    scores = 0.5 * (f0 @ lead + f1 @ lead)

    # orient: per map axis, the combination of the leading components that best predicts the
    # retinal position along that axis (falls back to the gaze position where x says nothing)
    centred = scores - scores.mean(axis=0)
    for codes, shape in ((x0, x_shape), (y0, y_shape)):
        target = _centroid(codes, shape)[:, :n_components]
        if target.shape[1] == n_components:
            rot = _orientation(centred, target - target.mean(axis=0))
            if rot is not None:
                return np.asarray(centred @ rot)
    return np.asarray(scores)


def _orientation(
    scores: NDArray[np.float64], target: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """Least-squares map from centred scores to a centred target, or None where it says too
    little: some target axis predicted with R^2 < 0.05, or an ill-conditioned fit."""
    rot, *_ = np.linalg.lstsq(scores, target, rcond=None)
    resid = target - scores @ rot
    r2 = 1.0 - (resid**2).sum(axis=0) / np.maximum((target**2).sum(axis=0), 1e-300)
    if np.all(r2 >= 0.05) and np.linalg.cond(rot) < 1e3:
        return np.asarray(rot, dtype=np.float64)
    return None


def crossview_init(
    views: tuple[NDArray[np.float64], ...],
    x_shape: tuple[int, ...],
    y_shape: tuple[int, ...],
    geometry: MapGeometry,
    sigma: float,
    periodic: bool = False,
) -> NDArray[np.float64]:
    """Ordered initial weights ``(n_units, n_x, n_y)`` from view pairs (module docstring) on
    the map ``geometry`` (periodic: a ring or a torus, a periodic map of one or two
    dimensions, step 5 of the module docstring).

    ``sigma`` is the width (map units) of the neighbourhood that averages the outer products
    ``x1 y1^T`` of the pairs placed near each unit. ``periodic``: the codes' axes are rings.
    """
    map_shape, map_periodic = geometry.shape, geometry.periodic
    n, d = views[0].shape[0], len(map_shape)
    if n < 4 * d:
        raise ConfigError(
            f"ordering='crossview' needs at least {4 * d} view pairs to start from, got {n}; "
            "pass more views or set ordering='none'"
        )
    check_periodic_map(map_shape, map_periodic)
    sizes = np.asarray(map_shape, dtype=np.float64)
    # small dense problems: on one BLAS thread they run faster than on several, and far
    # faster on a busy machine (threads wait for each other at every step of the eigh)
    with threadpool_limits(limits=1, user_api="blas"):
        if map_periodic:  # the 2 d leading components are cos and sin of each angle
            cs = crossview_scores(views, x_shape, y_shape, 2 * d, periodic=periodic)
            place = torus_angles(cs) * sizes
        else:
            scores = crossview_scores(views, x_shape, y_shape, d, periodic=periodic)
            ranks = (np.argsort(np.argsort(scores, axis=0, kind="stable"), axis=0) + 0.5) / n
            place = ranks * (sizes - 1.0)
        units = grid_coordinates(map_shape)
        diff = axis_distance(np.abs(units[:, None, :] - place[None, :, :]), sizes, map_periodic)
        d2 = (diff**2).sum(axis=-1)
        a = gaussian(d2 - d2.min(axis=1, keepdims=True), sigma)
        a /= a.sum(axis=1, keepdims=True)
        return _placed_sum(a, views[2], views[3], x_shape, y_shape)


def _tiled(codes: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.float64]:
    """Codes on grid ``shape`` by tile, ``(n, tiles, INIT_TILE ** d)``: the grid padded with
    zeros to whole tiles of :data:`INIT_TILE` points per axis, tiles in C order over the tile
    grid, each tile's points in C order."""
    t, d, n = INIT_TILE, len(shape), codes.shape[0]
    padded = np.zeros((n, *(-(-s // t) * t for s in shape)))
    padded[(slice(None), *(slice(0, s) for s in shape))] = codes.reshape(n, *shape)
    split = padded.reshape(n, *(v for s in padded.shape[1:] for v in (s // t, t)))
    order = (0, *range(1, 2 * d, 2), *range(2, 2 * d + 1, 2))  # tile axes first, then points
    return split.transpose(order).reshape(n, -1, t**d)


def _placed_sum(
    a: NDArray[np.float64],
    x1: NDArray[np.float64],
    y1: NDArray[np.float64],
    x_shape: tuple[int, ...],
    y_shape: tuple[int, ...],
) -> NDArray[np.float64]:
    """``W[k] = sum_p a[k, p] x1[p] y1[p]^T`` over the pairs' tiles that hold a product of at
    least :data:`INIT_CUT` of the pair's largest: per tile of the pair grid one matrix
    product (BLAS) over the pairs that reach it, written into the weights' tile as a strided
    view (no copy where the grids hold whole tiles). ``(n_units, n_x, n_y)``."""
    t, units = INIT_TILE, a.shape[0]
    xt, yt = _tiled(x1, x_shape), _tiled(y1, y_shape)
    top_x, top_y = np.abs(xt).max(axis=2), np.abs(yt).max(axis=2)  # (pairs, tiles)
    cut = INIT_CUT * top_x.max(axis=1) * top_y.max(axis=1)
    reach = top_x[:, :, None] * top_y[:, None, :] >= cut[:, None, None]
    grid_x, grid_y = (tuple(-(-s // t) for s in shape) for shape in (x_shape, y_shape))
    w = np.zeros((units, *(g * t for g in grid_x + grid_y)))
    view = w.reshape(units, *(v for g in grid_x + grid_y for v in (g, t)))
    points = (t,) * (len(x_shape) + len(y_shape))
    a_rows = np.ascontiguousarray(a.T)
    for i in range(xt.shape[1]):
        at_x = np.unravel_index(i, grid_x)
        for j in range(yt.shape[1]):
            p = np.flatnonzero(reach[:, i, j])
            if p.size:
                outer = (xt[p, i][:, :, None] * yt[p, j][:, None, :]).reshape(p.size, -1)
                at = (*at_x, *np.unravel_index(j, grid_y))
                tile = (slice(None), *(v for g in at for v in (g, slice(None))))
                view[tile] = (a_rows[p].T @ outer).reshape(units, *points)
    inside = (slice(None), *(slice(0, s) for s in (*x_shape, *y_shape)))
    nx, ny = math.prod(x_shape), math.prod(y_shape)
    return np.ascontiguousarray(w[inside]).reshape(units, nx, ny)


def check_periodic_map(map_shape: tuple[int, ...], map_periodic: bool) -> None:
    """A ConfigError unless the cross-view start can order the map: any bounded map, and a
    periodic one of one or two dimensions (a ring, a torus; step 5 of the module docstring)."""
    if map_periodic and len(map_shape) > 2:
        raise ConfigError(
            f"ordering='crossview' orders a periodic map of one or two dimensions (a ring, a "
            f"torus), got map_shape {tuple(map_shape)}; set ordering='none'"
        )


def torus_angles(scores: NDArray[np.float64]) -> NDArray[np.float64]:
    """The angles (in turns, ``[0, 1)``) that the cross-view scores of a ring or a torus
    encode: ``(B, 2 d)`` scores -> ``(B, d)`` angles, ``d`` = 1 or 2 (step 5 of the module
    docstring).

    On a ring the two scores are about ``r (cos z, sin z)``. On a torus the four leading
    components span ``cos`` and ``sin`` of both angles, but their eigenvalues tie (a square
    problem), so each eigenvector may mix the two angles. What separates them: the scores
    are an orthogonal image of ``r (cos z1, sin z1, cos z2, sin z2)``, so the squared length
    of their projection ``|P_a s|^2`` onto the plane of either angle is the same for every
    pair. The symmetric matrices ``Q`` with ``s^T Q s`` constant over the pairs are the
    combinations of ``P_1`` and ``P_2``: the two directions of least variance of the
    quadratic features ``s s^T``. Their combination without trace is ``P_1 - P_2`` (up to
    scale), whose eigenvectors of eigenvalue +1 span one angle's plane and those of -1 the
    other's; ``atan2`` within each plane gives the angle. Which angle becomes map axis 0,
    and each angle's direction and offset, are symmetries of a torus: fixed by the data
    (the same views give the same angles), not by z.

    The four leading components are the two angles' only on a square problem. On a torus
    of unequal sides (8x12 units) the two angles' pairs were components 0-1 and 6-7, so the
    start placed pairs poorly (circular order 0.23-0.27 after 100 iterations); the
    ``angles-2d`` schedule from it still ended seamless on seeds 0 and 1, as it did from the
    random start.
    """
    m = scores.shape[1]
    if m not in (2, 4):
        raise ValueError(f"torus_angles takes 2 or 4 scores per pair, got {m}")
    if m == 2:  # the ring: the scores as they are (their mean is 0 by construction)
        return (np.arctan2(scores[:, 1], scores[:, 0]) / (2.0 * np.pi) % 1.0)[:, None]
    s = scores - scores.mean(axis=0)
    iu = np.triu_indices(m)
    scale = np.where(iu[0] == iu[1], 1.0, np.sqrt(2.0))  # <Q, s s^T> = q . feat
    feat = (s[:, iu[0]] * s[:, iu[1]]) * scale
    _, vecs = np.linalg.eigh(np.cov(feat, rowvar=False))
    null = []
    for v in vecs[:, :2].T:  # the two directions of least variance, as matrices
        q = np.zeros((m, m))
        q[iu] = v / scale
        null.append(q + np.triu(q, 1).T)  # s^T Q s = v . feat
    # the combination without trace: t_0 Q_1 - t_1 Q_0 (t = the traces)
    t = [np.trace(q) for q in null]
    diff = t[0] * null[1] - t[1] * null[0]
    if np.linalg.norm(diff) == 0:
        diff = null[0]
    _, evecs = np.linalg.eigh(diff)
    # a deterministic order of the planes: the plane of the larger eigenvalues first
    planes = [evecs[:, 2:], evecs[:, :2]]
    out = np.empty((s.shape[0], len(planes)))
    for a, plane in enumerate(planes):
        u = s @ plane
        out[:, a] = np.arctan2(u[:, 1], u[:, 0]) / (2.0 * np.pi) % 1.0
    return out


# ---------------------------------------------------------------------------- procedures


Views = tuple[NDArray[np.float64], ...] | None
"""View pairs ``(x0, y0, x1, y1)``, codes ``(B, n_x)``, ``(B, n_y)``, ... (or none)."""
Weights = NDArray[np.float64]
"""Weights ``(n_units, n_x, n_y)``."""


class OrderingSettings(Protocol):
    """What an ordering procedure reads of a run's settings (a :class:`~sigmapi.SOMConfig`)."""

    @property
    def map_shape(self) -> tuple[int, ...]: ...
    @property
    def x_shape(self) -> tuple[int, ...]: ...
    @property
    def y_shape(self) -> tuple[int, ...]: ...
    @property
    def init_scale(self) -> float: ...
    @property
    def ordering_sigma(self) -> float: ...
    @property
    def same_view(self) -> bool: ...
    @property
    def periodic(self) -> bool: ...
    @property
    def geometry(self) -> MapGeometry: ...


class Ordering(ABC):
    """An ordering procedure: the initial weights, the sigma cap and the rule training uses."""

    name: ClassVar[str]
    """The procedure's name (its key in :data:`ORDERINGS`, ``SOMConfig.ordering``)."""
    init_pairs: ClassVar[int] = 0
    """View pairs :meth:`initial_weights` reads (0: it reads none)."""

    @abstractmethod
    def initial_weights(self, settings: OrderingSettings, rng: Generator, views: Views) -> Weights:
        """Initial weights ``(n_units, n_x, n_y)``, from ``rng`` and/or the first
        :attr:`init_pairs` rows of ``views`` ``(x0, y0, x1, y1)``."""

    def cap_sigma(self, sigma: NDArray[np.float64], ordering_sigma: float) -> NDArray[np.float64]:
        """The neighbourhood width the run trains with, from its schedule's ``sigma``."""
        return sigma

    def start_bytes(self, map_shape: tuple[int, ...]) -> int:
        """Working memory of :meth:`initial_weights` besides the weights it returns (bytes)."""
        return 0

    def training_rule(self, rule: WinnerRule) -> WinnerRule:
        """The winner rule a model trains and answers with, from the configured ``rule``."""
        return rule

    def __repr__(self) -> str:
        return f"<ordering {self.name!r}>"


class NoOrdering(Ordering):
    """``"none"``: the paper's procedure, bit for bit: uniform random weights in
    ``[-init_scale, init_scale]``, the configured schedule and winner rule unchanged."""

    name = "none"

    def initial_weights(self, settings: OrderingSettings, rng: Generator, views: Views) -> Weights:
        s = settings.init_scale
        shape = (
            math.prod(settings.map_shape),
            math.prod(settings.x_shape),
            math.prod(settings.y_shape),
        )
        return rng.uniform(-s, s, size=shape)


class Crossview(Ordering):
    """``"crossview"``, sigmapi's procedure (module docstring): an ordered start computed
    from :data:`INIT_PAIRS` view pairs, sigma capped at ``ordering_sigma``, and the soft
    winner normalised at the map's border.

    Examples
    --------
    >>> from sigmapi.rules.winners import SOFT
    >>> CROSSVIEW.training_rule(SOFT), NONE.training_rule(SOFT)
    (<winner rule 'soft_mean'>, <winner rule 'soft'>)
    >>> CROSSVIEW.cap_sigma(np.array([8.0, 1.0]), 3.0)
    array([3., 1.])
    """

    name = "crossview"
    init_pairs = INIT_PAIRS

    def initial_weights(self, settings: OrderingSettings, rng: Generator, views: Views) -> Weights:
        """From the first :data:`INIT_PAIRS` rows of ``views`` (``rng`` is not used); with
        ``same_view`` (the ablation, which never sees a second view) view 0 stands in for
        view 1 here too."""
        if views is None:
            raise ValueError("ordering 'crossview' starts from view pairs; pass views")
        views = tuple(v[: self.init_pairs] for v in views)
        if settings.same_view:
            views = (views[0], views[1], views[0], views[1])
        return crossview_init(
            views,
            settings.x_shape,
            settings.y_shape,
            settings.geometry,
            settings.ordering_sigma / 2.0,
            periodic=settings.periodic,
        )

    def cap_sigma(self, sigma: NDArray[np.float64], ordering_sigma: float) -> NDArray[np.float64]:
        return np.minimum(sigma, ordering_sigma)

    def start_bytes(self, map_shape: tuple[int, ...]) -> int:
        """The ``(n_units, init_pairs, d)`` offsets and the ``(n_units, init_pairs)`` squared
        distances, profile and temporaries of :func:`crossview_init`, float64."""
        k, d = math.prod(map_shape), len(map_shape)
        return 8 * k * self.init_pairs * (2 * d + 4) + 8 * k * d

    def training_rule(self, rule: WinnerRule) -> WinnerRule:
        return rule.border_normalised


CROSSVIEW, NONE = Crossview(), NoOrdering()

ORDERINGS: dict[str, Ordering] = {CROSSVIEW.name: CROSSVIEW, NONE.name: NONE}
"""Ordering procedures by name: ``"crossview"`` (sigmapi's) and ``"none"`` (the paper's)."""
