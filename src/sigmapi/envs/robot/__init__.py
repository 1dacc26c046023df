"""A body for the map: a simulated robot in MuJoCo (``pip install 'sigmapi[robot]'``).

- :mod:`~sigmapi.envs.robot.scene`: the MJCF model (``robot.xml``, from primitives), poses,
  the head camera's projection and pixels, contacts;
- :mod:`~sigmapi.envs.robot.frames`: the three frames, measured: retina x, gaze y,
  body-centred z;
- :mod:`~sigmapi.envs.robot.views`: a view source (:class:`~sigmapi.envs.PlacedViewSource`),
  two views of one z from the head's saccades;
- :mod:`~sigmapi.envs.robot.reach`: the scripted arm reach, from the perceived ball to a touch;
- :mod:`~sigmapi.envs.robot.env`: ``sigmapi/RobotDock-v0``, docking at the table, then the
  reach.

``mujoco`` is imported when the first :class:`Scene` is built, not with this package.
"""

from __future__ import annotations

from sigmapi.envs.robot.env import ACTIONS, RobotDockEnv
from sigmapi.envs.robot.frames import RETINA_SOURCES, Frames, Workspace
from sigmapi.envs.robot.reach import arm_ik, perceived_target, scripted_reach
from sigmapi.envs.robot.scene import Pose, Scene, blob_centroid, load_model, mujoco_module
from sigmapi.envs.robot.views import RobotViewBatch, RobotViews

__all__ = [
    "ACTIONS",
    "RETINA_SOURCES",
    "Frames",
    "Pose",
    "RobotDockEnv",
    "RobotViewBatch",
    "RobotViews",
    "Scene",
    "Workspace",
    "arm_ik",
    "blob_centroid",
    "load_model",
    "mujoco_module",
    "perceived_target",
    "scripted_reach",
]
