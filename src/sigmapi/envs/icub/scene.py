"""One iCub world in MuJoCo: its poses, the eyes' projection and pixels, frames and contacts.

An :class:`ICubScene` holds the model (:func:`~sigmapi.envs.icub.model.load_model`) and one
``MjData``. Poses are set by joint positions (:meth:`ICubScene.set_gaze`,
:meth:`ICubScene.set_arm`, :meth:`ICubScene.set_ball`) followed by ``mj_kinematics``; the
physics (:meth:`ICubScene.step`) drives the position actuators.

The gaze is six angles, radians, in the order of :data:`GAZE`: eye tilt (positive up), version
and vergence (``(l + r) / 2`` and ``l - r`` of the eyes' pans, positive pan to the robot's
right), neck pitch (positive up), roll and yaw (positive to the robot's left).

Frames (all measured on the model, never assumed):

- **retina**: pixel coordinates ``(u, v)`` of a point in an eye's image, as
  :mod:`sigmapi.envs.robot.scene` defines them (``u`` along columns, ``v`` along rows, 0 at the
  left and top edges), by the pinhole of MuJoCo's camera pose and ``fovy``
  (:meth:`ICubScene.project`) or from the rendered pixels (:meth:`ICubScene.see`);
- **head-centred**: a point's direction from the right eye's centre (on both eye axes, so it
  moves with neither) in the head's frame: x forward, y left, z up with the eyes at zero;
- **torso-centred**: a point's direction in the chest's frame (x forward, y left, z up), from
  the point between the eyes when the neck is at zero (fixed in the chest).

A direction is given as ``(azimuth, elevation)`` in radians (:func:`direction_angles`) in the
coordinates of the gimbals that point the eyes and the head (tilt or pitch outside, pan or yaw
inside: Helmholtz coordinates): the elevation ``atan2(z, x)`` is the rotation about the left-right
axis, the azimuth ``asin(y / |v|)`` the sideways angle out of the x-z plane. They are the tilt
and pan that would turn an eye (or the pitch and yaw that would turn the head) to the point, and
they stay regular over the table below the chest, where longitude and latitude (``atan2(y, x)``
about the vertical) crowd together near the downward pole: a box of longitude and latitude there
is a fan on the table.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.envs.icub.detect import detect
from sigmapi.envs.icub.model import (
    ARM,
    BALL_RADIUS,
    EYE_GROUPS,
    HOME_ARM,
    NECK,
    REST_ARM,
    TABLE_HEIGHT,
    load_model,
)
from sigmapi.envs.robot.scene import check_rendering, mujoco_module
from sigmapi.errors import ConfigError, SigmapiError

__all__ = [
    "EYE_SIZE",
    "GAZE",
    "ICubScene",
    "TruthLeak",
    "direction_angles",
    "direction_vectors",
]


class TruthLeak(SigmapiError, RuntimeError):
    """The simulator's truth (a body's, site's or camera's place in the world) was read
    outside :meth:`ICubScene.truth` on a sealed scene (:meth:`ICubScene.seal`)."""


_F = TypeVar("_F", bound=Callable[..., Any])


def _truth(method: _F) -> _F:
    """Mark ``method`` as a reader of the simulator's truth: on a sealed scene it raises
    :class:`TruthLeak` outside :meth:`ICubScene.truth`."""

    @functools.wraps(method)
    def guarded(self: ICubScene, *args: Any, **kwargs: Any) -> Any:
        if self._sealed and not self._truth_depth:
            raise TruthLeak(
                f"ICubScene.{method.__name__} reads the simulator's truth outside "
                "scene.truth() (only scoring and labelled references may)"
            )
        return method(self, *args, **kwargs)

    return guarded  # type: ignore[return-value]


EYE_SIZE = 64
"""Side of an eye's square image, pixels."""
GAZE = ("eyes_tilt", "eyes_version", "eyes_vergence", *NECK)
"""The six gaze angles, in order."""

Array = NDArray[np.float64]


def direction_angles(v: ArrayLike) -> Array:
    """``(azimuth, elevation)`` radians of vectors ``v`` ``(..., 3)`` (x forward, y left, z
    up): ``(..., 2)``, ``asin(y / |v|)`` and ``atan2(z, x)`` (the module's account)."""
    a = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(a, axis=-1)
    return np.stack(
        [np.arcsin(np.clip(a[..., 1] / n, -1.0, 1.0)), np.arctan2(a[..., 2], a[..., 0])], axis=-1
    )


