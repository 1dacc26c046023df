"""What a map learned, shown: figure data, drawing, the report's figures, learning curves.

- :mod:`~sigmapi.viz.analysis`: figure data computed from a model (Fig. 8, receptive fields,
  polarity, invariance, tiles), no drawing;
- :mod:`~sigmapi.viz.plots`: drawing, ``ax=None`` in, the Axes out;
- :mod:`~sigmapi.viz.figures`: the report's figures, a registry name -> draw function +
  caption computed from the data;
- :mod:`~sigmapi.viz.curves`: learning curves (checkpoints, costs, the ``LearningCurve``
  callback);
- :mod:`~sigmapi.viz.ceiling`: the learning rule's ceiling, the fixed point of Eq. 7 reached
  from a map (drawn in the learning curves);
- :mod:`~sigmapi.viz.compare`: the figure of the comparison with the baselines.

matplotlib is imported by the drawing modules only, when they are imported.
"""
