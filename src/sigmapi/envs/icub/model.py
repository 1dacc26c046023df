"""The iCub's MuJoCo model: converted from ``icub-models``' URDF at first use, then cached.

:func:`load_model` returns the compiled ``MjModel`` of an iCub 2.x (``iCubGazeboV2_7``) with
what the URDF lacks added (:func:`build_spec`):

- the URDF fixes MuJoCo needs: ``package://iCub/`` paths made relative to the package's
  ``share/iCub`` folder, one geom per link (visual and collision name the same mesh), the fixed
  frames kept as bodies until the final compile (a site on ``r_hand_dh_frame``, the palm);
- a fixed root 0.63 m above the floor, turned to face world +x (the iCub's root frame points x
  backward), the legs welded (their joints removed), gravity compensation on every body,
  armature and damping on every joint, position actuators on the torso, neck, both arms and
  eyes;
- eyes after the iCub's published eye kinematics: a tilt link 0.0509 m ahead of the neck-yaw
  axis and 0.08205 m above the neck-roll axis, two eyes 0.034 m either side of the midline,
  each with a pan joint (positive: to the robot's right) and a camera at its rotation centre
  (``fovy`` :data:`FOVY`); version ``(l + r) / 2`` and vergence ``l - r`` are fixed tendons
  with position actuators, as on the robot;
- a green marker on the back of the right hand (:data:`HAND_MARKER`; no contacts), which the
  eyes detect as they detect the ball (:mod:`sigmapi.envs.icub.detect`), as iCub experiments
  mark the hand;
- a table, and a red ball on it (free joint), contacts only between the right forearm and hand,
  the ball and the table; lights without shadows (software EGL spends most of a frame on them).

Geom groups: 0 the world (table, ball, floor), 1 the right hand and forearm, 2 the rest of the
body (hidden in the eye renders: :data:`EYE_GROUPS`, which is what makes an eye frame cheap).

The models are CC BY-SA 4.0: the package is a dependency (``pip install 'sigmapi[robot]'``),
the converted model is written only into the user's cache folder (:func:`cache_dir`, a binary
``.mjb`` keyed by the versions of ``icub-models``, ``mujoco`` and :data:`BUILD`), never into
the repository.
"""

from __future__ import annotations

import importlib.metadata
import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sigmapi.envs.robot.scene import mujoco_module
from sigmapi.errors import ConfigError, install_hint

if TYPE_CHECKING:
    import mujoco

__all__ = [
    "ARM",
    "BALL_RADIUS",
    "BUILD",
    "EYE_GROUPS",
    "FOVY",
    "HAND_MARKER",
    "HOME_ARM",
    "MARKER_RADIUS",
    "NECK",
    "REST_ARM",
    "ROBOT",
    "ROOT_HEIGHT",
    "TABLE_HEIGHT",
    "TORSO",
    "build_spec",
    "cache_dir",
    "icub_models_module",
    "load_model",
]

