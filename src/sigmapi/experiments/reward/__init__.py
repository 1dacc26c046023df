"""The reward experiment (``sigmapi reward``): a map whose plasticity is gated by reward against
the frozen map and a shuffled control.

Guide: docs/guide/reward.md; results: none published yet.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``figures``,
``result``, ``run``.
"""
