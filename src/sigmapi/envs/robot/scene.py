"""The robot in MuJoCo: the model file, poses, the head camera's projection and its pixels.

The model (``robot.xml`` beside this module, written from MuJoCo primitives) is a torso on a
planar base (slide x, slide y, yaw), a neck with pan and tilt joints, a head camera on the tilt
link set off from both joint axes (8 cm ahead of and 6 cm above the tilt axis), a three-joint
arm (shoulder yaw, shoulder pitch, elbow), a table and a red ball on it. A :class:`Scene` holds
one ``MjModel`` and ``MjData`` and places the robot and the ball by their joint positions
(:meth:`Scene.pose`), reads MuJoCo's own camera pose, projects points through it
(:meth:`Scene.project`) and renders the cameras offscreen (:meth:`Scene.render`).

MuJoCo is imported on first use (:func:`mujoco_module`), not with this module: ``import
sigmapi`` and the command line start without it. Headless rendering: that first import sets
``MUJOCO_GL=egl`` unless the variable is already set (MuJoCo reads it once, at import), so a
machine without a display renders through EGL.

Pixel coordinates: ``(u, v)`` with ``u`` along the image columns (left to right) and ``v``
along the rows (top to bottom), both continuous with 0 at the image's left and top edges, so
pixel ``(row i, column j)`` covers ``u`` in ``[j, j + 1)`` and ``v`` in ``[i, i + 1)``.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from importlib import resources
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.errors import ConfigError, install_hint

if TYPE_CHECKING:
    import mujoco

__all__ = [
    "HEAD_SIZE",
    "NECK_HEIGHT",
    "OBJECT_RADIUS",
    "TABLE_HEIGHT",
    "Pose",
    "Scene",
    "blob_centroid",
    "load_model",
    "mujoco_module",
]

HEAD_SIZE = 64
"""Side of the head camera's square image, pixels."""
OBJECT_RADIUS = 0.04
"""Radius of the ball, metres (``robot.xml``)."""
TABLE_HEIGHT = 0.72
"""Height of the table top, metres (``robot.xml``)."""
NECK_HEIGHT = 1.28
"""Height of the neck point above the floor: on the pan axis, at the tilt axis (metres)."""

_ARM = ("shoulder_yaw", "shoulder_pitch", "elbow")


