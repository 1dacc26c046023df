"""The chain experiment (``sigmapi chain``): a chain of two maps (retina -> head -> body) against
one map.

Guide: docs/guide/chain.md; results: docs/results/chain.md.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``result``,
``run``.
"""
