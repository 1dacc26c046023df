"""The iCub as a view source: map 1's view pairs, coded, from the robot's own saccades.

The 2-D table task's first map (``sigmapi icub``, :mod:`sigmapi.experiments.icub.maps`) learns
from pairs of views of one ball taken with the head still: the eyes move between the two
views, so the pair shares the ball's head-centred direction
(:func:`~sigmapi.envs.icub.frames.view_pairs`, ``stage="eyes"``). :class:`ICubViews` hands
those pairs out as the codes the map reads (the right eye's retina and its eye angles, each a
``grid x grid`` population code), so that the kit's tools take the iCub as they take any
:class:`~sigmapi.envs.ViewSource` (:func:`~sigmapi.envs.collect_saccade_views`, the iCub's
world in :mod:`sigmapi.experiments.kit.worlds`). The scene is sealed: the ball's place is the
experimenter's (:func:`~sigmapi.envs.icub.frames.place_ball`), the retina is the colour
detector's find in the rendered frame and the gaze the robot's own search; no true position
leaves :meth:`~ICubViews.sample_views`.

The scalings below (:func:`retina_position`, :func:`eye_position`, :func:`neck_position`) are
the ones the experiment's maps and associations read.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.codes import PopulationCode
from sigmapi.envs.icub.frames import (
    BALLS,
    GAZE_HIGH,
    GAZE_LOW,
    PAIRS_PER_BALL,
    ViewBatch,
    view_pairs,
)
from sigmapi.envs.icub.scene import EYE_SIZE, ICubScene
from sigmapi.envs.protocols import Views

__all__ = ["GRID", "ICubViews", "eye_position", "neck_position", "retina_position", "view_codes"]

Array = NDArray[np.float64]

GRID = 16
"""Units per axis of map 1's codes by default (the retina's and the eye angles')."""

_EYE_LO = np.array([GAZE_LOW[0], GAZE_LOW[1] - 0.5 * GAZE_HIGH[2]])
_EYE_HI = np.array([GAZE_HIGH[0], GAZE_HIGH[1] - 0.5 * GAZE_LOW[2]])
_NECK = [3, 5]  # pitch and yaw (the roll is held at zero)


def retina_position(v: ViewBatch, eye_size: int) -> Array:
    """The retina as positions in [0, 1]^2: ``(u, v) / eye_size``."""
    return np.clip(v.retina / eye_size, 0.0, 1.0)


def eye_position(v: ViewBatch) -> Array:
    """The right eye's tilt and pan (``version - vergence / 2``) scaled to [0, 1] over the
    range the random gazes are drawn from."""
    eye = np.column_stack([v.gaze[:, 0], v.gaze[:, 1] - 0.5 * v.gaze[:, 2]])
    return np.clip((eye - _EYE_LO) / (_EYE_HI - _EYE_LO), 0.0, 1.0)


def neck_position(v: ViewBatch) -> Array:
    """The neck's pitch and yaw scaled to [0, 1]."""
    lo, hi = GAZE_LOW[_NECK], GAZE_HIGH[_NECK]
    return np.clip((v.gaze[:, _NECK] - lo) / (hi - lo), 0.0, 1.0)


def view_codes(
    x_code: PopulationCode, y_code: PopulationCode, v: ViewBatch, eye_size: int
) -> tuple[Array, Array]:
    """Map 1's inputs for views ``v``: ``x_code`` of the retina, ``y_code`` of the eye
    angles."""
    return x_code.encode(retina_position(v, eye_size)), y_code.encode(eye_position(v))


class ICubViews:
    """Map 1's view pairs on the iCub (a :class:`~sigmapi.envs.ViewSource`).

    Parameters
    ----------
    grid : int
        Units per axis of the retina's and the eye angles' codes (3 to 64).
    code_width : float
        Width of the codes' hills, grid units.
    moved_share : float
        Share of the pairs in which the experimenter moved the ball between the views.
    balls : {"table", "directions"}
        Where the experimenter puts the balls (:data:`~sigmapi.envs.icub.frames.BALLS`).
    per_ball : int
        Pairs the robot records of one ball before the next is put down.
    eye_size : int
        Side of each eye's image, pixels.

    The MuJoCo scene is built (and sealed) at the first :meth:`sample_views`, so that the
    codes can be read without MuJoCo.
    """

    def __init__(
        self,
        grid: int = GRID,
        code_width: float = 1.0,
        moved_share: float = 0.0,
        balls: str = "table",
        per_ball: int = PAIRS_PER_BALL,
        eye_size: int = EYE_SIZE,
    ) -> None:
        grid = _validate.integer("grid", grid, 3, 64, fix="e.g. grid=16")
        self.x_code = PopulationCode((grid, grid), code_width)
        """The code of the right eye's retina (the views' ``x0``, ``x1``)."""
        self.y_code = PopulationCode((grid, grid), code_width)
        """The code of the right eye's tilt and pan (``y0``, ``y1``)."""
        self.moved_share = _validate.number("moved_share", moved_share, 0.0, 1.0)
        self.balls = _validate.choice("balls", balls, BALLS)
        self.per_ball = _validate.integer("per_ball", per_ball, 1, 100, fix="e.g. per_ball=2")
        self.eye_size = _validate.integer("eye_size", eye_size, 8, 240, fix="e.g. 64")
        self._scene: ICubScene | None = None

    @property
    def scene(self) -> ICubScene:
        """The sealed scene the views are recorded in (built at first use)."""
        if self._scene is None:
            self._scene = ICubScene(self.eye_size)
            self._scene.seal()
        return self._scene

    def sample_pairs(self, n: int, rng: np.random.Generator) -> tuple[ViewBatch, ViewBatch]:
        """``n`` pairs of measured views (with their truth labels, for scoring), drawn from
        ``rng`` as :meth:`sample_views` draws them."""
        n = _validate.integer("n", n, 1, fix="e.g. 2000")
        return view_pairs(
            self.scene,
            n,
            rng,
            stage="eyes",
            moved_share=self.moved_share,
            balls=self.balls,
            per_ball=self.per_ball,
        )

    def codes(self, v: ViewBatch) -> tuple[Array, Array]:
        """The codes of views ``v`` (:func:`view_codes`)."""
        return view_codes(self.x_code, self.y_code, v, self.eye_size)

    def sample_views(self, n: int, rng: np.random.Generator) -> Views:
        """``n`` view pairs of balls the robot found, as codes ``(x0, y0, x1, y1)``; every
        random choice from ``rng``."""
        a, b = self.sample_pairs(n, rng)
        return (*self.codes(a), *self.codes(b))
