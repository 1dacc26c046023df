"""The scripted reach: from where the head sees the ball to the hand touching it, in the physics.

The target is what the robot perceives, never the simulator's ball position: the line of
sight through the ball's retinal position (:meth:`Scene.ray`, the head camera's pose for the
current neck angles) meets the horizontal plane of a ball resting on the table. The arm
(shoulder yaw, shoulder pitch, elbow; two links of :data:`LINK` metres) reaches it by inverse
kinematics, elbow up, through four waypoints driven by its position actuators while MuJoCo
integrates the dynamics: fold the forearm back, lift it above the table, go above the target,
then come down onto it. The reach succeeds when the hand geom touches the ball geom (a
contact in MuJoCo's collision detection) before the script ends.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi.envs.robot.scene import OBJECT_RADIUS, TABLE_HEIGHT, Scene, mujoco_module

__all__ = ["LINK", "arm_ik", "perceived_target", "scripted_reach"]

LINK = 0.35
"""Length of the upper arm and of the forearm, metres (``robot.xml``)."""

_FOLD = np.deg2rad([0.0, -150.0])  # pitch, elbow: forearm folded back, hand behind the shoulder
_LIFT = np.deg2rad([120.0, -150.0])  # upper arm raised forward, hand above the table's edge
_ABOVE = 0.12  # metres above the target for the approach
_PHASE_S = 0.3  # seconds per waypoint
_TICK = 5  # physics steps per update of the arm's targets (and per look for a touch)


def perceived_target(scene: Scene, uv: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Where a ball seen at pixel coordinates ``uv`` lies in the world ``(3,)``: the line of
    sight meets the plane ``z = TABLE_HEIGHT + OBJECT_RADIUS``; None if it points upwards."""
    c, d = scene.ray(uv)
    if d[2] >= -1e-9:
        return None
    t = (TABLE_HEIGHT + OBJECT_RADIUS - c[2]) / d[2]
    return c + t * d


def arm_ik(scene: Scene, target: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Joint angles ``(yaw, pitch, elbow)`` (radians) that put the hand's centre at the world
    point ``target``, elbow up; None when it is out of reach.

    In the torso's frame, relative to the shoulder: ``yaw = atan2(dy, dx)``; in the arm's
    vertical plane the two links of length ``L`` reach horizontal distance ``r`` and height
    ``h`` with ``cos(elbow) = (r^2 + h^2 - 2 L^2) / (2 L^2)`` (elbow < 0: folded upwards) and
    ``pitch = atan2(r, -h) - atan2(L sin(elbow), L + L cos(elbow))``, both measured from the
    arm hanging straight down.
    """
    _, rot = scene.torso_frame()
    p = (np.asarray(target, dtype=np.float64) - scene.shoulder_position()) @ rot
    yaw = float(np.arctan2(p[1], p[0]))
    r, h = float(np.hypot(p[0], p[1])), float(p[2])
    c = (r * r + h * h - 2.0 * LINK * LINK) / (2.0 * LINK * LINK)
    if not -1.0 <= c <= 1.0:
        return None
    elbow = -float(np.arccos(c))
    pitch = float(np.arctan2(r, -h) - np.arctan2(LINK * np.sin(elbow), LINK + LINK * np.cos(elbow)))
    q = np.array([yaw, pitch, elbow])
    lo, hi = scene.arm_range[:, 0], scene.arm_range[:, 1]
    return q if np.all(q >= lo) and np.all(q <= hi) else None


def scripted_reach(scene: Scene, target: NDArray[np.float64] | None) -> bool:
    """Reach for the world point ``target`` in the physics; True if the hand touched the ball.

    The arm's actuators follow four waypoints (:data:`_PHASE_S` seconds each, the targets
    interpolated linearly in joint space, updated every :data:`_TICK` physics steps) while
    ``mj_step`` integrates everything: base and neck hold their poses, the ball lies free on
    the table and can be pushed.
    """
    if target is None:
        return False
    above = arm_ik(scene, target + np.array([0.0, 0.0, _ABOVE]))
    down = arm_ik(scene, target)
    if above is None or down is None:
        return False
    mujoco = mujoco_module()
    m, d = scene.model, scene.data
    start = scene.arm_joints()
    yaw0 = start[0]
    waypoints = [np.array([yaw0, *_FOLD]), np.array([above[0], *_LIFT]), above, down]
    ticks = max(1, round(_PHASE_S / (_TICK * m.opt.timestep)))
    mujoco.mj_forward(m, d)
    q = start
    for goal in waypoints:
        for i in range(1, ticks + 1):
            scene.set_arm_targets(q + (goal - q) * (i / ticks))
            mujoco.mj_step(m, d, _TICK)
            if scene.hand_touches_object():
                return True
        q = goal
    mujoco.mj_step(m, d, _TICK * ticks)  # hold the last waypoint: the hand settles on the ball
    return scene.hand_touches_object()
