"""``sigmapi physiology MODEL``: a model file read as an electrophysiologist reads a brain area.

Every unit of the model file's map and of the map's random start (the paper's random
weights for the model's own config and seed) is recorded by
:func:`sigmapi.analysis.physiology.record`: tuning curves over retinal position at several
fixed gazes, a reference-frame index per unit (0 eye-centred, 1 body-centred; Duhamel et al.
1997) and planar gain-field fits (Andersen et al. 1985). The result holds the per-unit lists,
their medians and a Kolmogorov-Smirnov comparison of the two index distributions; the figure
draws them. Guide: docs/guide/neurons.md. Module: ``run`` (``REGISTRY``'s entry).
"""
