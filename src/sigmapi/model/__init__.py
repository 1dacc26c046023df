"""The estimator, :class:`~sigmapi.model.som.SigmaPiSOM` (``som``), and what it is made of:
its mixins (``_grids``: grids and codes, ``_cost``: the section 6.3 cost, ``_params``:
scikit-learn's parameters, ``_persist``: arrays, files and pickles, ``_refine``: the
refinement, ``_stream``: stream learning), the checks of view pairs and input codes
(``views``) and what a model file holds (``file``, which never imports ``som``)."""
