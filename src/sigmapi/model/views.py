"""Views: the checks of the code arrays a map learns from and answers, before any arithmetic.

A *view* is one input pair ``(x, y)``: a code ``x`` of shape ``(B, n_x)`` (retinal position)
and a code ``y`` of shape ``(B, n_y)`` (gaze direction), each flattened in C order over its
grid (:class:`~sigmapi.codes.PopulationCode`). Training data are two views of the same
body-centred positions, ``(x0, y0, x1, y1)``: the winner is found from view 0 and learns
view 1. The functions here turn what a caller passes into float64 arrays of those shapes, or
raise :class:`~sigmapi.errors.DataError` (a ``ValueError``) naming the array, the shape
expected, what was received and the fix. They know grids and codes, not the estimator.

Examples
--------
>>> from sigmapi.codes import PopulationCode
>>> code = PopulationCode((5,))
>>> x0, y0, x1, y1 = encode_views(code, code, [0.2], [0.4], [0.5], [0.1])
>>> check_views((x0, y0, x1, y1), (5,), (5,))[0].shape
(1, 5)
>>> check_codes(np.zeros((2, 4)), "x", (5,))  # doctest: +ELLIPSIS
Traceback (most recent call last):
    ...
sigmapi.errors.DataError: x must have shape (B, 5) (codes on grid (5,), ...), got (2, 4); ...
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError, DataError

__all__ = [
    "MAX_PRODUCT",
    "CodeViews",
    "StreamFrames",
    "Views",
    "check_codes",
    "check_frames",
    "check_gates",
    "check_pairs",
    "check_views",
    "encode_views",
    "fit_views",
]

MAX_PRODUCT = 1e15
"""Largest ``|x_i y_j|`` of the views a model learns (weights move towards ``x y^T``): keeps
every backend's weights far inside float32's range (see :data:`sigmapi.config.MAX_INIT_SCALE`)."""

Views = tuple[ArrayLike, ArrayLike, ArrayLike, ArrayLike]
"""Your own two-view data ``(x0, y0, x1, y1)``: codes ``(B, n_x)``, ``(B, n_y)``, ``(B, n_x)``,
``(B, n_y)``; row b holds two views of the same body-centred position."""

StreamFrames = tuple[ArrayLike, ArrayLike]
"""A stream ``(x, y)``: codes ``(T, n_x)`` and ``(T, n_y)``, row t the view of frame t, in time
order, with no mark of when the object moved (``SigmaPiSOM.fit_stream``)."""

Array = NDArray[np.float64]
CodeViews = tuple[Array, Array, Array, Array]
"""Checked views: four float64 arrays of the same number of rows."""


def _asarray(a: ArrayLike, name: str, what: str) -> NDArray[np.generic]:
    """``np.asarray(a)``; ragged nested lists raise DataError naming ``name``."""
    try:
        return np.asarray(a)
    except (ValueError, TypeError) as exc:
        raise DataError(
            f"{name} must be a rectangular array of {what}, got {type(a).__name__} that numpy "
            f"cannot make one of ({str(exc)[:80]}); give every row the same length"
        ) from None


def _distinct(arr: NDArray[np.generic]) -> NDArray[np.generic]:
    """The part of ``arr`` that holds every value once where an axis repeats it (stride 0, as
    ``np.broadcast_to`` makes): checks then cost the data, not the shape."""
    repeated = [st == 0 and dim > 1 for st, dim in zip(arr.strides, arr.shape, strict=True)]
    if not any(repeated):
        return arr
    return arr[tuple(slice(0, 1) if r else slice(None) for r in repeated)]


def check_codes(a: ArrayLike, name: str, shape: tuple[int, ...]) -> Array:
    """``a`` as float64 codes ``(B, prod(shape))`` (one row ``(n,)`` becomes ``(1, n)``).

    Raises :class:`~sigmapi.errors.DataError` unless ``a`` is numeric, of that shape, and
    finite. Rows repeated by a stride of 0 are checked (and converted) once.
    """
    arr = _asarray(a, name, "codes")
    if arr.dtype.kind not in "fiub":
        raise DataError(
            f"{name} must be a numeric array, got dtype {arr.dtype}; pass codes as floats"
        )
    n = math.prod(shape)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != n:
        raise DataError(
            f"{name} must have shape (B, {n}) (codes on grid {shape}, flattened in C order), "
            f"got {np.shape(a)}; encode positions with model.x_code.encode / y_code.encode"
        )
    part = _distinct(arr)
    out: Array
    if part is not arr:  # keep the repetition a view: no (B, n) copy
        out = np.broadcast_to(part.astype(np.float64, copy=False), arr.shape)
        part = _distinct(out)
    else:
        out = arr.astype(np.float64, copy=False)
        part = out
    if not np.isfinite(part.sum()) and not np.all(np.isfinite(part)):  # one pass when finite
        raise DataError(f"{name} must be finite, got NaN or inf values; remove those rows")
    return out


def _same_rows(arrays: dict[str, Array], what: str) -> None:
    rows = [a.shape[0] for a in arrays.values()]
    if len(set(rows)) > 1:
        raise DataError(
            f"{what} must have the same number of rows, got {', '.join(map(str, rows))}; "
            f"row b of {', '.join(arrays)} holds one sample"
        )


def check_pairs(
    x: ArrayLike, y: ArrayLike, x_shape: tuple[int, ...], y_shape: tuple[int, ...]
) -> tuple[Array, Array]:
    """Input pairs ``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)`` as checked codes (see
    :func:`check_codes`), of the same number of rows."""
    xa, ya = check_codes(x, "x", x_shape), check_codes(y, "y", y_shape)
    _same_rows({"x": xa, "y": ya}, "x and y")
    return xa, ya


def check_views(views: object, x_shape: tuple[int, ...], y_shape: tuple[int, ...]) -> CodeViews:
    """Two views ``(x0, y0, x1, y1)`` as checked codes of the same number of rows.

    Besides :func:`check_codes` on each array: ``|x_i y_j|`` of each view must stay within
    :data:`MAX_PRODUCT` (the weights learn ``x1 y1^T``, the winner weighs ``x0 y0^T``).
    """
    got = _what(views)
    if got.startswith("one array") or not isinstance(views, tuple | list) or len(views) != 4:
        raise DataError(
            f"views must be a tuple (x0, y0, x1, y1) of 4 code arrays, got {got}; row b "
            "holds two views of one position (encode positions with model.encode_views)"
        )
    shapes = (x_shape, y_shape, x_shape, y_shape)
    names = ("x0", "y0", "x1", "y1")
    arrays = {n: check_codes(v, n, s) for n, v, s in zip(names, views, shapes, strict=True)}
    _same_rows(arrays, "views")
    x0, y0, x1, y1 = arrays.values()
    for xv, yv, v in ((x1, y1, "1"), (x0, y0, "0")):
        # the weights learn x1 y1^T; the winner (and an ordering's eigh) uses x0 y0^T alike
        _check_product(xv, yv, f"views x{v} and y{v}", v)
    return x0, y0, x1, y1


def _what(obj: object) -> str:
    """What a caller passed where a tuple of arrays belongs, in words."""
    if isinstance(obj, np.ndarray):
        return f"one array of shape {obj.shape}"
    if isinstance(obj, tuple | list):
        return f"a {type(obj).__name__} of {len(obj)} items"
    return type(obj).__name__


def _check_product(xv: Array, yv: Array, name: str, sub: str = "") -> None:
    """A DataError unless ``|x_i y_j|`` stays within :data:`MAX_PRODUCT` (the map multiplies
    them): ``name`` the arrays, ``sub`` their index in the message (``x1_i``)."""
    top = float(np.abs(_distinct(xv)).max(initial=0.0))
    top *= float(np.abs(_distinct(yv)).max(initial=0.0))
    if top > MAX_PRODUCT:
        raise DataError(
            f"{name} must have |x{sub}_i y{sub}_j| <= {MAX_PRODUCT:g} (the map multiplies them "
            f"and would overflow), got up to {top:.3g}; scale your codes to about 1 "
            "(model.x_code.encode gives unit-length codes)"
        )


def check_frames(
    frames: object, x_shape: tuple[int, ...], y_shape: tuple[int, ...], least: int = 1
) -> tuple[Array, Array]:
    """A stream ``(x, y)`` as checked codes ``(T, n_x)``, ``(T, n_y)`` of at least ``least``
    frames (see :func:`check_codes`; ``|x_i y_j|`` within :data:`MAX_PRODUCT`)."""
    if isinstance(frames, np.ndarray) or not isinstance(frames, tuple | list) or len(frames) != 2:
        raise DataError(
            f"frames must be a tuple (x, y) of 2 code arrays, got {_what(frames)}; row t holds "
            "the view of frame t (encode positions with model.x_code.encode / y_code.encode)"
        )
    x, y = check_codes(frames[0], "x", x_shape), check_codes(frames[1], "y", y_shape)
    _same_rows({"x": x, "y": y}, "frames x and y")
    if x.shape[0] < least:
        raise DataError(
            f"frames must hold at least {least} frame{'s' if least > 1 else ''}, got "
            f"{x.shape[0]}; a stream learns frame t + 1 under the trace of the frames before"
        )
    _check_product(x, y, "frames x and y")
    return x, y


def fit_views(
    views: object, x_shape: tuple[int, ...], y_shape: tuple[int, ...], method: str
) -> CodeViews | None:
    """The ``views`` argument of ``fit`` / ``partial_fit`` (``method``): None (the built-in
    task) or :func:`check_views`'s codes; an int is refused with the keyword that takes it."""
    if views is None:
        return None
    if _validate.is_int(views):
        raise ConfigError(
            f"views must be a tuple (x0, y0, x1, y1) of code arrays or None, got the int "
            f"{views}; pass an iteration count by name: {method}(iterations={views})"
        )
    return check_views(views, x_shape, y_shape)


