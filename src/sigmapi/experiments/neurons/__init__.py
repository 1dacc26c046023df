"""``sigmapi neurons``: the transformation in neurons a biologist accepts.

Per seed, on the same task, the Sigma-Pi map of the preset, dendritic maps with first-order
synapses (:mod:`sigmapi.neurons.dendritic`, :mod:`sigmapi.neurons.sparse`) and a
basis-function network (:mod:`sigmapi.neurons.basis`), in 1-D and 2-D; in 1-D also each map's
physiology and spiking deployments (:mod:`sigmapi.neurons.spiking`). The method names of the
result are in docs/guide/neurons.md. Modules: ``config`` (:class:`~.config.NeuronsConfig`),
``run`` (the experiment, ``REGISTRY``'s entry: one job per seed and task), ``result``
(medians, acceptance, table, figure) and ``figures``.

Guide: docs/guide/neurons.md; results: docs/results/neurons.md.
"""