def mujoco_module() -> ModuleType:
    """The ``mujoco`` package, imported on first use (after ``MUJOCO_GL=egl`` unless the
    variable is set); a ConfigError that names the extra to install when it is missing (as
    the baselines' and Dask's extras do)."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    try:
        import mujoco
    except ImportError as exc:
        raise ConfigError(
            f"the simulated robot needs MuJoCo (not installed here: {exc}); {install_hint('robot')}"
        ) from None
    except (RuntimeError, AttributeError, OSError) as exc:  # MUJOCO_GL names no platform here
        raise _bad_gl(exc) from None
    return mujoco


def _bad_gl(exc: BaseException) -> ConfigError:
    gl = os.environ.get("MUJOCO_GL", "")
    return ConfigError(
        f"MUJOCO_GL must name a rendering platform this machine has (egl, glfw or osmesa), "
        f"got {gl[:40]!r} ({type(exc).__name__}: {str(exc)[:120]}); unset it (sigmapi then "
        "uses egl) or install that platform's library"
    )


_GL_OK: list[bool] = []


def check_rendering() -> None:
    """Before any work that renders: a ConfigError naming ``MUJOCO_GL`` if no offscreen
    image can be rendered here (the platform's library missing); checked once a process."""
    if _GL_OK:
        return
    mj = mujoco_module()
    fatal = getattr(mj, "FatalError", RuntimeError)  # no OpenGL context (an empty MUJOCO_GL)
    try:
        with warnings.catch_warnings():  # GLFW without a display warns, then fails: one line
            warnings.simplefilter("ignore")
            model = mj.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
            renderer = mj.Renderer(model, 8, 8)
            try:
                renderer.update_scene(mj.MjData(model))
                renderer.render()
            finally:
                renderer.close()
    except (RuntimeError, AttributeError, OSError, ImportError, fatal) as exc:
        raise _bad_gl(exc) from None
    _GL_OK.append(True)


def load_model() -> mujoco.MjModel:
    """The robot's ``MjModel``, compiled from the package's ``robot.xml``."""
    xml = resources.files("sigmapi.envs.robot").joinpath("robot.xml").read_text("utf-8")
    return mujoco_module().MjModel.from_xml_string(xml)


@dataclass(frozen=True)
class Pose:
    """Where everything is: base ``(x, y, yaw)`` in the world, neck ``(pan, tilt)``, the
    ball's centre ``(x, y, z)`` in the world, arm joints (shoulder yaw, pitch, elbow).
    Angles in radians."""

    base: tuple[float, float, float] = (0.0, 0.0, 0.0)
    neck: tuple[float, float] = (0.0, 0.7)
    object: tuple[float, float, float] = (0.55, 0.0, TABLE_HEIGHT + OBJECT_RADIUS)
    arm: tuple[float, float, float] = (0.0, 0.0, 0.0)


class Scene:
    """One robot model and its state, with the head camera's geometry and pixels.

    Parameters
    ----------
    head_size : int
        Side of the head camera's square image (pixels, at most 240: the offscreen buffer).

    Examples
    --------
    >>> scene = Scene()
    >>> scene.pose(Pose(neck=(0.0, 0.7)))
    >>> u, v = scene.project(scene.object_position())[0]
    >>> bool(0 <= u <= 64 and 0 <= v <= 64)
    True
    """

    def __init__(self, head_size: int = HEAD_SIZE) -> None:
        if not isinstance(head_size, int) or not 8 <= head_size <= 240:
            raise ConfigError(f"head_size must be an int in [8, 240], got {head_size!r}")
        self._mj = mujoco_module()
        self.model = load_model()
        self.data = self._mj.MjData(self.model)
        self.head_size = head_size
        m = self.model
        self._cam = m.camera("head").id
        self._third = m.camera("third").id
        self.fovy = float(np.deg2rad(m.cam_fovy[self._cam]))
        self.focal = 0.5 * head_size / np.tan(0.5 * self.fovy)
        """Focal length of the head camera in pixels (MuJoCo's ``fovy`` is vertical)."""
        self._q = {
            n: int(m.joint(n).qposadr[0])
            for n in ("base_x", "base_y", "base_yaw", "neck_pan", "neck_tilt", *_ARM)
        }
        self._obj_q = int(m.joint("object").qposadr[0])
        self._obj_v = int(m.joint("object").dofadr[0])
        self._act = {m.actuator(i).name: i for i in range(m.nu)}
        self._arm_act = np.array([self._act[n] for n in _ARM])
        self.neck_range = np.array([m.joint("neck_pan").range, m.joint("neck_tilt").range])
        """Joint limits ``[[pan_lo, pan_hi], [tilt_lo, tilt_hi]]`` in radians."""
        self._torso = m.body("torso").id
        self._head = m.body("head").id
        self._shoulder = m.body("shoulder").id
        self._hand_site = m.site("hand").id
        self.arm_range = np.array([m.joint(n).range for n in _ARM])
        """Joint limits of the arm ``(3, 2)``, radians."""

        def geoms(*names: str) -> NDArray[np.bool_]:  # a mask over the geoms
            mask = np.zeros(m.ngeom, dtype=bool)
            mask[[m.geom(n).id for n in names]] = True
            return mask

        self._is_ball, self._is_hand = geoms("object"), geoms("hand")
        self._is_robot = geoms("base", "torso")
        self._is_table = geoms("table_top", "leg_a", "leg_b", "leg_c", "leg_d")
        self._chain = {
            "neck": _offset(m.body_pos[m.body("neck").id], m.body_quat[m.body("neck").id]),
            "head": _offset(m.body_pos[self._head], m.body_quat[self._head]),
            "camera": _offset(m.cam_pos[self._cam], m.cam_quat[self._cam]),
        }
        self._pan_axis = np.array(m.jnt_axis[m.joint("neck_pan").id])
        self._tilt_axis = np.array(m.jnt_axis[m.joint("neck_tilt").id])
        self._renderers: dict[tuple[int, int], Any] = {}
        self.pose(Pose())

    # ------------------------------------------------------------------ state
    def pose(self, pose: Pose, forward: bool = True) -> None:
        """Set every joint to ``pose`` (the actuators' targets too) and run MuJoCo's forward
        pass (kinematics, camera poses and contacts), unless ``forward`` is False."""
        q = self.data.qpos
        for name, value in zip(("base_x", "base_y", "base_yaw"), pose.base, strict=True):
            q[self._q[name]] = value
        for name, value in zip(("neck_pan", "neck_tilt"), pose.neck, strict=True):
            q[self._q[name]] = value
        for name, value in zip(_ARM, pose.arm, strict=True):
            q[self._q[name]] = value
        q[self._obj_q : self._obj_q + 3] = pose.object
        q[self._obj_q + 3 : self._obj_q + 7] = (1.0, 0.0, 0.0, 0.0)
        self.data.qvel[:] = 0.0
        for name, i in self._act.items():
            self.data.ctrl[i] = q[self._q[name]]
        if forward:
            self._mj.mj_forward(self.model, self.data)

    def set_neck(self, pan: float, tilt: float) -> None:
        """Move the neck only and update the camera pose (kinematics, no contacts)."""
        self.data.qpos[self._q["neck_pan"]] = pan
        self.data.qpos[self._q["neck_tilt"]] = tilt
        self.data.ctrl[self._act["neck_pan"]] = pan
        self.data.ctrl[self._act["neck_tilt"]] = tilt
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_camlight(self.model, self.data)

    def arm_joints(self) -> NDArray[np.float64]:
        """The arm's joint positions ``(yaw, pitch, elbow)``, radians."""
        return np.array([self.data.qpos[self._q[n]] for n in _ARM])

    def set_arm_targets(self, q: NDArray[np.float64]) -> None:
        """Set the arm's position actuators' targets ``(yaw, pitch, elbow)`` (radians)."""
        self.data.ctrl[self._arm_act] = q

    def shoulder_position(self) -> NDArray[np.float64]:
        """The shoulder joint's centre in the world ``(3,)``."""
        return np.array(self.data.xpos[self._shoulder])

    def hand_position(self) -> NDArray[np.float64]:
        """The hand's centre in the world ``(3,)``."""
        return np.array(self.data.site_xpos[self._hand_site])

    def joint(self, name: str) -> float:
        """The position of joint ``name`` (radians or metres)."""
        return float(self.data.qpos[self._q[name]])

    def object_position(self) -> NDArray[np.float64]:
        """The ball's centre in the world, ``(3,)``."""
        return np.array(self.data.xpos[self.model.body("object").id])

    def torso_frame(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The torso's pose: origin ``(3,)`` and rotation ``(3, 3)`` (columns: its axes)."""
        return np.array(self.data.xpos[self._torso]), self.data.xmat[self._torso].reshape(3, 3)

    def in_torso_frame(self, p: ArrayLike) -> NDArray[np.float64]:
        """World points ``(B, 3)`` in the torso's frame, relative to the neck point."""
        _, r = self.torso_frame()
        return (np.atleast_2d(np.asarray(p, dtype=np.float64)) - self.neck_point()) @ r

    def neck_point(self) -> NDArray[np.float64]:
        """The neck point in the world ``(3,)``: on the pan axis at the tilt axis's height
        (the origin of the head body, which the pan and tilt joints leave in place)."""
        return np.array(self.data.xpos[self._head])

    # ------------------------------------------------------------------ the head camera
    def camera_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The head camera's position ``(3,)`` and rotation ``(3, 3)`` as MuJoCo computed them
        (columns: the camera's x right, y up, z backwards; it looks along -z)."""
        return np.array(self.data.cam_xpos[self._cam]), self.data.cam_xmat[self._cam].reshape(3, 3)

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """Pixel coordinates ``(B, 2)`` of world points ``(B, 3)`` in the head camera: the
        pinhole of MuJoCo's camera pose and ``fovy``; NaN for points behind the camera.

        ``u = W/2 + f X / (-Z)``, ``v = H/2 - f Y / (-Z)`` with ``(X, Y, Z)`` the point in the
        camera's frame and ``f = (H/2) / tan(fovy/2)``.
        """
        c, r = self.camera_pose()
        return self._pinhole((np.atleast_2d(np.asarray(points, dtype=np.float64)) - c) @ r)

    def project_at_necks(self, neck: ArrayLike, point: ArrayLike) -> NDArray[np.float64]:
        """Pixel coordinates ``(B, 2)`` of one world point ``(3,)`` in the head camera at neck
        angles ``(B, 2)`` (the torso where it is now), without moving the neck.

        The model's kinematic chain (torso -> neck body -> pan -> head body -> tilt -> camera,
        offsets and axes read from the compiled model) in NumPy, walked down from the point:
        into the neck body's frame once, then per candidate back through the pan rotation, the
        head's offset, the tilt rotation and the camera's offset (rotations of vectors, no
        matrices built). ``tests/envs/test_robot.py`` checks it against MuJoCo's camera pose.
        """
        q = np.atleast_2d(np.asarray(neck, dtype=np.float64))
        o, r = self.torso_frame()
        (n_pos, n_rot), (h_pos, h_rot), (c_pos, c_rot) = (
            self._chain[k] for k in ("neck", "head", "camera")
        )
        a = ((np.asarray(point, dtype=np.float64) - o) @ r - n_pos) @ n_rot  # neck body (3,)
        b = (_unrotate(self._pan_axis, q[:, 0], a) - h_pos) @ h_rot  # head body (B, 3)
        pc = (_unrotate(self._tilt_axis, q[:, 1], b) - c_pos) @ c_rot  # camera (B, 3)
        return self._pinhole(pc)

    def _pinhole(self, pc: NDArray[np.float64]) -> NDArray[np.float64]:
        """Pixel coordinates ``(B, 2)`` of points ``(B, 3)`` in the camera's frame."""
        depth = -pc[:, 2:]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = pc[:, :2] * (self.focal / depth)
        uv[:, 1] *= -1.0
        uv += 0.5 * self.head_size
        uv[depth[:, 0] <= 0] = np.nan
        return uv

    def ray(self, uv: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The inverse of :meth:`project`: the camera's position and the unit direction of the
        line of sight through pixel coordinates ``uv`` ``(2,)``, in the world."""
        c, r = self.camera_pose()
        u, v = np.asarray(uv, dtype=np.float64) - 0.5 * self.head_size
        d = r @ np.array([u / self.focal, -v / self.focal, -1.0])
        return c, d / np.linalg.norm(d)

    # ------------------------------------------------------------------ pixels
    def render(
        self, camera: str = "head", size: tuple[int, int] | None = None
    ) -> NDArray[np.uint8]:
        """An RGB image ``(H, W, 3)`` uint8 of camera ``"head"`` (``head_size`` square) or
        ``"third"`` (default 240 x 320), top row first."""
        if camera not in ("head", "third"):
            raise ConfigError(f"camera must be 'head' or 'third', got {camera!r}")
        if size is None:
            size = (self.head_size,) * 2 if camera == "head" else (240, 320)
        r = self._renderers.get(size)
        if r is None:
            check_rendering()  # a platform that cannot render: one line naming MUJOCO_GL
            r = self._renderers[size] = self._mj.Renderer(self.model, *size)
        r.update_scene(self.data, camera=self._cam if camera == "head" else self._third)
        return np.asarray(r.render())

    def close(self) -> None:
        """Free the offscreen renderers (their GL contexts)."""
        for r in self._renderers.values():
            r.close()
        self._renderers.clear()

    # ------------------------------------------------------------------ contacts
    def _touching(self, a: NDArray[np.bool_], b: NDArray[np.bool_]) -> bool:
        """Whether a geom of mask ``a`` is in contact with one of mask ``b``."""
        n = self.data.ncon
        if n == 0:
            return False
        g1, g2 = self.data.contact.geom1[:n], self.data.contact.geom2[:n]
        return bool(np.any((a[g1] & b[g2]) | (a[g2] & b[g1])))

    def robot_touches_table(self) -> bool:
        """Whether the base or torso is in contact with the table (a bump)."""
        return self._touching(self._is_robot, self._is_table)

    def hand_touches_object(self) -> bool:
        """Whether the hand is in contact with the ball."""
        return self._touching(self._is_hand, self._is_ball)


def _offset(pos: ArrayLike, quat: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A child frame's offset in its parent: position ``(3,)`` and rotation ``(3, 3)``."""
    mat = np.zeros(9)
    mujoco_module().mju_quat2Mat(mat, np.asarray(quat, dtype=np.float64))
    return np.array(pos, dtype=np.float64), mat.reshape(3, 3)


def _unrotate(
    axis: NDArray[np.float64], angles: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Vectors ``v`` (``(3,)`` or ``(B, 3)``) rotated about the unit ``axis`` by ``-angles``
    ``(B,)`` (the inverse of a joint's rotation; Rodrigues on vectors), ``(B, 3)``."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(angles)[:, None], np.cos(angles)[:, None]
    along = np.outer(1.0 - c[:, 0], axis) * (v @ axis)[..., None]
    return v * c - (v @ k.T) * s + along  # k.T: v @ k.T is axis x v


def blob_centroid(image: NDArray[np.generic]) -> NDArray[np.float64] | None:
    """Pixel coordinates ``(u, v)`` of the red blob's centroid in an RGB ``image``, or None.

    A pixel belongs to the blob when its red channel exceeds 150 and green and blue stay below
    100 (the ball is drawn in one flat red, ``emission="1"``; the table, floor and robot are
    not red); the centroid is the mean of the pixel centres (``j + 0.5``, ``i + 0.5``).
    """
    img = np.asarray(image)
    mask = (img[..., 0] > 150) & (img[..., 1] < 100) & (img[..., 2] < 100)
    rows, cols = np.nonzero(mask)
    if rows.size == 0:
        return None
    return np.array([cols.mean() + 0.5, rows.mean() + 0.5])
