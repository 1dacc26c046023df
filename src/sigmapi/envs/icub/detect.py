"""What the eyes see: the ball and the hand found in an eye's rendered pixels by their colours.

The robot finds a target in an RGB frame by its colour alone, as iCub experiments find a
coloured ball and a marked hand: a pixel is the target's when its colour passes the target's
rule (:data:`COLOURS`: the red ball, the green marker on the back of the right hand,
:data:`~sigmapi.envs.icub.model.HAND_MARKER`), and the target's retinal position ``(u, v)`` is
the centroid of those pixels (pixel centres at ``j + 0.5``, ``i + 0.5``; ``u`` along columns,
as :meth:`~sigmapi.envs.icub.scene.ICubScene.project` counts them).

A detection is valid when at least ``min_pixels`` pixels pass (:data:`MIN_PIXELS`) and none
lies on the image's outermost row or column (a blob cut by the border has a biased centroid);
else :func:`detect` says None and the sample is dropped or the eyes move. Nothing here reads
the simulator's state: only the pixels.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["COLOURS", "MIN_PIXELS", "TARGETS", "detect", "mask"]

TARGETS = ("ball", "hand")
"""What the detector finds."""
COLOURS = {"ball": (0, (1, 2)), "hand": (1, (0, 2))}
"""Each target's colour rule: ``(channel, others)``: the pixel's ``channel`` above 150 and its
``others`` below 100 (the ball is drawn flat red, the marker flat green, ``emission=1``; the
table, floor and hand are neither)."""
MIN_PIXELS = {"ball": 6, "hand": 4}
"""The fewest pixels of a valid detection, per target (what the ball and the marker cover in
a frame: docs/guide/icub.md)."""


def mask(image: NDArray[Any], target: str) -> NDArray[np.bool_]:
    """The pixels of ``image`` ``(H, W, 3)`` that pass ``target``'s colour rule."""
    channel, others = COLOURS[target]
    img = np.asarray(image)
    out = img[..., channel] > 150
    for k in others:
        out &= img[..., k] < 100
    return out


def detect(image: NDArray[Any], target: str) -> NDArray[np.float64] | None:
    """``target``'s retinal position ``(u, v)`` in ``image``, or None when the detection is
    not valid (too few pixels, or the blob touches the border: the module's account)."""
    m = mask(image, target)
    rows, cols = np.nonzero(m)
    if rows.size < MIN_PIXELS[target]:
        return None
    h, w = m.shape
    if rows.min() == 0 or cols.min() == 0 or rows.max() == h - 1 or cols.max() == w - 1:
        return None
    return np.array([cols.mean() + 0.5, rows.mean() + 0.5])
