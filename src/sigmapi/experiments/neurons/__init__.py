"""``sigmapi neurons``: the transformation in neurons a biologist accepts (docs/guide/neurons.md).

Per seed, on the same task: the Sigma-Pi map of the preset; maps of dendritic neurons with
first-order synapses, one per branch count (:mod:`sigmapi.neurons.dendritic`); a
basis-function network (:mod:`sigmapi.neurons.basis`); all trained by the chapter's two-view
rule and scored by :func:`sigmapi.evaluate`, in 1-D and (on the first ``seeds_2d`` seeds) in
2-D. In 1-D also each map's physiology (:mod:`sigmapi.analysis.physiology`) and the Sigma-Pi
and one dendritic map deployed in spiking neurons (:mod:`sigmapi.neurons.spiking`) over
decision windows and peak rates. ``"methods"`` holds one entry per map and per spiking
network, window and peak rate (``sigma-pi``, ``dendritic-D<n>``, ``basis-function``,
``spiking-conjunction-<w>ms``, ``spiking-dendritic-<w>ms``; other rates than 100 Hz end in
``-<r>hz``); ``"acceptance"`` the comparisons seed by seed.

- :mod:`.config`: :class:`NeuronsConfig` and the quick look;
- :mod:`.run`: one job per seed and task;
- :mod:`.result`: :class:`NeuronsResult` (medians, acceptance, table, figure).

The experiment object and its run are in ``run`` (``REGISTRY``'s entry); results:
docs/results/neurons.md.
"""
