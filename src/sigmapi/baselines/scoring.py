"""How ``sigmapi compare`` scores a method: by the unit it answers with, or by a read-out.

:func:`score_units` scores a map (its output is a unit); :func:`score_readout` a method whose
output is a feature vector read out linearly (:func:`~sigmapi.baselines.readout.fit_readout`).
Both return the view consistency, the same without labels, and the z error per number of
labelled samples (the definitions in :mod:`sigmapi.experiments.compare.run`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from sigmapi.baselines.readout import fit_readout
from sigmapi.metrics import z_decoder
from sigmapi.tasks import Batch

__all__ = ["score_readout", "score_units"]

Array = NDArray[np.float64]


def _bins(z: Array, lo: float, hi: float, shape: tuple[int, ...]) -> NDArray[np.int64]:
    """Flat cell of each read-out ``z`` ``(B, d)`` on a grid of ``shape`` cells over [lo, hi]."""
    n = np.asarray(shape)
    cell = np.clip(np.floor((z - lo) / (hi - lo) * n), 0, n - 1).astype(np.int64)
    return np.asarray(np.ravel_multi_index(tuple(cell.T), shape), dtype=np.int64)


def score_units(
    unit: Callable[[Array, Array], NDArray[np.int64]],
    coords: Array,
    cal: Batch,
    test: Batch,
    labels: Sequence[int],
    spacing: Array,
) -> tuple[float, float, dict[int, float]]:
    """View consistency and z error per number of labels of a map whose output is a unit.

    Returns ``(view consistency, the same again (a map's unit needs no label), curve)``.
    """
    w0, w1, wc = unit(test.x0, test.y0), unit(test.x1, test.y1), unit(cal.x0, cal.y0)
    curve = {}
    for n in labels:
        table = z_decoder(wc[:n], cal.z[:n], coords)
        curve[n] = _rmse(table[w0] - test.z, spacing)
    same = float(np.mean(w0 == w1))
    return same, same, curve


def score_readout(
    features: Callable[[Array, Array], Array],
    cal: Batch,
    test: Batch,
    labels: Sequence[int],
    spacing: Array,
    cells: tuple[tuple[float, float], tuple[int, ...]],
) -> tuple[float, float, dict[int, float]]:
    """View consistency and z error per number of labels of a read-out.

    Returns ``(same cell of the binned read-out, same most active middle-layer unit (no
    label used), curve)``.
    """
    fc, f0, f1 = features(cal.x0, cal.y0), features(test.x0, test.y0), features(test.x1, test.y1)
    curve = {}
    for n in labels:
        readout = fit_readout(fc[:n], cal.z[:n])
        curve[n] = _rmse(readout(f0) - test.z, spacing)
    (lo, hi), shape = cells
    b0, b1 = _bins(readout(f0), lo, hi, shape), _bins(readout(f1), lo, hi, shape)
    unit = float(np.mean(np.argmax(f0, axis=1) == np.argmax(f1, axis=1)))
    return float(np.mean(b0 == b1)), unit, curve


def _rmse(err: Array, spacing: Array) -> float:
    return float(np.sqrt(np.mean(np.sum((err * spacing) ** 2, axis=1))))
