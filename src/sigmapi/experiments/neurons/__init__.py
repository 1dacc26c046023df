"""``sigmapi neurons``: the transformation in neurons a biologist accepts (docs/guide/neurons.md).

Per seed, on the same task: the Sigma-Pi map of the preset; maps of dendritic neurons with
first-order synapses, one per branch count (:mod:`sigmapi.neurons.dendritic`); a
basis-function network (:mod:`sigmapi.neurons.basis`); all trained by the chapter's two-view
rule and scored by :func:`sigmapi.evaluate`, in 1-D and (on the first ``seeds_2d`` seeds) in
2-D. In 1-D also each map's physiology (:mod:`sigmapi.analysis.physiology`) and the Sigma-Pi
and one dendritic map deployed in spiking neurons (:mod:`sigmapi.neurons.spiking`) over
decision windows and peak rates. ``"methods"`` holds one entry per map and per spiking
network, window and peak rate (``sigma-pi``, ``dendritic-D<n>``, ``basis-function``,
``spiking-conjunction-<w>ms``, ``spiking-dendritic-<w>ms``; other rates than 100 Hz end in
``-<r>hz``); ``"acceptance"`` the comparisons seed by seed.

- :mod:`.config`: :class:`NeuronsConfig` and the quick look;
- :mod:`.run`: one job per seed and task;
- :mod:`.result`: :class:`NeuronsResult` (medians, acceptance, table, figure).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import Experiment, check_seeds, register, run_all
from sigmapi.progress import Progress

from .config import QUICK, NeuronsConfig
from .result import NeuronsResult
from .run import NeuronsJob, neurons_job

__all__ = ["NEURONS", "NeuronsConfig", "NeuronsExperiment", "NeuronsResult", "run_neurons"]


def run_neurons(
    config: NeuronsConfig,
    seeds: Sequence[int],
    executor: Executor | None = None,
    progress: Progress | None = None,
) -> NeuronsResult:
    """Every job of ``config`` on ``seeds`` (2-D on the first ``seeds_2d``); the result."""
    seeds = check_seeds(seeds)
    start = time.perf_counter()
    jobs = [(f"seed {s} 1d", NeuronsJob(s, "1d", config)) for s in seeds]
    if config.preset_2d:
        jobs += [(f"seed {s} 2d", NeuronsJob(s, "2d", config)) for s in seeds[: config.seeds_2d]]
    per_job = job_memory(config.som_config_2d if config.preset_2d else config.som_config,
                         config.n_test)  # fmt: skip

    def describe(key: str, value: dict[str, Any]) -> str:
        return f"{key}: " + ", ".join(f"{r['name']} {r['view_consistency']:.3f}"
                                      for r in value["maps"])  # fmt: skip

    done = run_all(neurons_job, jobs, executor=executor, per_job=per_job, progress=progress,
                   desc="neurons", describe=describe)  # fmt: skip
    return NeuronsResult(config, seeds, [done[k] for k, _ in jobs], time.perf_counter() - start)


class NeuronsExperiment(Experiment[NeuronsConfig]):
    """Dendritic neurons with first-order synapses, a basis-function network and spiking
    networks against the Sigma-Pi map, on the same seeds (the chapter's section 7.1)."""

    name = "neurons"
    summary = "the transformation in dendritic, basis-function and spiking neurons"
    config_type = NeuronsConfig
    quick = QUICK
    seeds = (100, 101, 102, 103, 104)
    quick_seeds = (100,)
    default_out = "neurons"

    def run(
        self,
        config: NeuronsConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> NeuronsResult:
        return run_neurons(config, seeds, executor, progress)


NEURONS = register(NeuronsExperiment())
