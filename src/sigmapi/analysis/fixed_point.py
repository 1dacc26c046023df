"""The learning rule's own ceiling: the fixed point of Eq. 7 reached from a trained map.

At a fixed point of the rule (section 6.3 of the chapter, Eq. 7) every unit's weights are the
mean of view 1's outer products ``x' y'^T`` over the view pairs whose view 0 it wins,

    w_k = E[x' y'^T | k wins (x, y)],

and the winners are those of the same weights. The learning rule cannot do better than such
a map: its weights move towards exactly these means, with the noise of a finite learning rate
(training) or of a finite number of pairs (the refinement). :func:`fixed_point` estimates the
fixed point nearest a trained map and scores it with :func:`sigmapi.metrics.evaluate`; the
report draws its view consistency as the ceiling of the learning curves.

How it is computed (no sampling, so no weight noise of its own): views of one z are
independent given z, so ``E[x' y'^T | k] = sum_z P(k | z) M(z) / sum_z P(k | z)`` with
``M(z) = E[x y^T | z]``. Both are computed by quadrature on a grid:

- ``z``: the midpoints of ``z_points`` equal cells per axis of the relation's ``z_range``
  (z is uniform there);
- the views of one z: the sampler's distribution given z (the coin of
  :meth:`~sigmapi.tasks.TwoViewSampler.sample_view` weighted by the lengths of the feasible
  intervals, then uniform within the interval), ``view_points`` midpoints per axis and branch,
  every combination over the axes;
- ``P(k | z)``: the weight of the views of z whose **hard winner** is k (the rule the
  refinement assigns with, :attr:`~sigmapi.rules.WinnerRule.hard`); ``M(z)``: the weighted
  mean of their outer products.

Starting from the trained map's winners, the two steps alternate (weights to the means with
the winners fixed, winners of the new weights) until the share of the grid's probability mass
whose winner changes falls to ``tol`` or ``max_rounds`` is reached; a unit that wins nothing
keeps its weights. Each round costs the winners of the grid's views (2-D at the defaults:
24 x 24 z's x 6 x 6 views each) and one pass of matrix products; the report runs it for one
map per task (the map its figures show), which keeps it within the run's time budget.

Relations whose sampler has no interval bounds (custom ones) are not supported: the
distribution of a view given z is then only known through rejection.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sigmapi.errors import ConfigError
from sigmapi.kernels import DEFINITION
from sigmapi.metrics import evaluate

if TYPE_CHECKING:
    from sigmapi.metrics import Metrics
    from sigmapi.model.som import SigmaPiSOM

__all__ = ["Ceiling", "fixed_point", "view_grid"]

Z_POINTS = {1: 240, 2: 24}
"""Default z cells per axis, by the number of z dimensions."""
VIEW_POINTS = {1: 24, 2: 6}
"""Default quadrature points per axis and branch for the views of one z."""
CHUNK = 4096
"""Views per step of the mean's matrix products (bounds the memory of one step)."""


@dataclass(frozen=True)
class ViewGrid:
    """Quadrature of the views: ``z`` ``(Z, d)`` with ``z_weight`` ``(Z,)`` (sum 1); per z
    the views ``px``, ``py`` ``(Z, V, d)`` with weights ``weight`` ``(Z, V)`` (rows sum 1)."""

    z: NDArray[np.float64]
    z_weight: NDArray[np.float64]
    px: NDArray[np.float64]
    py: NDArray[np.float64]
    weight: NDArray[np.float64]


