"""What a trained map learned, as arrays: the computations behind the figures.

Everything here is numerics on a fitted :class:`~sigmapi.model.som.SigmaPiSOM`;
:mod:`sigmapi.viz.plots` draws the results. Functions take a ``numpy.random.Generator`` or an
int seed wherever they draw data, so a figure is a pure function of the model and the seed.

- :func:`fig8_data`: the inputs and map responses of Fig. 8 of the chapter (four views of one
  z; an "L" on one input with a single hill on the other).
- :func:`receptive_field_centres`: the body-centred z each unit responds to.
- :func:`map_polarity`: how the map is oriented relative to z (rotated, mirrored, ...).
- :func:`invariance_matrix`: the winner as a function of x and y.
- :func:`weight_tiles`: each unit's Sigma-Pi weight matrix (2-D inputs: marginals per axis).

References
----------
C. Weber and S. Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007)
2552-2560; section 6.2 and Fig. 8 of "Neural control of actions involving different coordinate
systems", in Humanoid Robots, Human-like Machines (2007).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.metrics import affine_fit

if TYPE_CHECKING:
    from sigmapi.model.som import SigmaPiSOM

__all__ = [
    "Fig8Data",
    "InvarianceMatrix",
    "Polarity",
    "fig8_data",
    "invariance_matrix",
    "map_polarity",
    "receptive_field_centres",
    "weight_tiles",
]

Seed = int | np.random.Generator | None


def _rng(seed: Seed) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


# ----------------------------------------------------------------------------- Fig. 8


@dataclass(frozen=True)
class Fig8Data:
    """Inputs and responses of Fig. 8 (codes flattened; reshape with the shapes).

    Attributes
    ----------
    z : ndarray, shape (d,)
        The body-centred position shared by the invariance columns.
    x, y : ndarray, shape (C, n_x), (C, n_y)
        Input codes per column: ``n_pairs`` views of ``z``, then the pattern columns.
    h : ndarray, shape (C, n_units)
        Map activations ``h_k = x^T W_k y`` per column.
    labels : list of str
        Column titles.
    n_pairs : int
        How many of the columns are views of ``z`` (the rest are pattern columns).
    x_shape, y_shape, map_shape : tuple of int
        Grids to reshape the codes and responses onto.
    polarity : Polarity
        Orientation of the map relative to z (see :func:`map_polarity`).
    """

    z: NDArray[np.float64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    h: NDArray[np.float64]
    labels: list[str]
    n_pairs: int
    x_shape: tuple[int, ...]
    y_shape: tuple[int, ...]
    map_shape: tuple[int, ...]
    polarity: Polarity

    @property
    def invariance_spread(self) -> float:
        """Largest distance between the normalised responses of the view columns (0: identical).

        Responses are scaled to unit length first, so the number compares shapes: it is at most
        2 and about 0.1 when the responses look the same.
        """
        h = self.h[: self.n_pairs]
        h = h / np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
        d = np.linalg.norm(h[:, None, :] - h[None, :, :], axis=2)
        return float(d.max())


def fig8_data(
    model: SigmaPiSOM, seed: Seed = 0, n_pairs: int = 4, z: Any = None, centres: Any = None
) -> Fig8Data:
    """Data of Fig. 8: views of one z, and a pattern on one input with a hill on the other.

    Parameters
    ----------
    model : SigmaPiSOM
        A fitted model.
    seed : int or Generator
        Draws z (uniform in the middle half of its range, unless given) and its views.
    n_pairs : int
        Number of random (x, y) pairs that share ``z`` (the paper shows four).
    z : array-like, shape (d,), optional
        The shared body-centred position.
    centres : ndarray, optional
        Receptive-field centres (:func:`receptive_field_centres`), reused for the polarity.

    Returns
    -------
    Fig8Data
        Columns ``0 .. n_pairs - 1``: views of z. Then two pattern columns. 2-D inputs: an "L"
        on x with a single hill on y at the centre, and a hill on x with the "L" on y. 1-D
        inputs: two hills on x (at 0.15 and 0.55) with a hill on y at 0.5, and the reverse.
        Because the activation is bilinear, a pattern of several hills on one input evokes the
        sum of the responses to each hill: the pattern is copied onto the map, shifted by the
        other input and oriented as the map's polarity dictates.
    """
    rng = _rng(seed)
    sampler = model.sampler
    d = sampler.ndim
    lo, hi = sampler.relation.z_range
    if z is None:
        zz = lo + (hi - lo) * rng.uniform(0.25, 0.75, size=d)
    else:
        zz = np.asarray(z, dtype=np.float64).reshape(d)
    views = sampler.sample(n_pairs, rng, z=np.repeat(zz[None, :], n_pairs, axis=0))
    xc, yc = model.x_code, model.y_code
    centre = np.full((1, d), 0.5)
    if d == 2:
        px = xc.l_shape(corner=(0.1, 0.1), arm=0.8)
        py = yc.l_shape(corner=(0.1, 0.1), arm=0.8)
        labels = ['"L" on x,\nhill on y', 'hill on x,\n"L" on y']
    elif d == 1:
        px = xc.pattern([[0.15], [0.55]])
        py = yc.pattern([[0.15], [0.55]])
        labels = ["two hills on x,\nhill on y", "hill on x,\ntwo hills on y"]
    else:
        raise ValueError(f"fig8_data draws 1-D or 2-D inputs, this model's are {d}-D")
    x = np.vstack([views.x0, px[None, :], xc.encode(centre)])
    y = np.vstack([views.y0, yc.encode(centre), py[None, :]])
    h = model.respond(x, y)
    return Fig8Data(
        z=zz,
        x=x,
        y=y,
        h=h,
        labels=[f"pair {i + 1}" for i in range(n_pairs)] + labels,
        n_pairs=n_pairs,
        x_shape=model.x_shape,
        y_shape=model.y_shape,
        map_shape=model.map_shape,
        polarity=map_polarity(model, centres=centres),
    )


# ----------------------------------------------------------------------------- the map in z


def z_grid(model: SigmaPiSOM, per_axis: int | None = None) -> NDArray[np.float64]:
    """A regular grid of body-centred positions over the relation's z range; ``(N, d)``."""
    d = len(model.x_shape)
    n = per_axis or (2 * max(model.x_shape) - 1 if d == 1 else max(model.x_shape) + 6)
    lo, hi = model.sampler.relation.z_range
    axes = [np.linspace(lo, hi, n)] * d
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def receptive_field_centres(
    model: SigmaPiSOM, seed: Seed = 0, n_views: int | None = None, per_axis: int | None = None
) -> NDArray[np.float64]:
    """The body-centred position each unit responds to; ``(n_units, d)``.

    The receptive field of unit k in z is its activation ``h_k`` averaged over ``n_views``
    random views (x, y) of each z on a regular grid (:func:`z_grid`). The centre is the centre
    of mass of the part of the field above half its peak (so the long, flat tails of a field
    do not pull border units towards the middle). A unit whose field is flat (never above
    zero) sits at the middle of the z range.
    """
    rng = _rng(seed)
    zs = z_grid(model, per_axis)
    d = zs.shape[1]
    if n_views is None:
        n_views = 8 if d == 1 else 2
    batch = model.sampler.sample(zs.shape[0] * n_views, rng, z=np.repeat(zs, n_views, axis=0))
    h = model.respond(batch.x0, batch.y0)  # (N * views, K)
    rf = h.reshape(zs.shape[0], n_views, -1).mean(axis=1)  # (N, K)
    peak = rf.max(axis=0, keepdims=True)
    mass = np.clip(rf - 0.5 * peak, 0.0, None)
    total = mass.sum(axis=0)
    centres = (mass.T @ zs) / np.maximum(total, 1e-300)[:, None]
    lo, hi = model.sampler.relation.z_range
    centres[total <= 0] = 0.5 * (lo + hi)
    return np.asarray(centres)


