"""The reach experiment (``sigmapi reach``): learning to reach with an actor-critic on the learned
map against other states. Guide: docs/guide/reach.md (and docs/guide/reach-levelling.md);
results: docs/results/reach.md. Modules: ``config``, ``run`` (``REGISTRY``'s entry),
``result``, ``figures`` and ``section`` (its part of the reproduction report).
"""
