"""The sweep experiment (``sigmapi sweep``): parameter and seed sweeps.

Guide: docs/guide/sweeps.md; results: docs/results/angles.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``figures``, ``run``,
``table``.
"""
