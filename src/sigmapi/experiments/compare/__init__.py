"""The compare experiment (``sigmapi compare``): the Sigma-Pi map beside the baselines a user would
pick instead. Guide: docs/guide/compare.md; results: docs/results/baselines.md.

Modules: ``run`` (settings, result and run, read top to bottom; ``REGISTRY``'s entry) and
``figures`` (the figure, matplotlib).
"""
