"""What a map learned, drawn (the numbers come from :mod:`sigmapi.analysis`).

- :mod:`~sigmapi.viz.plots`: drawing, ``ax=None`` in, the Axes out;
- :mod:`~sigmapi.viz.figures`: the report's figures, a registry name -> draw function +
  caption computed from the data.

An experiment's own figures live in its package (``sigmapi.experiments.<name>``), what they
share in :mod:`sigmapi.experiments.kit.figures`.

The figure data (Fig. 8, receptive fields, polarity, invariance, tiles), the learning curves'
callback and the rule's ceiling (the fixed point of Eq. 7) are computed in
:mod:`sigmapi.analysis` (``map_data``, ``curves``, ``fixed_point``). matplotlib is imported by
the drawing modules only, when they are imported.
"""
