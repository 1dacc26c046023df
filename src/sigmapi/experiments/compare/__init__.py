"""The compare experiment (``sigmapi compare``): the Sigma-Pi map beside the baselines a user would
pick instead.

Guide: docs/guide/compare.md; results: docs/results/baselines.md.

Modules: ``run`` (its settings, result and run in one module, read top to bottom; the
experiment object, ``REGISTRY``'s entry) and ``figures`` (the figure, matplotlib).
"""
