"""The gaze-and-reach world drawn as a small picture (its ``rgb_array`` render)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["COLOURS", "draw_workspace"]

COLOURS = {
    "workspace": (225, 225, 225),
    "goal": (150, 220, 150),
    "gaze": (40, 90, 220),
    "object": (220, 40, 40),
}
"""RGB of each part of the picture (the background is white)."""


def draw_workspace(
    goal: NDArray[np.float64],
    goal_radius: float,
    gaze: NDArray[np.float64],
    obj: NDArray[np.float64],
    size: int = 96,
    pad: int = 16,
) -> NDArray[np.uint8]:
    """A picture of the workspace ``[0, 1]^d``, uint8 ``(H, W, 3)``, ``d`` = ``len(goal)``.

    Grey: the workspace (``size`` pixels a side, ``pad`` of white around it); green: the goal
    box (centre ``goal``, Chebyshev radius ``goal_radius``); blue: lines through the gaze
    direction; red: the object (outside the grey square once it has left the view). 1-D
    tasks are drawn as a strip; axis 1 points up.
    """
    dim = len(goal)
    rows = size if dim == 2 else 24
    img = np.full((rows + 2 * pad, size + 2 * pad, 3), 255, dtype=np.uint8)

    def px(p: NDArray[np.float64]) -> tuple[int, int]:
        c = int(np.clip(round(pad + p[0] * (size - 1)), 0, size + 2 * pad - 1))
        if dim == 1:
            return pad + rows // 2, c
        r = int(np.clip(round(pad + (1.0 - p[1]) * (size - 1)), 0, rows + 2 * pad - 1))
        return r, c

    img[pad : pad + rows, pad : pad + size] = COLOURS["workspace"]
    lo = np.maximum(goal - goal_radius, 0.0)
    hi = np.minimum(goal + goal_radius, 1.0)
    (r0, c0), (r1, c1) = px(lo), px(hi)
    r0, r1 = (pad, pad + rows) if dim == 1 else (r1, r0 + 1)
    img[r0:r1, c0 : c1 + 1] = COLOURS["goal"]
    gr, gc = px(gaze)
    img[pad : pad + rows, gc] = COLOURS["gaze"]
    if dim == 2:
        img[gr, pad : pad + size] = COLOURS["gaze"]
    zr, zc = px(obj)
    img[max(zr - 3, 0) : zr + 4, max(zc - 3, 0) : zc + 4] = COLOURS["object"]
    return img
