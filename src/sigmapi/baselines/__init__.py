"""Baselines: what a user would pick instead of a Sigma-Pi map, scored by the same metrics.

- :class:`KohonenSOM` (sigmapi's first-order SOM on ``[x; y]``) and :class:`MiniSomMap`
  (MiniSom on the same rows, the external reference);
- :class:`GainFieldNetwork` (basis-function network: gain-field products, linear read-out);
- :class:`RBMFeatures` (scikit-learn's ``BernoulliRBM`` on ``[x; y]``, linear read-out);
- :func:`run_compare`: every method on the same two-view data (``sigmapi compare``).

MiniSom and scikit-learn are the extra ``pip install 'sigmapi[baselines]'``; they are
imported only when a method that needs them runs.
"""

from sigmapi.baselines.experiment import (
    METHODS,
    QUICK,
    CompareConfig,
    CompareResult,
    MethodScore,
    run_compare,
)
from sigmapi.baselines.kohonen import KohonenSOM, MiniSomMap, concat_views
from sigmapi.baselines.readout import GainFieldNetwork, RBMFeatures, fit_readout

__all__ = [
    "METHODS",
    "QUICK",
    "CompareConfig",
    "CompareResult",
    "GainFieldNetwork",
    "KohonenSOM",
    "MethodScore",
    "MiniSomMap",
    "RBMFeatures",
    "concat_views",
    "fit_readout",
    "run_compare",
]