ROBOT = "iCubGazeboV2_7"
"""The ``icub-models`` robot that is converted."""
BUILD = 6
"""Version of the conversion in this module: part of the cache key (raise it on any change)."""
ROOT_HEIGHT = 0.63
"""Height of the robot's root link above the floor, metres."""
TABLE_HEIGHT = 0.56
"""Height of the table top, metres (below the hand's reach when the forearm is level)."""
BALL_RADIUS = 0.03
"""Radius of the ball, metres."""
FOVY = 50.0
"""Vertical field of view of each eye camera, degrees (the package holds no intrinsics)."""
EYE_GROUPS = (1, 1, 0, 0, 0, 0)
"""Geom groups drawn in the eye renders: the world and the right hand, not the body."""
TORSO = ("torso_pitch", "torso_roll", "torso_yaw")
NECK = ("neck_pitch", "neck_roll", "neck_yaw")
ARM = (
    "r_shoulder_pitch",
    "r_shoulder_roll",
    "r_shoulder_yaw",
    "r_elbow",
    "r_wrist_prosup",
    "r_wrist_pitch",
    "r_wrist_yaw",
)
"""The right arm's joints, shoulder to wrist."""
HOME_ARM = (-0.52, 0.52, 0.0, 0.785, 0.0, 0.0, 0.0)
"""The Gazebo model's home pose of an arm, radians (``ARM``'s order)."""
HAND_MARKER = (0.0, 0.0, -0.03)
"""Where the green marker on the back of the right hand sits in the palm's frame
(``r_hand_dh_frame``), metres: 3 cm behind the palm, where the eyes see it over the table."""
MARKER_RADIUS = 0.015
"""Radius of the hand's marker (a flat green sphere, no contacts), metres."""
HAND_SPAN = (0.039, 0.012)
"""How far the right hand's mesh reaches behind and in front of the palm's contact point (the
palm site) along the palm's normal, metres (the diagram of the end-point error draws it;
``tests/experiments/test_icub_reach3d.py`` measures it on the model)."""
REST_ARM = (0.17, 0.35, 0.0, 0.27, 0.0, 0.0, 0.0)
"""The right arm's rest pose, radians: hanging at the side, out of the eyes' view of the table."""
_LEFT = tuple("l" + name[1:] for name in ARM)
_TILT_AHEAD, _TILT_ABOVE, _EYE_HALF = 0.0509, 0.08205, 0.034
_KP = {
    "torso": 200.0,
    "neck": 60.0,
    "arm": 50.0,
    "wrist": 10.0,
    "eyes_tilt": 20.0,
    "eyes_version": 40.0,
    "eyes_vergence": 20.0,
}
_EYE_RANGE = {
    "eyes_tilt": (-35.0, 15.0),
    "pan": (-50.0, 50.0),
    "eyes_version": (-50.0, 50.0),
    "eyes_vergence": (0.0, 90.0),
}
_REACHING = ("r_forearm", "r_wrist_1", "r_hand")
"""The links whose geoms touch the ball and the table (group 1)."""


def icub_models_module() -> Any:
    """The ``icub_models`` package; a ConfigError naming the extra when it is missing."""
    try:
        import icub_models
    except ImportError as exc:
        raise ConfigError(
            f"the iCub needs its models (not installed here: {exc}); {install_hint('robot')}"
        ) from None
    return icub_models