@dataclass(frozen=True)
class Polarity:
    """Orientation of the map relative to z.

    Attributes
    ----------
    linear : ndarray, shape (d, d)
        Linear part ``A`` of the affine fit ``z ~ A g + b`` from the map grid coordinates g of
        the units to their receptive-field centres.
    permutation : ndarray, shape (d, d)
        The signed permutation nearest to ``A^-1`` (columns normalised): how a picture in z
        appears on the map, in image coordinates (row down, column right).
    name : str
        Plain words for ``permutation``: "same orientation", "rotated by 180 degrees",
        "mirrored left-right", ... (1-D: "same direction" or "reversed").
    r2 : float
        R^2 of the affine fit (near 1: an ordered map; low: the name means little).
    """

    linear: NDArray[np.float64]
    permutation: NDArray[np.int64]
    name: str
    r2: float


_POLARITY_NAMES = {
    ((1, 0), (0, 1)): "same orientation as in z (not rotated or mirrored)",
    ((-1, 0), (0, -1)): "rotated by 180 degrees",
    ((0, 1), (-1, 0)): "rotated by 90 degrees clockwise",
    ((0, -1), (1, 0)): "rotated by 90 degrees counter-clockwise",
    ((-1, 0), (0, 1)): "mirrored top-bottom",
    ((1, 0), (0, -1)): "mirrored left-right",
    ((0, 1), (1, 0)): "mirrored about the main diagonal (transposed)",
    ((0, -1), (-1, 0)): "mirrored about the anti-diagonal",
}


