"""The iCub experiment (``sigmapi icub``): the humanoid learns where things are from its own
eyes and neck (a chain of two Sigma-Pi maps), and learns to reach from motor babbling.

Guide and results: docs/guide/icub.md (its numbers rendered from benchmarks/results/icub.json).

- :mod:`~sigmapi.experiments.icub.config`: :class:`ICubConfig` and the quick config;
- :mod:`~sigmapi.experiments.icub.maps`: map 1 (eyes) and map 2 (head), their scores against
  the true directions, the true-direction map and the cubic fit beside them;
- :mod:`~sigmapi.experiments.icub.reaching`: babbling, the associations, the reaches;
- :mod:`~sigmapi.experiments.icub.run`: :data:`ICUB`, the registered experiment;
- :mod:`~sigmapi.experiments.icub.result` and :mod:`~sigmapi.experiments.icub.plots`: the
  outcome, its JSON, table and figures.
"""
