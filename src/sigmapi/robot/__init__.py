"""A body for the map: a simulated robot in MuJoCo (``pip install 'sigmapi[robot]'``).

- :mod:`~sigmapi.robot.scene`: the MJCF model (``robot.xml``, from primitives), poses, the
  head camera's projection and pixels, contacts;
- :mod:`~sigmapi.robot.frames`: the three frames, measured: retina x, gaze y, body-centred z;
- :mod:`~sigmapi.robot.views`: a view source, two views of one z from the head's saccades;
- :mod:`~sigmapi.robot.reach`: the scripted arm reach, from the perceived ball to a touch.

Importing this package imports ``mujoco``; ``import sigmapi`` does not.
"""

from __future__ import annotations

from sigmapi.robot.frames import RETINA_SOURCES, Frames, Workspace
from sigmapi.robot.reach import arm_ik, perceived_target, scripted_reach
from sigmapi.robot.scene import Pose, Scene, blob_centroid, load_model
from sigmapi.robot.views import RobotViewBatch, RobotViews

__all__ = [
    "RETINA_SOURCES",
    "Frames",
    "Pose",
    "RobotViewBatch",
    "RobotViews",
    "Scene",
    "Workspace",
    "arm_ik",
    "blob_centroid",
    "load_model",
    "perceived_target",
    "scripted_reach",
]