def direction_vectors(d: ArrayLike) -> Array:
    """Unit vectors ``(..., 3)`` of directions ``(azimuth, elevation)`` ``(..., 2)`` (the inverse
    of :func:`direction_angles`)."""
    a = np.asarray(d, dtype=np.float64)
    az, el = a[..., 0], a[..., 1]
    return np.stack([np.cos(az) * np.cos(el), np.sin(az), np.cos(az) * np.sin(el)], axis=-1)


class ICubScene:
    """The iCub world's model and state, with the eyes' geometry and pixels.

    Parameters
    ----------
    eye_size : int
        Side of each eye's square image (pixels, 8 to 240).

    Examples
    --------
    >>> scene = ICubScene()
    >>> scene.set_ball((0.3, -0.1))
    >>> scene.look_at(scene.ball_position())
    >>> np.round(scene.project(scene.ball_position(), "r_eye")[0], 1).tolist()
    [32.0, 32.0]
    """

    def __init__(self, eye_size: int = EYE_SIZE) -> None:
        if not isinstance(eye_size, int) or not 8 <= eye_size <= 240:
            raise ConfigError(f"eye_size must be an int in [8, 240], got {eye_size!r}")
        self._mj = mujoco_module()
        self.model = m = load_model()
        self.data = self._mj.MjData(m)
        self.eye_size = eye_size
        self.focal = 0.5 * eye_size / np.tan(np.radians(m.cam_fovy[m.camera("r_eye").id]) / 2)
        self._qadr = {m.joint(i).name: int(m.jnt_qposadr[i]) for i in range(m.njnt)}
        self._act = {m.actuator(i).name: i for i in range(m.nu)}
        self._arm_q = np.array([self._qadr[n] for n in ARM])
        self._ball_q = self._qadr["ball"]
        self._ball_body = m.body("ball").id
        self._ball_geom = m.geom("ball").id
        self._table_geom = m.geom("table").id
        self._hand = np.asarray(m.geom_bodyid == m.body("r_hand").id)
        self._palm = m.site("palm").id
        self._marker = m.geom("hand_marker").id
        self._chest = m.body("chest").id
        self._head = m.body("head").id
        tilt = m.body("eyes_tilt_link").id
        q = np.zeros(9)
        self._mj.mju_quat2Mat(q, m.body_quat[tilt])
        self._head_fix = q.reshape(3, 3)  # the tilt link's frame in the head's at tilt 0
        self.arm_range = np.array([m.jnt_range[m.joint(n).id] for n in ARM])
        self._renderers: dict[tuple[int, int], Any] = {}
        self._sealed, self._truth_depth = False, 0
        self._eye_opt = self._mj.MjvOption()
        self._eye_opt.geomgroup[:] = np.array(EYE_GROUPS, dtype=np.uint8)
        self.reset()
        # the torso-centred origin: between the eyes with the neck at zero, in the chest frame
        mid = 0.5 * (self.data.xpos[m.body("l_eye").id] + self.data.xpos[m.body("r_eye").id])
        c, r = self.torso_frame()
        self._torso_origin = (mid - c) @ r

    # ------------------------------------------------------------------ poses
    def reset(self) -> None:
        """Home pose: torso, neck and eyes at zero, the left arm at :data:`HOME_ARM`, the
        right at :data:`REST_ARM`, the ball at rest on the table; actuator targets where the
        joints are."""
        self._mj.mj_resetData(self.model, self.data)
        for side, pose in (("r", REST_ARM), ("l", HOME_ARM)):
            for name, q in zip(ARM, pose, strict=True):
                self.data.qpos[self._qadr[side + name[1:]]] = q
        self.set_ball((0.3, -0.1))
        self.hold()

    def _forward(self) -> None:
        """Positions of bodies, sites and cameras from the joints (no dynamics)."""
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_camlight(self.model, self.data)

    def hold(self) -> None:
        """Actuator targets set to where the joints are now (the pose is held)."""
        self._forward()
        self._mj.mj_transmission(self.model, self.data)
        self.data.ctrl[:] = self.data.actuator_length

    def set_gaze(self, gaze: ArrayLike, forward: bool = True) -> None:
        """Put the eyes and neck at ``gaze`` (:data:`GAZE`, radians) and hold them there."""
        g = np.asarray(gaze, dtype=np.float64)
        tilt, version, vergence = g[:3]
        qp = self.data.qpos
        qp[self._qadr["eyes_tilt"]] = tilt
        qp[self._qadr["l_eye_pan"]] = version + 0.5 * vergence
        qp[self._qadr["r_eye_pan"]] = version - 0.5 * vergence
        for name, a in zip(NECK, g[3:], strict=True):
            qp[self._qadr[name]] = a
        for name, a in zip(GAZE, g, strict=True):
            self.data.ctrl[self._act[name]] = a
        if forward:
            self._forward()

    def gaze(self) -> Array:
        """The six gaze angles now (:data:`GAZE`), measured from the joints."""
        qp = self.data.qpos
        left, right = qp[self._qadr["l_eye_pan"]], qp[self._qadr["r_eye_pan"]]
        neck = [qp[self._qadr[n]] for n in NECK]
        return np.array([qp[self._qadr["eyes_tilt"]], 0.5 * (left + right), left - right, *neck])

    def set_arm(self, q: ArrayLike, forward: bool = True) -> None:
        """Put the right arm at joint angles ``q`` (:data:`ARM`) and hold it there."""
        q = np.clip(np.asarray(q, dtype=np.float64), *self.arm_range.T)
        self.data.qpos[self._arm_q] = q
        self.data.qvel[:] = 0.0
        self.set_arm_targets(q)
        if forward:
            self._forward()

    def set_arm_targets(self, q: ArrayLike) -> None:
        """The right arm's actuator targets (the physics moves it there)."""
        for name, a in zip(ARM, np.asarray(q, dtype=np.float64), strict=True):
            self.data.ctrl[self._act[name]] = a

    def arm(self) -> Array:
        """The right arm's joint angles now (:data:`ARM`)."""
        return np.array(self.data.qpos[self._arm_q])

    def set_ball(self, xy: ArrayLike, forward: bool = True) -> None:
        """The ball at rest on the table at world ``(x, y)``."""
        x, y = np.asarray(xy, dtype=np.float64)
        a = self._ball_q
        self.data.qpos[a : a + 7] = [x, y, TABLE_HEIGHT + BALL_RADIUS, 1.0, 0.0, 0.0, 0.0]
        self.data.qvel[self.model.jnt_dofadr[self.model.joint("ball").id] :][:6] = 0.0
        if forward:
            self._forward()

    @_truth
    def ball_position(self) -> Array:
        """The ball's centre in the world, ``(3,)``."""
        return np.array(self.data.xpos[self._ball_body])

    @_truth
    def palm_position(self) -> Array:
        """The palm's position (a site on ``r_hand_dh_frame``) in the world, ``(3,)``."""
        return np.array(self.data.site_xpos[self._palm])

    @_truth
    def marker_position(self) -> Array:
        """The centre of the hand's marker in the world, ``(3,)``."""
        return np.array(self.data.geom_xpos[self._marker])

    def step(self, seconds: float) -> None:
        """Run the physics for ``seconds`` (the actuators follow their targets)."""
        for _ in range(max(1, round(seconds / self.model.opt.timestep))):
            self._mj.mj_step(self.model, self.data)

    # ------------------------------------------------------------------ frames
    @_truth
    def torso_frame(self) -> tuple[Array, Array]:
        """The chest's position ``(3,)`` and rotation ``(3, 3)`` with columns forward, left,
        up (the URDF's chest frame has x left, y up, z forward: re-ordered here)."""
        c = np.array(self.data.xpos[self._chest])
        r = self.data.xmat[self._chest].reshape(3, 3)
        return c, np.stack([r[:, 2], r[:, 0], r[:, 1]], axis=1)

    @_truth
    def head_frame(self) -> tuple[Array, Array]:
        """The right eye's centre ``(3,)`` and the head's rotation ``(3, 3)`` (columns forward,
        left, up with the eyes at zero)."""
        r = self.data.xmat[self._head].reshape(3, 3) @ self._head_fix
        return np.array(self.data.xpos[self.model.body("r_eye").id]), r

    @_truth
    def torso_direction(self, p: ArrayLike) -> Array:
        """Torso-centred ``(azimuth, elevation)`` of world points ``p`` ``(..., 3)``."""
        c, r = self.torso_frame()
        return direction_angles((np.asarray(p) - c) @ r - self._torso_origin)

    @_truth
    def head_direction(self, p: ArrayLike) -> Array:
        """Head-centred ``(azimuth, elevation)`` of world points ``p`` ``(..., 3)``."""
        c, r = self.head_frame()
        return direction_angles((np.asarray(p) - c) @ r)

    @_truth
    def table_point(self, direction: ArrayLike) -> Array:
        """World points ``(B, 3)`` at the ball's centre height seen from the torso-centred
        origin in torso-centred directions ``(B, 2)`` (azimuth, elevation < 0)."""
        d = np.atleast_2d(np.asarray(direction, dtype=np.float64))
        c, r = self.torso_frame()
        origin = c + r @ self._torso_origin
        ray = direction_vectors(d) @ r.T
        t = (TABLE_HEIGHT + BALL_RADIUS - origin[2]) / ray[:, 2]
        return origin + t[:, None] * ray

    @_truth
    def look_at(self, p: ArrayLike, vergence: float = 0.0) -> None:
        """Turn the eyes (not the neck) so that the right eye fixates world point ``p`` (the
        tilt is the outer gimbal: tilt in the head's x-z plane, then the pan out of it)."""
        c, r = self.head_frame()
        x, y, z = (np.asarray(p, dtype=np.float64) - c) @ r
        tilt, pan = np.arctan2(z, x), -np.arctan2(y, np.hypot(x, z))
        self.set_gaze([tilt, pan + 0.5 * vergence, vergence, *self.gaze()[3:]])

    # ------------------------------------------------------------------ the eyes
    @_truth
    def camera_pose(self, eye: str) -> tuple[Array, Array]:
        """Camera ``eye`` (``"l_eye"`` or ``"r_eye"``): position and rotation (columns: right,
        up, backward; it looks along -z) as MuJoCo computed them."""
        cam = self.model.camera(eye).id
        return np.array(self.data.cam_xpos[cam]), self.data.cam_xmat[cam].reshape(3, 3)

    @_truth
    def project(self, points: ArrayLike, eye: str = "r_eye") -> Array:
        """Pixel coordinates ``(B, 2)`` of world points ``(B, 3)`` in ``eye`` (the pinhole of
        the camera's pose and ``fovy``; NaN behind the camera)."""
        c, r = self.camera_pose(eye)
        pc = (np.atleast_2d(np.asarray(points, dtype=np.float64)) - c) @ r
        depth = -pc[:, 2:]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = pc[:, :2] * (self.focal / depth)
        uv[:, 1] *= -1.0
        uv += 0.5 * self.eye_size
        uv[depth[:, 0] <= 0] = np.nan
        return uv

    def render(self, camera: str, size: tuple[int, int] | None = None) -> NDArray[np.uint8]:
        """An RGB image of ``camera``: an eye (``"l_eye"``, ``"r_eye"``; ``eye_size`` square,
        the body hidden but the right forearm and hand) or ``"third"`` (240 x 320)."""
        eye = camera in ("l_eye", "r_eye")
        if not eye and camera != "third":
            raise ConfigError(f"camera must be 'l_eye', 'r_eye' or 'third', got {camera!r}")
        if size is None:
            size = (self.eye_size,) * 2 if eye else (240, 320)
        r = self._renderers.get(size)
        if r is None:
            check_rendering()  # a platform that cannot render: one line naming MUJOCO_GL
            r = self._renderers[size] = self._mj.Renderer(self.model, *size)
        r.update_scene(self.data, camera=camera, scene_option=self._eye_opt if eye else None)
        return np.asarray(r.render())

    def see(self, target: str, eye: str = "r_eye") -> Array | None:
        """Where ``eye`` sees ``target`` (``"ball"`` or ``"hand"``, its marker) in its rendered
        frame, ``(u, v)`` pixels, or None when the detection is not valid
        (:func:`~sigmapi.envs.icub.detect.detect`: only the pixels are read)."""
        return detect(self.render(eye), target)

    def seal(self) -> None:
        """From now on the truth's readers raise :class:`TruthLeak` outside :meth:`truth`."""
        self._sealed = True

    @contextmanager
    def truth(self) -> Iterator[None]:
        """Within this block the simulator's truth may be read (scoring, labelled references
        and where the experimenter puts the ball)."""
        self._truth_depth += 1
        try:
            yield
        finally:
            self._truth_depth -= 1

    def close(self) -> None:
        """Free the offscreen renderers."""
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()

    # ------------------------------------------------------------------ contacts
    def hand_on_table(self, depth: float = 0.01) -> bool:
        """Touch, sensed with the arm where it is set: whether the right hand touches the
        table, lightly (no contact of the arm with the table deeper than ``depth`` metres,
        MuJoCo's contact distance: how hard a touch sensor would feel it pressed); the
        contacts are found again from the pose (``mj_collision``)."""
        self._mj.mj_collision(self.model, self.data)
        n = self.data.ncon
        g1, g2 = self.data.contact.geom1[:n], self.data.contact.geom2[:n]
        t = self._table_geom
        on = (g1 == t) | (g2 == t)
        if not np.any(on) or np.any(self.data.contact.dist[:n][on] < -depth):
            return False
        h = self._hand
        return bool(np.any(on & (h[g1] | h[g2])))

    def _palm_frame(self) -> tuple[Array, Array]:
        """The palm's contact point and its frame's axes (columns; the third the palm's
        normal): the hand's own frame, in which its taxels report where a touch is."""
        return self.data.site_xpos[self._palm], self.data.site_xmat[self._palm].reshape(3, 3)

    def palm_side(self, points: ArrayLike, side: float) -> NDArray[np.bool_]:
        """Whether contact points ``(k, 3)`` lie on the palm's side of the hand (at least
        ``side`` metres along the palm's normal from its contact point): where on the hand
        they are, in the hand's own frame, as a tactile skin's taxels report it."""
        c, r = self._palm_frame()
        return np.asarray((np.asarray(points) - c) @ r[:, 2] >= side)

    def palm_patch(self, points: ArrayLike, radius: float) -> NDArray[np.bool_]:
        """Whether contact points ``(k, 3)`` lie within ``radius`` metres of the palm's contact
        point across the palm (their distance from its normal through that point): the
        taxels of the palm's middle, as against the fingers'."""
        c, r = self._palm_frame()
        d = np.asarray(points) - c
        across = d - np.outer(d @ r[:, 2], r[:, 2])
        return np.asarray(np.linalg.norm(across, axis=1) <= radius)

    def skin(self, side: float, patch: float | None = None) -> tuple[bool, bool]:
        """The arm's touch sensors, the arm where it is set: (the palm's skin touches the
        ball, any other part of the arm touches anything); the palm's skin is the hand's
        contacts with the ball on the palm's side (:meth:`palm_side`) and, with ``patch``,
        within ``patch`` metres of the palm's middle (:meth:`palm_patch`); the contacts are
        found again from the pose (``mj_collision``)."""
        g1, g2, on_arm = self._arm_contacts()
        b, n = self._ball_geom, len(g1)
        on_ball = ((g1 == b) & self._hand[g2]) | ((g2 == b) & self._hand[g1])
        points = self.data.contact.pos[:n]
        palm = on_ball & self.palm_side(points, side)
        if patch is not None:
            palm &= self.palm_patch(points, patch)
        other = on_arm & ~palm
        return bool(np.any(palm)), bool(np.any(other))

    def arm_touches(self) -> bool:
        """Touch, sensed with the arm where it is set: any contact of the hand or forearm
        (with the ball, the table or the body); the contacts are found again from the pose
        (``mj_collision``)."""
        return bool(np.any(self._arm_contacts()[2]))

    def _arm_contacts(self) -> tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.bool_]]:
        """The contacts found again from the pose (``mj_collision``): each one's two geoms and
        whether one of them is the arm's (the hand or the forearm)."""
        self._mj.mj_collision(self.model, self.data)
        n = self.data.ncon
        g1, g2 = self.data.contact.geom1[:n], self.data.contact.geom2[:n]
        arm = self.model.geom_contype == 2
        return g1, g2, arm[g1] | arm[g2]

    def hand_touches_ball(self) -> bool:
        """Whether the right hand (the palm's link, not the forearm) touches the ball."""
        n = self.data.ncon
        g1, g2 = self.data.contact.geom1[:n], self.data.contact.geom2[:n]
        b, h = self._ball_geom, self._hand
        return bool(np.any((h[g1] & (g2 == b)) | (h[g2] & (g1 == b))))