def encode_views(
    x_code: PopulationCode,
    y_code: PopulationCode,
    px0: ArrayLike,
    py0: ArrayLike,
    px1: ArrayLike,
    py1: ArrayLike,
) -> CodeViews:
    """Two views given as positions, as codes ``(x0, y0, x1, y1)``.

    ``px0``, ``px1`` are encoded with ``x_code`` and ``py0``, ``py1`` with ``y_code``; each is
    of shape ``(B, d)`` (``(B,)`` in 1-D) in [0, 1], checked by
    :meth:`~sigmapi.codes.PopulationCode.check_positions` under its own name.
    """
    pos = {"px0": px0, "py0": py0, "px1": px1, "py1": py1}
    for name, p in pos.items():
        if _asarray(p, name, "positions").size == 0:
            raise DataError(
                f"{name} holds no positions, got an empty array; give at least "
                "one row (one position per row)"
            )
    checked = [
        code.check_positions(p, name)
        for code, (name, p) in zip((x_code, y_code, x_code, y_code), pos.items(), strict=True)
    ]
    rows = {name: len(c) for name, c in zip(pos, checked, strict=True)}
    if len(set(rows.values())) > 1:  # row b of the four shows one position twice
        raise DataError(
            f"px0, py0, px1 and py1 must have the same number of rows (one per "
            f"pair of views), got {rows}; give one row per pair in each"
        )
    out = [
        code.encode(c) for code, c in zip((x_code, y_code, x_code, y_code), checked, strict=True)
    ]
    return out[0], out[1], out[2], out[3]


