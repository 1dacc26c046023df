"""The stream experiment (``sigmapi stream``): maps learned from a stream of frames (the trace
rule) against explicit view pairs.

Guide: docs/guide/stream.md; results: none published yet.

Modules (``run`` holds the experiment object, ``REGISTRY``'s entry): ``config``, ``result``,
``run``.
"""
