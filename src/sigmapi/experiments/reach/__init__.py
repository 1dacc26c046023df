"""The reach experiment (``sigmapi reach``): learning to reach with an actor-critic on the learned
map against other states.

Guide: docs/guide/reach.md (and docs/guide/reach-levelling.md); results: docs/results/reach.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``figures``,
``result``, ``run``, ``section``.
"""
