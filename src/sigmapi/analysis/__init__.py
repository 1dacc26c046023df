"""Analyses of trained maps, as arrays (no drawing): ``map_data`` (what a map learned: the
figure data), ``curves`` (the learning curves' training callback), ``fixed_point`` (the
learning rule's ceiling) and ``physiology`` (the map read as an electrophysiologist reads a
brain area: tuning curves, reference-frame index, gain fields)."""