def _axis_nodes(
    model: SigmaPiSOM, z: NDArray[np.float64], n: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Per z (1-D array), the views' x, y and weights on one axis ``(Z, 2 n)``: n midpoints
    of the x-branch (x uniform in its bounds) and n of the y-branch, weighted by length."""
    rel = model.sampler.relation
    if rel.x_bounds is None or rel.y_bounds is None:
        raise ConfigError(
            f"relation {rel.name!r} has no x_bounds / y_bounds, got a custom relation "
            "without them; the ceiling needs the distribution of a view given z (use a "
            "built-in relation or give the bounds)"
        )
    u = (np.arange(n) + 0.5) / n
    xlo, xhi = rel.x_bounds(z)
    ylo, yhi = rel.y_bounds(z)
    lx, ly = np.maximum(xhi - xlo, 0.0), np.maximum(yhi - ylo, 0.0)
    xa = xlo[:, None] + lx[:, None] * u[None, :]
    yb = ylo[:, None] + ly[:, None] * u[None, :]
    px = np.concatenate([xa, rel.solve_x(z[:, None], yb)], axis=1)
    py = np.concatenate([rel.solve_y(z[:, None], xa), yb], axis=1)
    px, py = np.clip(px, 0.0, 1.0), np.clip(py, 0.0, 1.0)
    if np.allclose(np.sort(px[:, :n], axis=1), np.sort(px[:, n:], axis=1)) and np.allclose(
        np.sort(py[:, :n], axis=1), np.sort(py[:, n:], axis=1)
    ):  # both branches give the same views (the mean relation): keep one
        return px[:, :n], py[:, :n], np.full((z.size, n), 1.0 / n)
    total = np.maximum(lx + ly, 1e-300)
    w = (
        np.concatenate(
            [np.repeat((lx / total)[:, None], n, 1), np.repeat((ly / total)[:, None], n, 1)], axis=1
        )
        / n
    )
    return px, py, w


def view_grid(model: SigmaPiSOM, z_points: int, view_points: int) -> ViewGrid:
    """The quadrature grid of the model's task (module docstring)."""
    d = model.sampler.ndim
    lo, hi = model.sampler.relation.z_range
    axis = lo + (hi - lo) * (np.arange(z_points) + 0.5) / z_points
    mesh = np.stack(np.meshgrid(*([axis] * d), indexing="ij"), axis=-1).reshape(-1, d)
    per_axis = [_axis_nodes(model, mesh[:, a], view_points) for a in range(d)]
    counts = [np.arange(nodes[0].shape[1]) for nodes in per_axis]
    combos = np.stack(np.meshgrid(*counts, indexing="ij"), -1).reshape(-1, d)
    px = np.stack([per_axis[a][0][:, combos[:, a]] for a in range(d)], axis=-1)
    py = np.stack([per_axis[a][1][:, combos[:, a]] for a in range(d)], axis=-1)
    weight = np.prod(np.stack([per_axis[a][2][:, combos[:, a]] for a in range(d)]), axis=0)
    weight /= weight.sum(axis=1, keepdims=True)
    z_weight = np.full(mesh.shape[0], 1.0 / mesh.shape[0])
    return ViewGrid(mesh, z_weight, px, py, weight)


@dataclass
class Ceiling:
    """The fixed point reached from a map: its metrics and how it was reached.

    Attributes
    ----------
    metrics : Metrics
        :func:`~sigmapi.metrics.evaluate` of the fixed-point map (the same test set as the
        maps it bounds).
    rounds : int
        Rounds of the two steps done.
    changed : list of float
        Per round, the share of the grid's probability mass whose winner changed.
    converged : bool
        Whether the last change was at most ``tol``.
    z_points, view_points : int
        The grid (module docstring).
    model : SigmaPiSOM or None
        The fixed-point map itself (not in :meth:`to_dict`).
    """

    metrics: Metrics
    rounds: int
    changed: list[float] = field(default_factory=list)
    converged: bool = False
    z_points: int = 0
    view_points: int = 0
    model: SigmaPiSOM | None = field(default=None, repr=False)

    def to_dict(self) -> dict[str, object]:
        return {
            **self.metrics.to_dict(),
            "rounds": self.rounds,
            "changed": self.changed,
            "converged": self.converged,
            "z_points": self.z_points,
            "view_points": self.view_points,
        }


def _winners(model: SigmaPiSOM, grid: ViewGrid) -> NDArray[np.int64]:
    """Hard winners of every grid view ``(Z, V)``."""
    zn, v, d = grid.px.shape
    x = model.x_code.encode(grid.px.reshape(-1, d))
    y = model.y_code.encode(grid.py.reshape(-1, d))
    return model.winner(x, y, hard=True).reshape(zn, v)


MOMENTS_BYTES = 512 * 2**20
"""Largest size of the grid's ``M(z)`` that :func:`fixed_point` keeps between rounds (every
round needs the same ones); larger grids compute them again each round."""


def _moments(model: SigmaPiSOM, grid: ViewGrid, start: int, stop: int) -> NDArray[np.float64]:
    """``M(z)`` ``(c, n_x n_y)`` of the grid's z's ``start:stop``: the weighted mean of their
    views' outer products (the same for every round: it does not depend on the weights)."""
    _, v, d = grid.px.shape
    c = grid.px[start:stop].shape[0]
    x = model.x_code.encode(grid.px[start:stop].reshape(-1, d)).reshape(c, v, -1)
    y = model.y_code.encode(grid.py[start:stop].reshape(-1, d)).reshape(c, v, -1)
    w = grid.weight[start:stop]
    return np.matmul(np.swapaxes(x * w[:, :, None], 1, 2), y).reshape(c, -1)


def _means(
    model: SigmaPiSOM,
    grid: ViewGrid,
    winners: NDArray[np.int64],
    old: NDArray[np.float64],
    kept: dict[int, NDArray[np.float64]] | None = None,
) -> NDArray[np.float64]:
    """Eq. 7 with the winners fixed: ``sum_z P(k|z) M(z) / sum_z P(k|z)`` per unit.
    ``kept`` holds the ``M(z)`` of earlier rounds by chunk (filled here), or is None."""
    k = model.n_units
    zn, v, _ = grid.px.shape
    n_x, n_y = old.shape[1], old.shape[2]
    sums = np.zeros((k, n_x * n_y))
    mass = np.zeros(k)
    per = max(1, CHUNK // v)
    for s in range(0, zn, per):
        sl = slice(s, s + per)
        c = grid.px[sl].shape[0]
        m = kept.get(s) if kept is not None else None
        if m is None:
            m = _moments(model, grid, s, s + per)  # M(z)
            if kept is not None:
                kept[s] = m
        w = grid.weight[sl]
        p = np.zeros((c, k))  # P(k | z) times the z's weight
        np.add.at(p, (np.repeat(np.arange(c), v), winners[sl].ravel()), w.ravel())
        p *= grid.z_weight[sl, None]
        rows, units = np.nonzero(p)  # few units win the views of one z: sum only those
        for u in np.unique(units):
            zs = rows[units == u]
            sums[u] += p[zs, u] @ m[zs]
        mass += p.sum(axis=0)
    out = np.array(old, dtype=np.float64, copy=True).reshape(k, -1)
    won = mass > 0
    out[won] = sums[won] / mass[won, None]
    return out.reshape(old.shape)


def fixed_point(
    model: SigmaPiSOM,
    *,
    z_points: int | None = None,
    view_points: int | None = None,
    tol: float = 1e-3,
    max_rounds: int = 8,
    n_test: int = 10_000,
) -> Ceiling:
    """The fixed point of Eq. 7 nearest ``model``'s map, and its metrics.

    Parameters
    ----------
    model : SigmaPiSOM
        A fitted model of a built-in task (relations with bounds); it is not changed.
    z_points, view_points : int, optional
        Grid of the quadrature (default :data:`Z_POINTS`, :data:`VIEW_POINTS` by dimension).
    tol : float
        Stop when the share of probability mass whose winner changed is at most this.
    max_rounds : int
        At most this many rounds (each: means, then winners).
    n_test : int
        Test set size of :func:`~sigmapi.metrics.evaluate` on the fixed point.

    Returns
    -------
    Ceiling
        The fixed point's metrics, rounds and the changes per round.

    Examples
    --------
    >>> from sigmapi import SigmaPiSOM
    >>> som = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0)
    >>> c = fixed_point(som.fit(), n_test=500)
    >>> 0.0 <= c.metrics.view_consistency <= 1.0 and c.rounds >= 1
    True
    """
    from sigmapi.model.som import SigmaPiSOM

    d = model.sampler.ndim
    zp = Z_POINTS.get(d, 8) if z_points is None else int(z_points)
    vp = VIEW_POINTS.get(d, 4) if view_points is None else int(view_points)
    if zp < 2 or vp < 1:
        raise ConfigError(
            f"z_points must be >= 2 and view_points >= 1, got {zp} and {vp}; e.g. the "
            "defaults (z_points=None, view_points=None)"
        )
    grid = view_grid(model, zp, vp)
    header = {**model.to_arrays()[0], "backend": DEFINITION}  # dense weights in, any kernel
    current, weights = model, np.array(model.weights_, dtype=np.float64)
    winners = _winners(current, grid)
    mass = grid.z_weight[:, None] * grid.weight
    changed: list[float] = []
    size = grid.px.shape[0] * weights[0].size * 8
    kept: dict[int, NDArray[np.float64]] | None = {} if size <= MOMENTS_BYTES else None
    for _ in range(max_rounds):
        weights = _means(current, grid, winners, weights, kept)
        current = SigmaPiSOM.from_arrays(header, {"weights": weights}, source="fixed point")
        new = _winners(current, grid)
        changed.append(float(np.sum(mass[new != winners])))
        winners = new
        if changed[-1] <= tol:
            break
    return Ceiling(
        evaluate(current, n_test=n_test),
        len(changed),
        changed,
        bool(changed) and changed[-1] <= tol,
        zp,
        vp,
        current,
    )
