"""sigmapi: self-organizing maps of Sigma-Pi units that learn frame-of-reference transformations.

Weber & Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70 (2007) 2552-2560.
"""

from sigmapi.codes import PopulationCode
from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.errors import ConfigError, ModelFileError, NotFittedError
from sigmapi.io import load_model as load
from sigmapi.metrics import Metrics, evaluate
from sigmapi.schedules import PiecewiseLinear
from sigmapi.som import SigmaPiSOM
from sigmapi.tasks import Batch, Relation, TwoViewSampler

__version__ = "0.1.0"

__all__ = [
    "Batch",
    "ConfigError",
    "Metrics",
    "ModelFileError",
    "NotFittedError",
    "PiecewiseLinear",
    "PopulationCode",
    "Relation",
    "SOMConfig",
    "SigmaPiSOM",
    "TwoViewSampler",
    "__version__",
    "evaluate",
    "list_presets",
    "load",
    "load_preset",
]
