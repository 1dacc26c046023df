"""The stream experiment (``sigmapi stream``): maps learned from a stream of frames (the trace
rule) against explicit view pairs.

Guide: docs/guide/stream.md; results: none published yet.

Modules: ``run`` (its settings, result and run in one module, read top to bottom; the
experiment object, ``REGISTRY``'s entry) and ``figures`` (the figure, matplotlib).
"""
