"""Baselines: what a user would pick instead of a Sigma-Pi map, scored by the same metrics.

- :class:`KohonenSOM` (sigmapi's first-order SOM on ``[x; y]``) and :class:`MiniSomMap`
  (MiniSom on the same rows, the external reference);
- :class:`GainFieldNetwork` (basis-function network: gain-field products, linear read-out);
- :class:`RBMFeatures` (scikit-learn's ``BernoulliRBM`` on ``[x; y]``, linear read-out);
- :func:`score_units` and :func:`score_readout`: how a method is scored;
- the comparison itself, every method on the same two-view data, is the experiment
  ``sigmapi compare`` (:mod:`sigmapi.experiments.compare.run`, :func:`run_compare` there).

MiniSom and scikit-learn are the extra ``pip install 'sigmapi[baselines]'``; they are
imported only when a method that needs them runs.
"""

from sigmapi.baselines.kohonen import KohonenSOM, MiniSomMap, concat_views
from sigmapi.baselines.readout import GainFieldNetwork, RBMFeatures, fit_readout
from sigmapi.baselines.scoring import score_readout, score_units

__all__ = [
    "GainFieldNetwork",
    "KohonenSOM",
    "MiniSomMap",
    "RBMFeatures",
    "concat_views",
    "fit_readout",
    "score_readout",
    "score_units",
]
