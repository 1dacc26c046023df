"""The iCub humanoid in MuJoCo (``pip install 'sigmapi[robot]'``: MuJoCo and ``icub-models``).

- :mod:`~sigmapi.envs.icub.model`: the URDF converted at first use (eyes, cameras, actuators,
  a table and a ball added) and cached outside the repository;
- :mod:`~sigmapi.envs.icub.scene`: one world, its poses, the eyes' projection and pixels, the
  head- and torso-centred frames, contacts;
- :mod:`~sigmapi.envs.icub.frames`: views of the ball from random gazes, measured;
- :mod:`~sigmapi.envs.icub.reach`: the scripted inverse kinematics and the physical reach;
- :mod:`~sigmapi.envs.icub.env`: ``sigmapi/ICubReach-v0``;
- :mod:`~sigmapi.envs.icub.views`: map 1's view pairs as a view source (:class:`ICubViews`).

``mujoco`` and ``icub_models`` are imported when the first scene is built, not with this
package.
"""

from __future__ import annotations

from sigmapi.envs.icub.env import ENV_ID, ICubReachEnv
from sigmapi.envs.icub.frames import (
    GAZE_HIGH,
    GAZE_LOW,
    HEAD_BOX,
    PAIRS_PER_BALL,
    REACH_REGION,
    TORSO_BOX,
    ViewBatch,
    direction_ball,
    measure,
    random_ball,
    random_gaze,
    random_neck,
    view_pairs,
)
from sigmapi.envs.icub.model import ARM, BALL_RADIUS, HOME_ARM, TABLE_HEIGHT, cache_dir, load_model
from sigmapi.envs.icub.reach import ReachOutcome, arm_ik, physical_reach
from sigmapi.envs.icub.scene import (
    EYE_SIZE,
    GAZE,
    ICubScene,
    TruthLeak,
    direction_angles,
    direction_vectors,
)
from sigmapi.envs.icub.views import ICubViews

__all__ = [
    "ARM",
    "BALL_RADIUS",
    "ENV_ID",
    "EYE_SIZE",
    "GAZE",
    "GAZE_HIGH",
    "GAZE_LOW",
    "HEAD_BOX",
    "HOME_ARM",
    "PAIRS_PER_BALL",
    "REACH_REGION",
    "TABLE_HEIGHT",
    "TORSO_BOX",
    "ICubReachEnv",
    "ICubScene",
    "ICubViews",
    "ReachOutcome",
    "TruthLeak",
    "ViewBatch",
    "arm_ik",
    "cache_dir",
    "direction_angles",
    "direction_ball",
    "direction_vectors",
    "load_model",
    "measure",
    "physical_reach",
    "random_ball",
    "random_gaze",
    "random_neck",
    "view_pairs",
]
