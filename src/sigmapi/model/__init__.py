"""The estimator as one room: :class:`~sigmapi.model.som.SigmaPiSOM` (``som``, its public
face) over one private run state (``_run``: the kernel state, counters, caches, the
refinement's sums, a stream's trace; one reset) and the training modes, functions on it
(``_train``: view pairs and reward-gated iterations, ``_refine``: the refinement,
``_stream``: streams of frames); its bases (``_core``: the map and its queries, ``_grids``:
grids and codes, ``_cost``: the section 6.3 cost, ``_params``: scikit-learn's parameters,
``_persist``: arrays, files and pickles), the checks of view pairs and input codes
(``views``) and what a model file holds (``file``, which never imports ``som``)."""
