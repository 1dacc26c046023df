"""The reward experiment (``sigmapi reward``): a map whose plasticity is gated by reward against
the frozen map and a shuffled control. Guide: docs/guide/reward.md; results: none published
yet. Modules: ``config``, ``run`` (``REGISTRY``'s entry), ``result`` and ``figures``.
"""
