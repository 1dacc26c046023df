"""Two views of one body-centred position from the robot's own movements.

The base keeps still and the ball lies still on the table; the head makes two saccades, each
to a neck pose drawn uniformly among those that keep the ball in view
(:meth:`~sigmapi.envs.robot.frames.Frames.saccade`). The two ``(retina, gaze)`` readings are two
views of one ``z``: the data :meth:`SigmaPiSOM.fit(views) <sigmapi.SigmaPiSOM.fit>` learns
from. A share ``moved_share`` of the pairs is spoiled as in a real recording: the ball is moved
to a fresh random place between the two views, so the pair's views show two different ``z``.

The ball's places are uniform over the :class:`~sigmapi.envs.robot.frames.Workspace` in
``(azimuth, elevation)``; ``z`` is recorded for analysis only. :class:`RobotViews` is a
:class:`~sigmapi.envs.PlacedViewSource`: :func:`~sigmapi.envs.collect_saccade_views` and
:func:`~sigmapi.envs.learn_map_in_env` take it as they take any view source.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.envs.protocols import Views
from sigmapi.envs.robot.frames import RETINA_SOURCES, Frames, FramesCodes, Workspace
from sigmapi.envs.robot.scene import Scene
from sigmapi.errors import DataError

__all__ = ["RobotViewBatch", "RobotViews"]

F64 = NDArray[np.float64]


class RobotViewBatch(NamedTuple):
    """View pairs with what analysis needs: codes, positions and the true ``z``.

    ``x0, y0, x1, y1``: codes ``(n, grid**2)``; ``z``: the workspace position ``(n, 2)`` of
    the ball at view 0 (``z1`` at view 1: the same unless ``moved``); ``direction``: view 0's
    ``(azimuth, elevation)`` in radians; ``px0, py0, px1, py1``: retinal and gaze positions in
    ``[0, 1]^2``.
    """

    x0: F64
    y0: F64
    x1: F64
    y1: F64
    z: F64
    z1: F64
    moved: NDArray[np.bool_]
    direction: F64
    px0: F64
    py0: F64
    px1: F64
    py1: F64

    @property
    def views(self) -> Views:
        """``(x0, y0, x1, y1)``, for ``SigmaPiSOM.fit(views)``."""
        return self.x0, self.y0, self.x1, self.y1


class RobotViews(FramesCodes):
    """A view source on the simulated robot (:class:`~sigmapi.envs.PlacedViewSource`).

    ``sample_views(n, rng)`` gives ``n`` view pairs, ``views_of(z, rng)`` one view of each
    given ``z``; the codes are :attr:`x_code` (retina) and :attr:`y_code` (gaze), both on a
    ``grid x grid`` grid.

    Parameters
    ----------
    grid : int
        Units per axis of the retina and gaze codes.
    code_width : float
        Width of the codes' hills, grid units.
    moved_share : float
        Fraction of pairs in which the ball moved between the two views (a nuisance).
    retina : {"projection", "pixels"}
        The retinal position from the camera's exact projection (fast) or from the rendered
        pixels (a blob centroid per view; about a millisecond or more per frame).
    margin : float
        Pixels kept between the ball's centre and the image border.
    workspace : Workspace, optional
        The ball's body-centred places.

    Examples
    --------
    >>> source = RobotViews(grid=7)
    >>> x0, y0, x1, y1 = source.sample_views(3, np.random.default_rng(0))
    >>> x0.shape, y1.shape, source.x_code.shape
    ((3, 49), (3, 49), (7, 7))
    """

    def __init__(
        self,
        grid: int = 9,
        code_width: float = 1.0,
        moved_share: float = 0.0,
        retina: str = "projection",
        margin: float = 6.0,
        workspace: Workspace | None = None,
    ) -> None:
        self.moved_share = _validate.number(
            "moved_share", moved_share, 0.0, 1.0, fix="a fraction of the pairs, e.g. 0.1"
        )
        self.retina = _validate.choice("retina", retina, RETINA_SOURCES)
        self.frames = Frames(Scene(), grid, code_width, margin, workspace)

    def sample_views(self, n: int, rng: np.random.Generator) -> Views:
        """``n`` view pairs ``(x0, y0, x1, y1)``, codes ``(n, grid**2)`` each."""
        return self.sample_views_with_z(n, rng).views

    def views_of(self, z: F64, rng: np.random.Generator) -> tuple[F64, F64]:
        """One view of each workspace position ``z`` ``(B, 2)`` (the body at the origin, a
        saccade to a neck pose that sees the ball): the codes ``x`` and ``y``."""
        z = np.atleast_2d(np.asarray(z, dtype=np.float64))
        if z.ndim != 2 or z.shape[1] != 2:
            raise _validate.fail("z", "positions of shape (B, 2)", z.shape, error=DataError)
        pos = np.empty((2, len(z), 2))
        for i, place in enumerate(z):
            self.frames.place_still(place)
            pos[0, i], pos[1, i] = self._view(rng)
        x, y = (self.frames.code.encode(np.clip(p, 0.0, 1.0)) for p in pos)
        return x, y

    def _view(self, rng: np.random.Generator) -> tuple[F64, F64]:
        while True:
            seen = self.frames.look(self.frames.saccade(rng), self.retina)
            if seen is not None:  # the pixels can disagree with the projection at the border
                return seen

    def sample_views_with_z(self, n: int, rng: np.random.Generator) -> RobotViewBatch:
        """``n`` view pairs with their true ``z`` (:class:`RobotViewBatch`)."""
        n = _validate.integer("n", n, 1, fix="e.g. n=20000")
        f = self.frames
        z = rng.random((n, 2))
        moved = rng.random(n) < self.moved_share
        z1 = np.where(moved[:, None], rng.random((n, 2)), z)
        pos = np.empty((4, n, 2))
        direction = np.empty((2, n, 2))
        for i in range(n):
            for view, place in enumerate((z[i], z1[i])):
                if view == 0 or moved[i]:
                    f.place_still(place)
                    direction[view, i] = f.direction(f.scene.object_position()[None, :])[0]
                else:
                    direction[1, i] = direction[0, i]
                pos[2 * view, i], pos[2 * view + 1, i] = self._view(rng)
        x0, y0, x1, y1 = (f.code.encode(np.clip(p, 0.0, 1.0)) for p in pos)
        return RobotViewBatch(
            x0, y0, x1, y1, f.z(direction[0]), f.z(direction[1]), moved, direction[0], *pos
        )