def map_polarity(model: SigmaPiSOM, centres: ArrayLike | None = None, seed: Seed = 0) -> Polarity:
    """How the learned map is oriented relative to z (see :class:`Polarity`).

    Before learning the orientation is unpredictable; after learning it is consistent (the
    paper's 2-D run came out rotated by 180 degrees).
    """
    c = np.asarray(receptive_field_centres(model, seed) if centres is None else centres)
    g = model.map_coords
    beta = affine_fit(g, c)
    pred = np.hstack([g, np.ones((g.shape[0], 1))]) @ beta
    sst = float(np.sum((c - c.mean(axis=0)) ** 2))
    r2 = 1.0 - float(np.sum((pred - c) ** 2)) / sst if sst > 0 else float("nan")
    a = beta[:-1].T  # z = A g + b, A is (d_z, d_map)
    d_map, d_z = g.shape[1], c.shape[1]
    perm = np.zeros((d_map, d_z), dtype=np.int64)
    if d_map == d_z and np.linalg.matrix_rank(a) == d_map:
        inv = np.linalg.inv(a)  # g = A^-1 (z - b)
        inv = inv / np.maximum(np.abs(inv).max(axis=0, keepdims=True), 1e-300)
        rows = np.argmax(np.abs(inv), axis=0)  # per z axis, the map axis it runs along
        if len(set(rows.tolist())) == d_map:
            for j, i in enumerate(rows):
                perm[i, j] = 1 if inv[i, j] > 0 else -1
    if not perm.any():
        name = f"undetermined: the map is not ordered along z (affine R² {r2:.2f})"
    elif d_map == 1:
        name = "same direction as z" if perm[0, 0] > 0 else "reversed (mirrored)"
    elif d_map == 2:
        name = _POLARITY_NAMES[tuple(tuple(int(v) for v in row) for row in perm)]  # type: ignore[index]
    else:
        name = f"signed permutation {perm.tolist()}"
    return Polarity(np.asarray(a), perm, name, r2)


# ----------------------------------------------------------------------------- invariance


