"""The transformation in neuron models other than the Sigma-Pi unit (docs/guide/neurons.md).

- :mod:`~sigmapi.neurons.training`: the chapter's two-view rule for maps of first-order
  neurons (:class:`FirstOrderMap`, :class:`TrainingConfig`);
- :mod:`~sigmapi.neurons.dendritic`: units with dendritic branches, each a conjunction of a
  retinal and a gaze region (:class:`DendriticMap`);
- :mod:`~sigmapi.neurons.sparse`: units whose branches hold two clustered synapses each, an
  AND of one retinal and one gaze input, pruned to a budget (:class:`SparseDendriticMap`);
- :mod:`~sigmapi.neurons.basis`: a basis-function network, a fixed conjunctive layer and a
  learned readout (:class:`BasisFunctionMap`);
- :mod:`~sigmapi.neurons.spiking`: a trained map deployed in spiking neurons (NumPy only);
- :mod:`~sigmapi.neurons.nengo_net`: a trained map as a spiking Nengo network (the nengo
  extra; imported only when used, not here);
- :mod:`~sigmapi.neurons.nir_graph`: a trained map as a NIR graph of spiking primitives
  (``sigmapi export --format nir``; the nir extra; not imported here).
"""

from sigmapi.neurons.basis import BasisFunctionMap
from sigmapi.neurons.dendritic import DendriticMap
from sigmapi.neurons.sparse import SparseDendriticMap
from sigmapi.neurons.spiking import SpikingConfig
from sigmapi.neurons.training import FirstOrderMap, TrainingConfig

__all__ = [
    "BasisFunctionMap",
    "DendriticMap",
    "FirstOrderMap",
    "SparseDendriticMap",
    "SpikingConfig",
    "TrainingConfig",
]
