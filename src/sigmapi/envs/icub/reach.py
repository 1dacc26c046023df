"""Reaching with the iCub's right arm: the scripted inverse kinematics and the physical reach.

- :func:`arm_ik`: position-only damped least squares on the palm (the upper bound the learned
  reaches are compared with); kinematics only, the world is left as it was.
- :func:`physical_reach`: the actuators move the arm to a posture in the physics, approaching
  from above (first the posture with the elbow bent by :data:`LIFT` more, which raises the
  hand, then the posture), and report whether the hand touched the ball. A reach starts with
  the arm at :data:`~sigmapi.envs.icub.model.HOME_ARM` (the hand above the table; the rest
  pose the eyes see the table from holds it below the table's edge, and the physics would
  drag the forearm along the edge's underside).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi.envs.icub.model import ARM, BALL_RADIUS, HOME_ARM
from sigmapi.envs.icub.scene import ICubScene

__all__ = ["AIM", "LIFT", "ReachOutcome", "arm_ik", "physical_reach"]

Array = NDArray[np.float64]

AIM = 0.6 * BALL_RADIUS
"""Height above the ball's centre that a reach aims the palm at, metres."""
LIFT = 0.45
"""Extra elbow flexion of the approach posture, radians (raises the hand above the target)."""
_ELBOW = ARM.index("r_elbow")


def arm_ik(
    scene: ICubScene,
    target: ArrayLike,
    q0: ArrayLike | None = None,
    *,
    damping: float = 0.03,
    max_step: float = 0.2,
    iterations: int = 300,
    tol: float = 0.002,
) -> tuple[Array, float]:
    """A right-arm posture that puts the palm at world point ``target``, and the distance
    (metres) left: damped least squares on the palm's position Jacobian, steps clipped to
    ``max_step`` radians, joints clipped to their ranges. The scene's arm is restored.
    """
    mj, m, d = scene._mj, scene.model, scene.data
    saved = scene.arm()
    q = np.array(saved if q0 is None else q0, dtype=np.float64)
    goal = np.asarray(target, dtype=np.float64)
    dofs = np.array([m.jnt_dofadr[m.joint(n).id] for n in ARM])
    jac = np.zeros((3, m.nv))
    err = np.inf
    for _ in range(iterations):
        scene.set_arm(q)
        e = goal - scene.palm_position()
        err = float(np.linalg.norm(e))
        if err < tol:
            break
        mj.mj_comPos(m, d)  # the Jacobian reads the dofs' motion axes
        mj.mj_jacSite(m, d, jac, None, scene._palm)
        j = jac[:, dofs]
        dq = j.T @ np.linalg.solve(j @ j.T + damping**2 * np.eye(3), e)
        q = np.clip(q + np.clip(dq, -max_step, max_step), *scene.arm_range.T)
    scene.set_arm(saved)
    return q, err


@dataclass(frozen=True)
class ReachOutcome:
    """What one physical reach did."""

    touched: bool
    """Whether the right hand touched the ball (the forearm does not count)."""
    distance: float
    """Closest distance of the palm to the ball's centre during the reach, metres."""
    frames: tuple[NDArray[np.uint8], ...] = ()
    """Third-person frames, when asked for."""


def physical_reach(
    scene: ICubScene, q: ArrayLike, *, seconds: float = 0.6, film: int = 0
) -> ReachOutcome:
    """Move the right arm from its home pose to posture ``q`` in the physics, through the
    approach posture (``q`` with the elbow bent by :data:`LIFT`), ``seconds`` for each leg;
    ``film`` > 0 keeps that many third-person frames per leg."""
    scene.set_arm(HOME_ARM)
    target = np.asarray(q, dtype=np.float64)
    above = target.copy()
    above[_ELBOW] += LIFT
    touched, best = False, np.inf
    frames: list[NDArray[np.uint8]] = []
    dt = scene.model.opt.timestep
    steps = max(1, round(seconds / dt))
    for goal in (above, target):
        scene.set_arm_targets(np.clip(goal, *scene.arm_range.T))
        for i in range(steps):
            scene._mj.mj_step(scene.model, scene.data)
            if i % 10 == 0:
                touched = touched or scene.hand_touches_ball()
                with scene.truth():  # the score
                    gap = float(np.linalg.norm(scene.palm_position() - scene.ball_position()))
                best = min(best, gap)
            if film and i % max(1, steps // film) == 0:
                frames.append(scene.render("third"))
    touched = touched or scene.hand_touches_ball()
    return ReachOutcome(touched, best, tuple(frames))