def cache_dir() -> Path:
    """The folder of converted models: ``$XDG_CACHE_HOME/sigmapi/icub`` (``~/.cache`` when
    the variable is unset)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "sigmapi" / "icub"


def _urdf_text() -> tuple[str, Path]:
    """The robot's URDF, fixed for MuJoCo, and the mesh folder (the package's share/iCub)."""
    path = Path(icub_models_module().get_model_file(ROBOT))
    share = path.parents[2]  # share/iCub/robots/<robot>/model.urdf
    text = path.read_text("utf-8").replace("package://iCub/", "")
    head = text.index(">", text.index("<robot")) + 1
    compiler = (
        '<mujoco><compiler strippath="false" discardvisual="true" fusestatic="false"/></mujoco>'
    )
    return text[:head] + compiler + text[head:], share


def _quat(columns: np.ndarray) -> np.ndarray:
    """The unit quaternion of the rotation matrix whose columns are ``columns`` ``(3, 3)``."""
    q = np.zeros(4)
    mujoco_module().mju_mat2Quat(q, np.ascontiguousarray(columns).reshape(9))
    return q


def build_spec() -> mujoco.MjSpec:
    """The iCub world as an ``MjSpec`` (see the module's account), ready to compile."""
    mj = mujoco_module()
    text, share = _urdf_text()
    spec = mj.MjSpec.from_string(text)
    spec.meshdir = str(share)
    # where the head is at the zero pose (root at the origin): places the eyes
    m0 = spec.compile()
    d0 = mj.MjData(m0)
    mj.mj_kinematics(m0, d0)
    spec.compiler.discardvisual = False
    head_id = m0.body("head").id
    head_pos, head_rot = d0.xpos[head_id].copy(), d0.xmat[head_id].reshape(3, 3).copy()
    yaw_x = d0.xanchor[m0.joint("neck_yaw").id][0]
    roll_z = d0.xanchor[m0.joint("neck_roll").id][2]

    spec.option.timestep = 0.002
    root = spec.body("root_link")
    root.pos = [0.0, 0.0, ROOT_HEIGHT]
    root.quat = [0.0, 0.0, 0.0, 1.0]  # 180 degrees about z: the robot faces world +x
    for joint in list(spec.joints):
        if "hip" in joint.name or "knee" in joint.name or "ankle" in joint.name:
            spec.delete(joint)
    for body in spec.bodies:
        body.gravcomp = 1.0
    for joint in spec.joints:
        joint.armature = 0.01
        joint.damping = np.maximum(np.atleast_1d(joint.damping), 1.0)
    reaching = set(_REACHING)
    for body in spec.bodies:
        for geom in body.geoms:
            if body.name in reaching:
                geom.group, geom.contype, geom.conaffinity = 1, 2, 0
                geom.rgba = [0.85, 0.75, 0.6, 1.0]
            else:
                geom.group, geom.contype, geom.conaffinity = 2, 0, 0
    hand = spec.body("r_hand_dh_frame")
    hand.add_site(name="palm", size=[0.005, 0, 0])
    spec.add_material(name="marker", rgba=[0, 1, 0, 1], emission=1.0)
    hand.add_geom(
        name="hand_marker",
        type=mj.mjtGeom.mjGEOM_SPHERE,
        size=[MARKER_RADIUS, 0, 0],
        pos=list(HAND_MARKER),
        material="marker",
        group=1,
        contype=0,
        conaffinity=0,
    )
    _add_eyes(spec, head_pos, head_rot, yaw_x, roll_z)
    _add_world(spec)
    _add_actuators(spec)
    spec.compiler.fusestatic = True
    return spec


def _add_eyes(
    spec: Any, head_pos: np.ndarray, head_rot: np.ndarray, yaw_x: float, roll_z: float
) -> None:
    """The eye-tilt link on the head, a panning eye either side with a camera at its centre."""
    # the root frame points x backward, y right, z up: "ahead" is -x
    tilt_world = np.array([yaw_x - _TILT_AHEAD, 0.0, roll_z + _TILT_ABOVE])
    forward_left_up = np.array([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]).T
    tilt = spec.body("head").add_body(
        name="eyes_tilt_link",
        pos=head_rot.T @ (tilt_world - head_pos),
        quat=_quat(head_rot.T @ forward_left_up),
        mass=0.02,
        inertia=[1e-5, 1e-5, 1e-5],
    )
    # in the tilt link: x forward, y left, z up; positive tilt looks up, positive pan right
    tilt.add_joint(
        name="eyes_tilt",
        axis=[0, -1, 0],
        range=np.radians(_EYE_RANGE["eyes_tilt"]),
        damping=[0.05, 0, 0],
        armature=0.01,
    )
    cam_quat = _quat(np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]]).T)
    for side, y in (("l", _EYE_HALF), ("r", -_EYE_HALF)):
        eye = tilt.add_body(
            name=f"{side}_eye", pos=[0.0, y, 0.0], mass=0.01, inertia=[1e-6, 1e-6, 1e-6]
        )
        eye.add_joint(
            name=f"{side}_eye_pan",
            axis=[0, 0, -1],
            range=np.radians(_EYE_RANGE["pan"]),
            damping=[0.05, 0, 0],
            armature=0.01,
        )
        eye.add_geom(
            type=mujoco_module().mjtGeom.mjGEOM_SPHERE,
            size=[0.012, 0, 0],
            group=2,
            contype=0,
            conaffinity=0,
            rgba=[0.95, 0.95, 0.95, 1],
        )
        eye.add_camera(name=f"{side}_eye", quat=cam_quat, fovy=FOVY)
        eye.gravcomp = 1.0
    tilt.gravcomp = 1.0
    for name, coef in (("eyes_version", (0.5, 0.5)), ("eyes_vergence", (1.0, -1.0))):
        tendon = spec.add_tendon(name=name)
        tendon.wrap_joint("l_eye_pan", coef[0])
        tendon.wrap_joint("r_eye_pan", coef[1])


