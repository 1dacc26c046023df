"""The three frames of the robot, measured in the simulator: retina x, gaze y, body-centred z.

- **retina x**: where the ball is in the head camera's image, ``(u, v)`` pixels, either from
  the rendered pixels (the red blob's centroid, :func:`~sigmapi.envs.robot.scene.blob_centroid`)
  or from the camera's exact projection of the ball's centre (:meth:`Scene.project`); as a
  position in ``[0, 1]^2``: ``(u - m) / (W - 2 m)``, ``(v - m) / (H - 2 m)`` with a margin of
  ``m`` pixels (a view keeps the whole ball inside the image).
- **gaze y**: the neck angles ``(pan, tilt)``, as a position in ``[0, 1]^2`` over the joints'
  limits.
- **body-centred z**: the ball's direction from the neck point in the torso's frame,
  ``(azimuth, elevation)`` in radians, and as a position in ``[0, 1]^2`` over the
  :class:`Workspace`. For analysis only: nothing the robot learns reads it.

The relation ``z = f(x, y)`` is whatever the geometry makes it: perspective, and parallax from
the camera's offset from the neck joints (the ball's retinal position under one gaze depends on
its distance as well as its direction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.codes import PopulationCode
from sigmapi.envs.robot.scene import OBJECT_RADIUS, TABLE_HEIGHT, Pose, Scene, blob_centroid
from sigmapi.errors import ConfigError

__all__ = ["RETINA_SOURCES", "Frames", "FramesCodes", "Workspace"]

RETINA_SOURCES = ("projection", "pixels")
"""Where the retinal position comes from: the camera's exact projection, or the rendered
pixels (blob centroid)."""

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Workspace:
    """The body-centred positions the robot learns and docks in: the ball's azimuth
    (radians, positive to the robot's left) and horizontal distance from the neck point
    (metres), the ball resting on the table."""

    azimuth: tuple[float, float] = (-np.deg2rad(45.0), np.deg2rad(45.0))
    distance: tuple[float, float] = (0.25, 1.3)

    def __post_init__(self) -> None:
        a, d = tuple(map(float, self.azimuth)), tuple(map(float, self.distance))
        if not -np.pi / 2 < a[0] < a[1] < np.pi / 2:
            raise ConfigError(f"azimuth must be (lo, hi) with -pi/2 < lo < hi < pi/2, got {a}")
        if not 0.0 < d[0] < d[1]:
            raise ConfigError(f"distance must be (lo, hi) with 0 < lo < hi (metres), got {d}")
        object.__setattr__(self, "azimuth", a)
        object.__setattr__(self, "distance", d)

    def elevation(self, drop: float) -> tuple[float, float]:
        """The elevation range (radians, negative: below the neck) of a ball ``drop`` metres
        below the neck point over the distance range: ``(lowest, highest)``."""
        return -float(np.arctan2(drop, self.distance[0])), -float(
            np.arctan2(drop, self.distance[1])
        )


class Frames:
    """The robot's frames and their population codes, on one :class:`Scene`.

    Parameters
    ----------
    scene : Scene
        The simulator (its state is read and set here).
    grid : int
        Units per axis of the retina and gaze codes (codes of ``grid**2`` units).
    code_width : float
        Width of the codes' Gaussian hills, grid units.
    margin : float
        Pixels between the ball's projected centre and the image border for a view to count
        (the ball's image stays whole).
    workspace : Workspace
        The body-centred positions of the ball.
    """

    def __init__(
        self,
        scene: Scene,
        grid: int = 9,
        code_width: float = 1.0,
        margin: float = 6.0,
        workspace: Workspace | None = None,
    ) -> None:
        self.scene = scene
        self.grid = _validate.integer("grid", grid, 2, fix="e.g. grid=9")
        n = self.grid**2  # the code's (n, n) float64 table of hills, and one copy of it
        _memory.check(
            16 * n * n,
            f"a robot world of grid={self.grid} ({n:,} units a view)",
            "use a smaller grid, e.g. grid=12",
        )
        self.code = PopulationCode((self.grid, self.grid), width=code_width)
        w = scene.head_size
        self.margin = _validate.number("margin", margin, 0.0, w / 4, fix="pixels, e.g. 6")
        self.workspace = workspace if workspace is not None else Workspace()
        self.drop = float(scene.neck_point()[2] - TABLE_HEIGHT - OBJECT_RADIUS)
        """How far the ball's centre lies below the neck point (metres)."""
        self.elevation = self.workspace.elevation(self.drop)

    # ------------------------------------------------------------------ x: retina
    def retinal_pixels(self, source: str = "projection") -> F64 | None:
        """The ball's ``(u, v)`` in the head camera now, by ``source`` (None: not seen)."""
        _validate.choice("source", source, RETINA_SOURCES)
        if source == "pixels":
            return blob_centroid(self.scene.render("head"))
        return self.scene.project(self.scene.object_position())[0]

    def retina(self, uv: F64) -> F64:
        """Pixel coordinates ``(..., 2)`` as retinal positions in ``[0, 1]^2`` (unclipped)."""
        m, w = self.margin, self.scene.head_size
        return (np.asarray(uv, dtype=np.float64) - m) / (w - 2.0 * m)

    def in_view(self, uv: F64) -> NDArray[np.bool_]:
        """Whether pixel coordinates ``(..., 2)`` lie inside the margin (False for NaN)."""
        x = self.retina(uv)
        with np.errstate(invalid="ignore"):
            return np.all((x >= 0.0) & (x <= 1.0), axis=-1)

    # ------------------------------------------------------------------ y: gaze
    def gaze(self, neck: F64) -> F64:
        """Neck angles ``(..., 2)`` (pan, tilt; radians) as gaze positions in ``[0, 1]^2``."""
        lo, hi = self.scene.neck_range[:, 0], self.scene.neck_range[:, 1]
        return (np.asarray(neck, dtype=np.float64) - lo) / (hi - lo)

    def neck_angles(self, y: F64) -> F64:
        """The inverse of :meth:`gaze`: positions in ``[0, 1]^2`` as neck angles (radians)."""
        lo, hi = self.scene.neck_range[:, 0], self.scene.neck_range[:, 1]
        return lo + np.asarray(y, dtype=np.float64) * (hi - lo)

    # ------------------------------------------------------------------ z: body-centred
    def direction(self, p_world: F64) -> F64:
        """Direction ``(azimuth, elevation)`` (radians) of world points ``(B, 3)`` from the
        neck point in the torso's frame; ``(B, 2)``."""
        p = self.scene.in_torso_frame(p_world)
        return np.stack(
            [np.arctan2(p[:, 1], p[:, 0]), np.arctan2(p[:, 2], np.hypot(p[:, 0], p[:, 1]))], axis=1
        )

    def z(self, direction: F64) -> F64:
        """Directions ``(B, 2)`` as positions in the workspace, ``[0, 1]^2`` inside it."""
        (a0, a1), (e0, e1) = self.workspace.azimuth, self.elevation
        d = np.atleast_2d(direction)
        return np.stack([(d[:, 0] - a0) / (a1 - a0), (d[:, 1] - e0) / (e1 - e0)], axis=1)

    def torso_position(self, z: F64) -> F64:
        """Where a ball at workspace position ``z`` ``(B, 2)`` lies relative to the neck point
        in the torso's frame (on the table's height), ``(B, 3)`` metres."""
        (a0, a1), (e0, e1) = self.workspace.azimuth, self.elevation
        z = np.atleast_2d(z)
        az, el = a0 + z[:, 0] * (a1 - a0), e0 + z[:, 1] * (e1 - e0)
        rho = self.drop / np.tan(-el)
        return np.stack([rho * np.cos(az), rho * np.sin(az), np.full_like(rho, -self.drop)], 1)

    def world_position(self, z: F64) -> F64:
        """World position ``(3,)`` of a ball at workspace position ``z`` ``(2,)`` for the
        torso where it is now."""
        _, r = self.scene.torso_frame()
        return self.scene.neck_point() + r @ self.torso_position(z)[0]

    # ------------------------------------------------------------------ looking
    def saccade(self, rng: np.random.Generator, max_tries: int = 1024) -> F64:
        """Move the neck to a pose drawn uniformly within its limits among those that keep
        the ball in view, and return the neck angles ``(2,)``.

        Rejection sampling: candidates are drawn in batches of 32 and the first one whose
        projection of the ball lies in view is taken (:meth:`Scene.project_at_necks`). A
        ConfigError if none of ``max_tries`` sees it.
        """
        lo, hi = self.scene.neck_range[:, 0], self.scene.neck_range[:, 1]
        p = self.scene.object_position()
        for _ in range(0, max_tries, 32):
            neck = lo + (hi - lo) * rng.random((32, 2))
            seen = np.flatnonzero(self.in_view(self.scene.project_at_necks(neck, p)))
            if seen.size:
                self.scene.set_neck(*neck[seen[0]])
                return neck[seen[0]]
        raise ConfigError(
            f"no neck pose of {max_tries} keeps the ball in view (ball at {p.tolist()}); "
            "place it inside the workspace"
        )

    def look(self, neck: F64, source: str = "projection") -> tuple[F64, F64] | None:
        """Set the neck and read the retina: ``(x, y)`` positions in ``[0, 1]^2``, or None if
        the ball is not in view by ``source``."""
        self.scene.set_neck(*neck)
        uv = self.retinal_pixels(source)
        if uv is None or not self.in_view(uv):
            return None
        return self.retina(uv), self.gaze(neck)

    def place_still(self, z: F64) -> None:
        """Put the base at the origin facing +x and the ball at workspace position ``z``."""
        self.scene.pose(Pose(), forward=False)
        self.scene.set_neck(0.0, 0.7)
        self.scene.pose(Pose(object=tuple(self.world_position(z))))


class FramesCodes:
    """The codes of a view source on the robot's :class:`Frames` (``self.frames``): retina and
    gaze on one ``grid x grid`` code, and a 2-D ``z`` (what
    :class:`~sigmapi.envs.PlacedViewSource` asks besides its methods)."""

    frames: Frames

    @property
    def x_code(self) -> PopulationCode:
        """The code of the retinal position (``grid x grid`` units)."""
        return self.frames.code

    @property
    def y_code(self) -> PopulationCode:
        """The code of the gaze (the retina's grid and width)."""
        return self.frames.code

    @property
    def z_dim(self) -> int:
        """Dimensions of ``z``: the ball's azimuth and elevation (workspace units)."""
        return 2
