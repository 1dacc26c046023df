"""Analyses of a trained map beyond :func:`sigmapi.evaluate`: :mod:`~sigmapi.analysis.physiology`
reads the map as an electrophysiologist reads a brain area (tuning curves, reference-frame
index, gain fields)."""
