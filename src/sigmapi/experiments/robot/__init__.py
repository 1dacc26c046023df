"""The robot experiment (``sigmapi robot``): a simulated robot learns the map from its own
saccades, then docks on it. Guide: docs/guide/robot.md; results: docs/results/robot.md.

The reach experiment's run in the robot's world: ``variant`` holds the experiment object
(``REGISTRY``'s entry, a :class:`~sigmapi.experiments.reach.run.ReachExperiment`); also
``config``, ``map`` (the map learned from recorded view pairs), ``result`` and ``figures``.
"""
