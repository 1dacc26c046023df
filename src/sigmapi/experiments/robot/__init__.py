"""The robot experiment (``sigmapi robot``): a simulated robot learns the map from its own
saccades, then docks on it.

Guide: docs/guide/robot.md; results: docs/results/robot.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``figures``,
``map``, ``result``, ``run``.
"""
