"""The chain experiment (``sigmapi chain``): a chain of two maps (retina -> head -> body) against
one map.

Guide: docs/guide/chain.md; results: docs/results/chain.md.

Modules: ``run`` (its settings, result and run in one module, read top to bottom; the
experiment object, ``REGISTRY``'s entry).
"""