@dataclass(frozen=True)
class InvarianceMatrix:
    """The winner as a function of x and y along one input axis.

    Attributes
    ----------
    axis : int
        The input axis varied (2-D inputs: the other axis of x and y sits at 0.5).
    positions : ndarray, shape (n,)
        Positions of x and y along ``axis`` (in [0, 1]); x on rows, y on columns.
    winners : ndarray, shape (n, n)
        ``winners[i, j]``: flat index of the winner for x at ``positions[i]`` and y at
        ``positions[j]``. Invariance: constant along each anti-diagonal ``i + j = const``
        (constant z = (x + y) / 2).
    value : ndarray, shape (n, n)
        What the figure colours: the winner's index (1-D maps) or the receptive-field centre
        of the winner along ``axis`` (2-D maps).
    value_label : str
        Colour bar label for ``value``.
    constancy : float
        Fraction of cells whose winner is the most common winner of their anti-diagonal
        (1.0: perfectly invariant).
    """

    axis: int
    positions: NDArray[np.float64]
    winners: NDArray[np.int64]
    value: NDArray[np.float64]
    value_label: str
    constancy: float


def invariance_matrix(
    model: SigmaPiSOM, axis: int = 0, n: int | None = None, centres: ArrayLike | None = None
) -> InvarianceMatrix:
    """Winners for every pair of grid positions of x and y along ``axis``.

    ``n`` positions per input (default: the grid size of x along ``axis``, one per input
    unit). Only the ``"mean"`` relation puts constant z on the anti-diagonals; for others the
    matrix is still the winner map, the constancy score assumes the mean.
    """
    d = len(model.x_shape)
    if not 0 <= axis < d:
        raise ValueError(f"axis must be in [0, {d - 1}] for {d}-D inputs, got {axis}")
    n = n or model.x_shape[axis]
    pos = np.linspace(0.0, 1.0, n)
    xi, yj = np.meshgrid(pos, pos, indexing="ij")
    px = np.full((n * n, d), 0.5)
    py = np.full((n * n, d), 0.5)
    px[:, axis] = xi.ravel()
    py[:, axis] = yj.ravel()
    w = model.winner(model.x_code.encode(px), model.y_code.encode(py)).reshape(n, n)
    if len(model.map_shape) == 1:
        value = w.astype(np.float64)
        label = "winning map unit"
    else:
        c = np.asarray(receptive_field_centres(model) if centres is None else centres)
        value = c[w, axis]
        label = f"z{axis} the winner responds to (receptive-field centre)"
    agree = 0
    s = np.add.outer(np.arange(n), np.arange(n))
    for k in range(2 * n - 1):
        vals = w[s == k]
        agree += int(np.bincount(vals).max())
    return InvarianceMatrix(axis, pos, w, value, label, agree / float(n * n))


# ----------------------------------------------------------------------------- weights


def weight_tiles(model: SigmaPiSOM, axis: int = 0) -> NDArray[np.float64]:
    """Each unit's Sigma-Pi weight matrix as a tile; ``(n_units, a, b)``.

    1-D inputs: the full ``(n_x, n_y)`` matrix ``W_k`` (x on rows, y on columns). 2-D inputs:
    the marginal along ``axis``, ``M_k[i, j] = sum over the other axis of x and of y of W_k``,
    an ``(n_x[axis], n_y[axis])`` matrix. An invariant unit for z = (x + y) / 2 has its weight
    on an anti-diagonal ``i + j = const`` of the tile.
    """
    w = model.weights_
    k = w.shape[0]
    d = len(model.x_shape)
    if d == 1:
        return np.asarray(w)
    if not 0 <= axis < d:
        raise ValueError(f"axis must be in [0, {d - 1}] for {d}-D inputs, got {axis}")
    full = w.reshape((k, *model.x_shape, *model.y_shape))
    other = [1 + a for a in range(d) if a != axis] + [1 + d + a for a in range(d) if a != axis]
    return np.asarray(full.sum(axis=tuple(other)))
