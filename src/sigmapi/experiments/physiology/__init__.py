"""``sigmapi physiology MODEL``: a model file read as an electrophysiologist reads a brain area.

Every unit of the model file's map and of the map's random start (the paper's random
weights for the model's own config and seed) is recorded by
:func:`sigmapi.analysis.physiology.record`: tuning curves over retinal position at several
fixed gazes, a reference-frame index per unit (0 eye-centred, 1 body-centred; Duhamel et al.
1997) and planar gain-field fits (Andersen et al. 1985). The result holds the per-unit lists,
their medians and a Kolmogorov-Smirnov comparison of the two index distributions; the figure
draws them (docs/guide/neurons.md).

- :mod:`.config`: :class:`PhysiologyConfig`;
- :mod:`.run`: the recording and the random start;
- :mod:`.result`: :class:`PhysiologyResult`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

from sigmapi.executor import Executor
from sigmapi.experiments.base import Experiment, register
from sigmapi.progress import Progress

from .config import PhysiologyConfig
from .result import PhysiologyResult
from .run import RandomStart, record_model

__all__ = ["PHYSIOLOGY", "PhysiologyConfig", "PhysiologyExperiment", "PhysiologyResult",
           "RandomStart"]  # fmt: skip


class PhysiologyExperiment(Experiment[PhysiologyConfig]):
    """Tuning curves, reference-frame indices and gain fields of every unit of a model file,
    against the same map's random start. The seeds are not used (the model file holds its
    own)."""

    name = "physiology"
    summary = "read a model file's units as an electrophysiologist: reference frame, gain fields"
    config_type = PhysiologyConfig
    seeds = (0,)
    default_out = None

    def run(
        self,
        config: PhysiologyConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> PhysiologyResult:
        start = time.perf_counter()
        return PhysiologyResult(config, record_model(config), time.perf_counter() - start)


PHYSIOLOGY = register(PhysiologyExperiment())
