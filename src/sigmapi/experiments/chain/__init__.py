"""The chain experiment (``sigmapi chain``): a chain of two maps (retina -> head -> body) against
one map. Guide: docs/guide/chain.md; results: docs/results/chain.md.

Module: ``run`` (settings, result and run, read top to bottom; ``REGISTRY``'s entry).
"""