def _add_world(spec: Any) -> None:
    """Floor, light, table, the red ball and a third-person camera."""
    geom = mujoco_module().mjtGeom
    world = spec.worldbody
    world.add_light(
        pos=[0.6, 0.3, 2.5], dir=[-0.2, -0.1, -1.0], diffuse=[0.8, 0.8, 0.8], castshadow=False
    )
    world.add_light(
        pos=[1.5, -1.0, 2.0], dir=[-0.6, 0.4, -0.6], diffuse=[0.4, 0.4, 0.4], castshadow=False
    )
    world.add_geom(
        name="floor",
        type=geom.mjGEOM_PLANE,
        size=[3, 3, 0.1],
        rgba=[0.75, 0.78, 0.8, 1],
        group=0,
        contype=0,
        conaffinity=0,
    )
    top = 0.02
    world.add_geom(
        name="table",
        type=geom.mjGEOM_BOX,
        size=[0.25, 0.4, top / 2],
        pos=[0.34, -0.1, TABLE_HEIGHT - top / 2],
        rgba=[0.55, 0.42, 0.3, 1],
        group=0,
        contype=1,
        conaffinity=3,
    )
    spec.add_material(name="ball", rgba=[1, 0, 0, 1], emission=1.0)
    ball = world.add_body(name="ball", pos=[0.3, -0.1, TABLE_HEIGHT + BALL_RADIUS])
    ball.add_freejoint(name="ball")
    ball.add_geom(
        name="ball",
        type=geom.mjGEOM_SPHERE,
        size=[BALL_RADIUS, 0, 0],
        material="ball",
        mass=0.05,
        group=0,
        contype=1,
        conaffinity=3,
        condim=3,
    )
    world.add_camera(
        name="third", pos=[1.45, -1.05, 1.45], xyaxes=[0.6, 0.8, 0, -0.35, 0.26, 0.9], fovy=45
    )


def _add_actuators(spec: Any) -> None:
    """Position actuators (kv = kp / 10) on the torso, neck, arms and eyes."""
    groups = [
        (TORSO, "torso"),
        (NECK, "neck"),
        (ARM[:4], "arm"),
        (ARM[4:], "wrist"),
        (_LEFT[:4], "arm"),
        (_LEFT[4:], "wrist"),
    ]
    trn = mujoco_module().mjtTrn
    for names, kind in groups:
        for name in names:
            act = spec.add_actuator(name=name, target=name, trntype=trn.mjTRN_JOINT)
            act.set_to_position(kp=_KP[kind], kv=0.1 * _KP[kind])
            lo, hi = spec.joint(name).range
            act.ctrlrange, act.ctrllimited = [lo, hi], 1
    for name, kind in (
        ("eyes_tilt", trn.mjTRN_JOINT),
        ("eyes_version", trn.mjTRN_TENDON),
        ("eyes_vergence", trn.mjTRN_TENDON),
    ):
        act = spec.add_actuator(name=name, target=name, trntype=kind)
        act.set_to_position(kp=_KP[name], kv=0.1 * _KP[name])
        act.ctrlrange, act.ctrllimited = np.radians(_EYE_RANGE[name]), 1


def _key() -> str:
    icub = importlib.metadata.version("icub-models")
    return f"{ROBOT}-icub-models-{icub}-mujoco-{mujoco_module().__version__}-build{BUILD}"


def load_model(cache: bool = True) -> mujoco.MjModel:
    """The iCub world's ``MjModel``: read from :func:`cache_dir` when a conversion of the same
    versions is there, else built (:func:`build_spec`, a few seconds) and saved there
    atomically (``cache=False``: built, not saved)."""
    mj = mujoco_module()
    path = cache_dir() / f"{_key()}.mjb"
    if cache and path.is_file():
        try:
            return mj.MjModel.from_binary_path(str(path))
        except Exception:  # a damaged cache file: rebuild it
            pass
    model = build_spec().compile()
    if cache:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        os.close(fd)
        try:
            mj.mj_saveModel(model, tmp, None)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return model
