"""Population codes: Gaussian hills of activity on grids of units.

A position ``p`` in ``[0, 1]^d`` sits at grid coordinate ``p * (n - 1)`` on an axis of ``n``
units (``p * n`` on a periodic axis, where 0 and 1 are the same place). The code of ``p`` is::

    c_u = height * exp(-|g_u - p (n - 1)|^2 / (2 width^2))

over the units ``u`` with grid coordinates ``g_u``, optionally L2-normalised to length 1, as in
the authors' 1-D script (width 0.5 grid units, height 1, non-periodic, normalised). Codes of
several units are flattened in C order over the grid.

References
----------
C. Weber and S. Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007)
2552-2560.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi._validate import MAX_WIDTH
from sigmapi.errors import ConfigError, DataError

__all__ = ["MAX_WIDTH", "MIN_WIDTH", "NOISE_KINDS", "PopulationCode", "grid_coordinates", "noisy"]

MIN_WIDTH = 0.1
"""Narrowest hill (grid units). Half-way between two units a hill of width w is
``exp(-d / (8 w^2))`` of its peak in d dimensions: at w = 0.1 that is 4e-6 in 1-D, at w = 0.02
it underflows in 2-D and the normalised code becomes NaN."""

NOISE_KINDS = ("poisson", "gaussian")
"""Kinds of noise :func:`noisy` adds to codes."""


def grid_coordinates(shape: tuple[int, ...]) -> NDArray[np.float64]:
    """Grid coordinates of every unit, shape ``(prod(shape), len(shape))``, in C order."""
    axes = np.meshgrid(*[np.arange(n, dtype=np.float64) for n in shape], indexing="ij")
    return np.stack([a.ravel() for a in axes], axis=1)


_WIDTH_FIX = (
    "in grid units; narrower hills leave positions between units without a code "
    "(the paper uses 0.5)"
)


@dataclass(frozen=True)
class PopulationCode:
    """Gaussian-hill population code on a grid.

    Parameters
    ----------
    shape : tuple of int
        Grid shape, e.g. ``(15,)`` or ``(15, 15)``; any number of dimensions.
    width : float
        Standard deviation of the hill, in grid units (the paper's 1-D script: 0.5).
    height : float
        Peak value before normalisation.
    normalize : bool
        L2-normalise every code to length 1 (the paper does).
    periodic : bool
        Wrap distances around each axis (a ring or torus) instead of a bounded line.

    Examples
    --------
    >>> code = PopulationCode((15,))
    >>> c = code.encode([[0.5]])
    >>> c.shape, int(c.argmax())
    ((1, 15), 7)
    >>> float(np.round(code.decode(c)[0, 0], 6))
    0.5
    """

    shape: tuple[int, ...]
    width: float = 0.5
    height: float = 1.0
    normalize: bool = True
    periodic: bool = False
    _coords: NDArray[np.float64] = field(init=False, repr=False, compare=False)
    _units: tuple[NDArray[np.float64], ...] = field(init=False, repr=False, compare=False)
    _scale: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", _validate.shape("shape", self.shape))
        _validate.width("width", self.width, MIN_WIDTH, fix=_WIDTH_FIX)
        _validate.positive("height", self.height, fix="the paper uses 1.0")
        object.__setattr__(self, "_coords", grid_coordinates(self.shape))
        # what every encode needs, made once (an agent encodes one view per step)
        units = tuple(np.arange(n, dtype=np.float64)[None, :] for n in self.shape)
        object.__setattr__(self, "_units", units)
        object.__setattr__(self, "_scale", self.scale)

    @property
    def ndim(self) -> int:
        """Number of grid dimensions ``d``."""
        return len(self.shape)

    @property
    def size(self) -> int:
        """Number of units ``n`` (product of the grid shape)."""
        return int(np.prod(self.shape))

    @property
    def coords(self) -> NDArray[np.float64]:
        """Grid coordinates of the units, shape ``(n, d)``, C order."""
        return self._coords

    @property
    def scale(self) -> NDArray[np.float64]:
        """Grid units per unit of position along each axis, shape ``(d,)``."""
        n = np.asarray(self.shape, dtype=np.float64)
        return n if self.periodic else n - 1.0

    def check_positions(self, p: ArrayLike, name: str = "p") -> NDArray[np.float64]:
        """Validate positions: shape ``(B, d)``, finite, within ``[0, 1]``; returns them as
        float64 ``(B, d)``. Raises :class:`~sigmapi.errors.DataError` naming ``name``."""
        try:
            arr = np.asarray(p, dtype=np.float64)
        except (TypeError, ValueError):
            raise DataError(
                f"{name} must be an array of numbers (positions in [0, 1]), got "
                f"{type(p).__name__}; pass one row per position"
            ) from None
        if arr.ndim == 1 and self.ndim == 1:
            arr = arr[:, None]
        if arr.ndim != 2 or arr.shape[1] != self.ndim:
            raise DataError(
                f"{name} must have shape (B, {self.ndim}) for a {self.ndim}-D code, got "
                f"{arr.shape}; pass one row per position"
            )
        if arr.size == 0 or (arr.min() >= 0.0 and arr.max() <= 1.0):  # NaN fails both
            return arr
        if not np.all(np.isfinite(arr)):
            raise DataError(f"{name} must be finite, got NaN or inf; remove them")
        if np.any(arr < 0.0) or np.any(arr > 1.0):
            bad = float(arr[(arr < 0) | (arr > 1)][0])
            raise DataError(
                f"{name} must lie in [0, 1], got {bad!r}; positions are fractions of the axis"
            )
        return arr

    def _sq_dist(self, grid_pos: NDArray[np.float64]) -> NDArray[np.float64]:
        """Squared grid distances from positions ``(B, d)`` (grid units) to all units."""
        diff = grid_pos[:, None, :] - self._coords[None, :, :]
        if self.periodic:
            n = np.asarray(self.shape, dtype=np.float64)
            diff = diff - n * np.round(diff / n)
        return np.einsum("bud,bud->bu", diff, diff)

    def _finish(self, codes: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.height != 1.0:  # times 1.0 changes no bit
            codes = self.height * codes
        if self.normalize:  # np.linalg.norm's own arithmetic, without its checks
            codes = codes / np.sqrt(np.add.reduce(codes * codes, axis=-1, keepdims=True))
        return codes

    def encode(self, p: ArrayLike) -> NDArray[np.float64]:
        """Codes of positions ``p`` (shape ``(B, d)``, in [0, 1]); returns ``(B, n)``.

        The Gaussian is separable, so the code is the C-order outer product of one 1-D hill
        per axis.
        """
        hills = self.hills(p)
        out = hills[0]
        for hill in hills[1:]:
            out = (out[:, :, None] * hill[:, None, :]).reshape(
                len(hill), out.shape[1] * hill.shape[1]
            )
        return self._finish(out)

    def hills(self, p: ArrayLike) -> list[NDArray[np.float64]]:
        """The 1-D hills of positions ``p`` (shape ``(B, d)``, in [0, 1]), one ``(B, n_a)``
        array per axis of ``n_a`` units, unscaled: :meth:`encode` is their C-order outer
        product, times ``height``, normalised."""
        arr = self.check_positions(p) * self._scale
        spread = 2.0 * self.width**2
        out = []
        for axis, n in enumerate(self.shape):
            diff = arr[:, axis, None] - self._units[axis]
            if self.periodic:
                diff = diff - n * np.round(diff / n)
            np.square(diff, out=diff)  # in place: the same operations as -(d**2) / spread
            np.negative(diff, out=diff)
            np.divide(diff, spread, out=diff)
            out.append(np.exp(diff, out=diff))
        return out

    def pattern(self, points: ArrayLike) -> NDArray[np.float64]:
        """One code holding a hill at each of ``points`` (shape ``(m, d)``); returns ``(n,)``.

        Overlapping hills combine by their maximum, so a dense point set (an "L") gives a
        pattern of uniform height rather than a pile-up where points crowd.
        """
        arr = self.check_positions(points, "points")
        if arr.shape[0] == 0:
            raise DataError("points must hold at least one position (m >= 1 rows), got none")
        d2 = self._sq_dist(arr * self.scale)
        hills = np.exp(-d2 / (2.0 * self.width**2)).max(axis=0)
        return self._finish(hills[None, :])[0]

    def l_shape(
        self, corner: tuple[float, ...] | None = None, arm: float = 0.5
    ) -> NDArray[np.float64]:
        """An "L" pattern on a 2-D code: a vertical and a horizontal bar meeting at ``corner``.

        The bars run one grid unit apart along axis 0 (down) from the corner and along axis 1
        (right) from the corner, each ``arm`` of the axis long (as a fraction of it). The
        corner snaps to the nearest unit so that every point of the L sits on a unit.
        """
        if self.ndim != 2:
            raise ConfigError(
                f"l_shape needs a code of 2 dimensions, got a {self.ndim}-D code of shape "
                f"{self.shape}; make it with PopulationCode((n, n))"
            )
        if corner is None:
            corner = (0.25, 0.25)
        c0, c1 = (
            round(float(corner[a]) * (self.shape[a] - 1)) / (self.shape[a] - 1) for a in range(2)
        )
        steps = [round(arm * (self.shape[a] - 1)) for a in range(2)]
        down = [(c0 + k / (self.shape[0] - 1), c1) for k in range(steps[0] + 1)]
        right = [
            (c0 + steps[0] / (self.shape[0] - 1), c1 + k / (self.shape[1] - 1))
            for k in range(1, steps[1] + 1)
        ]
        pts = np.clip(np.array(down + right), 0.0, 1.0)
        return self.pattern(pts)

    def decode(self, codes: ArrayLike) -> NDArray[np.float64]:
        """Position of the strongest hill in each code; ``(B, n)`` -> ``(B, d)`` in [0, 1].

        Uses the peak unit and, along each axis, its larger neighbour: for a Gaussian of known
        width the log-ratio of two adjacent units gives the centre exactly,
        ``mu = k + 1/2 + width^2 * (log c_{k+1} - log c_k)``. Exact for codes made by
        :meth:`encode` (any height or normalisation), also at the borders.
        """
        arr = np.asarray(codes, dtype=np.float64)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.size:
            raise DataError(
                f"codes must have shape (B, {self.size}) for grid {self.shape}, got {arr.shape}; "
                "one code per row, flattened in C order"
            )
        b = arr.shape[0]
        grid = arr.reshape((b, *self.shape))
        flat_peak = np.argmax(arr, axis=1)
        peak = np.stack(np.unravel_index(flat_peak, self.shape), axis=1)  # (B, d)
        tiny = np.finfo(np.float64).tiny
        rows = np.arange(b)
        out = np.empty((b, self.ndim))
        for axis, n in enumerate(self.shape):
            k = peak[:, axis]
            here = grid[(rows, *peak.T)]

            def along(
                offset: NDArray[np.int64], axis: int = axis, n: int = n
            ) -> NDArray[np.float64]:
                idx = peak.copy()
                idx[:, axis] = (
                    (idx[:, axis] + offset) % n if self.periodic else idx[:, axis] + offset
                )
                valid = (idx[:, axis] >= 0) & (idx[:, axis] < n)
                idx[:, axis] = np.clip(idx[:, axis], 0, n - 1)
                vals = grid[(rows, *idx.T)]
                return np.where(valid, vals, -np.inf)

            up = along(np.ones(b, dtype=np.int64))
            down = along(-np.ones(b, dtype=np.int64))
            use_up = up >= down
            nb = np.maximum(np.where(use_up, up, down), tiny)
            here = np.maximum(here, tiny)
            lr = np.log(nb) - np.log(here)
            w2 = self.width**2
            mu = np.where(use_up, k + 0.5 + w2 * lr, k - 0.5 - w2 * lr)
            # the neighbour is never larger than the peak, so mu stays within half a unit
            mu = np.clip(mu, k - 0.5, k + 0.5)
            if self.periodic:
                mu = np.mod(mu, n)
            else:
                mu = np.clip(mu, 0.0, n - 1.0)
            out[:, axis] = mu / self.scale[axis]
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-able description (the model file stores it)."""
        return {
            "shape": list(self.shape),
            "width": float(self.width),
            "height": float(self.height),
            "normalize": bool(self.normalize),
            "periodic": bool(self.periodic),
        }


def noisy(
    codes: ArrayLike,
    kind: str,
    level: float,
    rng: np.random.Generator,
    normalize: bool = True,
) -> NDArray[np.float64]:
    """Noisy versions of population codes ``(B, n)``, as a population of neurons would give.

    ``kind="poisson"``: spike counts ``k_u ~ Poisson(level * c_u / max_u c_u)``, ``level`` the
    expected count of the most active unit (its peak rate times the counting window); fewer
    spikes, more noise. ``kind="gaussian"``: ``c_u + level * max_u c_u * N(0, 1)``, additive
    noise with a standard deviation of ``level`` times the peak. With ``normalize`` every
    noisy code is L2-normalised again, like the clean codes (a code without a single spike
    stays zero).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> c = PopulationCode((15,)).encode([[0.5]])
    >>> k = noisy(c, "poisson", 20.0, rng, normalize=False)
    >>> bool(np.all(k == np.round(k))), int(k.argmax()) in (6, 7, 8)
    (True, True)
    """
    _validate.choice("kind", kind, NOISE_KINDS)
    arr = np.asarray(codes, dtype=np.float64)
    if arr.ndim != 2:
        raise DataError(f"codes must have shape (B, n), got {arr.shape}; one code per row")
    peak = np.max(np.abs(arr), axis=1, keepdims=True)
    peak = np.where(peak > 0, peak, 1.0)
    if kind == "poisson":
        rate = _validate.positive("level", level, fix="the expected spike count at the peak")
        if np.any(arr < 0):
            raise DataError(
                f"codes must be >= 0 for Poisson noise (firing rates), got {float(arr.min())!r}; "
                'use kind="gaussian" for signed codes'
            )
        out = rng.poisson(rate * arr / peak).astype(np.float64)
    else:
        sd = _validate.number("level", level, 0.0, None, fix="a fraction of the peak, e.g. 0.1")
        out = arr + sd * peak * rng.standard_normal(arr.shape)
    if normalize:
        norm = np.linalg.norm(out, axis=1, keepdims=True)
        out = out / np.where(norm > 0, norm, 1.0)
    return out
