"""The fast kernel's weight layout in plain NumPy: its state as its model files hold it.

``W[k] = scale[k] * raw[:, k].reshape(n_x, n_y)``: ``raw`` ``(n_x * n_y, K)`` (float32, or
float64 in exact mode), per-unit ``scale`` ``(K,)`` (float64) and, where tracked, ``sqnorm``
``(K,)`` ``= sum_p raw[p, k]**2`` (float64). Model file members: ``state_raw``,
``state_scale`` and ``state_sqnorm``; version-1 files also held the dense float64
``weights``, which must agree exactly with ``raw x scale``.

No numba here, so that every machine reads such files, also one where the fast kernel does
not import (:func:`sigmapi.kernels.file_weights` falls back to :func:`file_weights`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "columns_to_dense",
    "columns_top",
    "file_weights",
    "read_file",
    "sqnorms",
    "to_file",
    "version1_members",
]

Shape = tuple[int, int, int]
MEMBERS = ("state_raw", "state_scale", "state_sqnorm")
"""The model file members of this layout (``state_sqnorm`` only while the norms are current)."""
_VERSION_1 = "weights"


def version1_members(
    shape: Shape, floats: tuple[str, ...]
) -> dict[str, tuple[tuple[str, ...], tuple[int, ...]]]:
    """The state arrays a version-1 model file may hold (this layout, of fixed shapes, under
    ``state_<name>``): name -> (allowed dtypes, shape) for weights of ``shape`` ``(K, n_x,
    n_y)``; ``raw`` in any of ``floats``, the per-unit arrays in float64."""
    k, nx, ny = shape
    per_unit = (("<f8",), (k,))
    return {"raw": (floats, (nx * ny, k)), "scale": per_unit, "sqnorm": per_unit}


def columns_top(raw: NDArray[np.floating], scale: NDArray[np.floating], shape: Shape) -> float:
    """Largest ``|W[k, i, j]|`` of the layout, without forming ``W``; NaN or inf if ``raw``
    holds them or the product overflows.

    Raises ``ValueError`` if the shapes do not fit ``shape`` (``(K, n_x, n_y)``) or a scale is
    not finite and > 0.
    """
    k, nx, ny = shape
    raw, scale = np.asarray(raw), np.asarray(scale)
    if raw.shape != (nx * ny, k) or raw.dtype.kind != "f":
        raise ValueError(f"raw must be float of shape {(nx * ny, k)}, got {raw.dtype} {raw.shape}")
    if scale.shape != (k,) or scale.dtype != np.float64:
        raise ValueError(f"scale must be float64 of shape ({k},), got {scale.dtype} {scale.shape}")
    if not np.all(np.isfinite(scale) & (scale > 0)):
        raise ValueError("scale must be finite and > 0")
    if raw.size == 0:
        return 0.0
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is the answer here
        return float((np.abs(raw).max(axis=0).astype(np.float64) * scale).max())


def columns_to_dense(
    raw: NDArray[np.floating], scale: NDArray[np.floating], shape: Shape
) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)``: ``W[k] = scale[k] * raw[:, k]`` (an overflow
    gives inf, for the caller to refuse)."""
    columns_top(raw[:0], scale, (shape[0], 0, 0))  # checks the scales
    k, nx, ny = shape
    if np.shape(raw) != (nx * ny, k):
        raise ValueError(f"raw must have shape {(nx * ny, k)}, got {np.shape(raw)}")
    with np.errstate(over="ignore"):
        w = np.asarray(raw).T.astype(np.float64) * scale[:, None]
    return np.ascontiguousarray(w.reshape(k, nx, ny))


def sqnorms(raw: NDArray[np.floating]) -> NDArray[np.float64]:
    """``sum_p raw[p, k]**2`` in float64, in blocks of rows (no full float64 copy)."""
    sq = np.zeros(raw.shape[1])
    for s in range(0, raw.shape[0], 4096):
        r = raw[s : s + 4096].astype(np.float64)
        sq += np.einsum("pk,pk->k", r, r)
    return sq


def to_file(
    raw: NDArray[np.floating], scale: NDArray[np.float64], sqnorm: NDArray[np.float64] | None
) -> dict[str, NDArray[np.floating]]:
    """The model file arrays of the layout (copies): ``state_raw``, ``state_scale`` and,
    where given (the norms are current), ``state_sqnorm``."""
    out = {"state_raw": raw.copy(), "state_scale": scale.copy()}
    if sqnorm is not None:
        out["state_sqnorm"] = sqnorm.copy()
    return out


def read_file(
    shape: Shape, arrays: dict[str, NDArray[np.floating]]
) -> tuple[NDArray[np.floating], NDArray[np.float64], NDArray[np.float64] | None]:
    """``(raw, scale, sqnorm or None)`` of a model file's arrays, checked against ``shape``.

    Raises ``ValueError`` if members are missing or unknown, do not fit ``shape``, are not
    finite (scales must be > 0), or, in a version-1 file, disagree with its ``weights``.
    """
    k = shape[0]
    names = set(arrays)
    if not {"state_raw", "state_scale"} <= names or names - {*MEMBERS, _VERSION_1}:
        raise ValueError(
            "the fast kernel's file arrays are state_raw, state_scale [, state_sqnorm] "
            f"(version 1: and weights), got {sorted(names)}"
        )
    raw, scale = arrays["state_raw"], arrays["state_scale"]
    columns_top(raw, scale, shape)  # checks shapes, dtypes and scales
    if not np.all(np.isfinite(raw)):
        raise ValueError("raw must be finite")
    sq = arrays.get("state_sqnorm")
    if sq is not None and sq.shape != (k,):
        raise ValueError(f"sqnorm must have shape ({k},), got {sq.shape}")
    w = arrays.get(_VERSION_1)
    if w is not None and not np.array_equal(columns_to_dense(raw, scale, shape), w):
        raise ValueError("the state (raw x scale) disagrees with the stored weights")
    sq64 = None if sq is None else np.asarray(sq, dtype=np.float64)
    return raw, np.asarray(scale, dtype=np.float64), sq64


def file_weights(shape: Shape, arrays: dict[str, NDArray[np.floating]]) -> NDArray[np.float64]:
    """Dense float64 weights ``(K, n_x, n_y)`` of a model file's arrays in this layout."""
    raw, scale, _ = read_file(shape, arrays)
    return columns_to_dense(raw, scale, shape)
