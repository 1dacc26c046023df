"""The compare experiment (``sigmapi compare``): the Sigma-Pi map beside the baselines a user would
pick instead.

Guide: docs/guide/compare.md; results: docs/results/baselines.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``result``,
``run``.
"""