def check_gates(gates: object, n: int, n_units: int) -> NDArray[np.float64]:
    """``gates`` as a float ``(n, n_units)`` array of numbers in ``[0, 1]`` (one row per view
    pair, one column per unit); a DataError naming the problem otherwise (ragged rows too)."""
    try:
        raw = np.asarray(gates)
        if raw.dtype.kind not in "fiub":  # complex (its imaginary part lost), text, objects
            raise TypeError(f"dtype {raw.dtype}")
        g = raw.astype(np.float64)
    except (TypeError, ValueError) as exc:  # ragged rows, None, text, complex
        raise DataError(
            f"gates must be a ({n}, {n_units}) array of real numbers in [0, 1], got "
            f"{type(gates).__name__} that numpy cannot make one of ({str(exc)[:80]}); give "
            "every row one real gate per unit"
        ) from None
    if g.shape != (n, n_units):
        raise DataError(
            f"gates must have shape ({n}, {n_units}) (one row per view pair, one column per "
            f"unit), got {g.shape}; give one gate per unit and pair"
        )
    if not np.all(np.isfinite(g)) or g.min(initial=0.0) < 0 or g.max(initial=0.0) > 1:
        raise DataError(
            f"gates must be finite numbers in [0, 1], got values in [{g.min():.3g}, "
            f"{g.max():.3g}]; clip them (0: no change, 1: the full update)"
        )
    return g
