"""What the experiments share, written once: the seed plan (:mod:`.seeds`) and the arithmetic
of episode records (:mod:`.episodes`: block success curves and final-window rates)."""
