"""The stream experiment (``sigmapi stream``): maps learned from a stream of frames (the trace
rule) against explicit view pairs. Guide: docs/guide/stream.md; results: none published yet.

Modules: ``run`` (settings, result and run, read top to bottom; ``REGISTRY``'s entry) and
``figures`` (the figure, matplotlib).
"""
