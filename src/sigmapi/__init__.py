"""sigmapi: self-organizing maps of Sigma-Pi units that learn frame-of-reference transformations.

Weber & Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007) 2552-2560.

Importing the package registers the Gymnasium environments ``sigmapi/GazeReach-v0``
(:class:`sigmapi.envs.GazeReachEnv`), ``sigmapi/RobotDock-v0``
(:class:`sigmapi.envs.robot.RobotDockEnv`, with ``sigmapi[robot]``) and
``sigmapi/ICubReach-v0`` (:class:`sigmapi.envs.icub.env.ICubReachEnv`, idem) by their entry-point
strings, with their time limits: ``gymnasium.make`` loads the environment's module when it is
first made and wraps it in ``TimeLimit``.
"""

# first: a quiet Ctrl-C while the command line starts (see _startup.py)
from sigmapi import _startup  # noqa: F401  # isort: skip

import gymnasium as _gymnasium

from sigmapi._version import __version__
from sigmapi.codes import PopulationCode
from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.errors import ConfigError, DataError, ModelFileError, NotFittedError, SigmapiError
from sigmapi.kernels import register_backend
from sigmapi.metrics import Metrics, evaluate
from sigmapi.model.som import SigmaPiSOM
from sigmapi.model.som import load_model as load
from sigmapi.schedules import PiecewiseLinear
from sigmapi.tasks import Batch, Relation, TwoViewSampler

__all__ = [
    "Batch",
    "ConfigError",
    "DataError",
    "Metrics",
    "ModelFileError",
    "NotFittedError",
    "PiecewiseLinear",
    "PopulationCode",
    "Relation",
    "SOMConfig",
    "SigmaPiSOM",
    "SigmapiError",
    "TwoViewSampler",
    "__version__",
    "evaluate",
    "list_presets",
    "load",
    "load_preset",
    "register_backend",
]

if "sigmapi/GazeReach-v0" not in _gymnasium.registry:
    # the time limit is defined here only (GazeReachConfig reads it back): 50 steps, 3x the
    # longest shortest path of the 2-D task (16 moves from a corner to the goal box)
    _gymnasium.register(
        id="sigmapi/GazeReach-v0",
        entry_point="sigmapi.envs.gaze_reach:GazeReachEnv",
        max_episode_steps=50,
    )
if "sigmapi/RobotDock-v0" not in _gymnasium.registry:
    # the simulated robot (sigmapi.envs.robot); making it needs the robot extra (MuJoCo)
    _gymnasium.register(
        id="sigmapi/RobotDock-v0",
        entry_point="sigmapi.envs.robot.env:RobotDockEnv",
        max_episode_steps=100,
    )
if "sigmapi/ICubReach-v0" not in _gymnasium.registry:
    # the iCub humanoid (sigmapi.envs.icub); making it needs the robot extra (MuJoCo and
    # icub-models); no time limit: every episode ends with its one reach (terminated)
    _gymnasium.register(id="sigmapi/ICubReach-v0", entry_point="sigmapi.envs.icub.env:ICubReachEnv")
if "sigmapi/ICubReach3D-v0" not in _gymnasium.registry:
    # the iCub's 3-D task (sigmapi.experiments.icub.env3d: a ball in the air, both eyes, palm
    # first); making it needs the robot extra; every episode ends with its one reach
    _gymnasium.register(
        id="sigmapi/ICubReach3D-v0", entry_point="sigmapi.experiments.icub.env3d:ICubReach3DEnv"
    )
