"""``sigmapi stream``: learning from a stream of frames against learning from explicit pairs.

A robot does not receive view pairs known to share z: it receives a stream in which the object
stays put for a few saccades (the dwell time ``d``) and then moves at moments nobody marks
(:meth:`sigmapi.tasks.TwoViewSampler.stream`), so the consecutive frames that straddle a move
are wrong pairs. Per seed this experiment trains

- **pairs**: the map on explicit view pairs of one z (:meth:`~sigmapi.SigmaPiSOM.fit` on the
  built-in task), the reference;
- **stream, trace lam**, for each dwell time ``d`` and trace constant ``lam``: the same config
  on ``iterations + 1`` frames of the stream (:meth:`~sigmapi.SigmaPiSOM.fit_stream`, the
  trace rule of :mod:`sigmapi.rules.trace`). All trace constants of one ``(seed, d)`` see the
  same frames.

and scores every map by :func:`sigmapi.evaluate` (view consistency, z error, order R^2, fold
score). ``"methods"`` holds one entry per method and dwell time: medians, worst seed and the
per-seed values; ``"acceptance"`` the comparison with pairs seed by seed at ``d >= 4``.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sigmapi.config import SOMConfig
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import Experiment, check_seeds, register, run_all
from sigmapi.experiments.kit.jobs import Tick, counted, iterations_counted
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.experiments.stream.config import (
    QUICK,
    StreamConfig,
)
from sigmapi.experiments.stream.result import (
    FIGURE,
    METRICS,
    VC_MARGIN,
    StreamResult,
)
from sigmapi.metrics import evaluate
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress

__all__ = [
    "FIGURE",
    "METRICS",
    "STREAM",
    "STREAM_KEY",
    "VC_MARGIN",
    "StreamConfig",
    "StreamExperiment",
    "StreamJob",
    "StreamResult",
    "stream_job",
]

STREAM_KEY = 7
"""Frames of seed s and dwell d: ``SeedSequence(s, spawn_key=(STREAM_KEY, d))``, apart from the
model's own streams (:mod:`sigmapi.model.som`)."""

PLAN = SeedPlan({"frames": STREAM_KEY})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the frames,
one stream per dwell time below it."""


@dataclass(frozen=True)
class StreamJob:
    """One map of the experiment (a job of the executor): pairs when ``dwell`` is None."""

    seed: int
    cfg: SOMConfig
    dwell: int | None
    traces: tuple[float, ...]
    n_test: int
    show: Progress | None = None
    """Where given, the job shows its maps' training iterations."""


def stream_job(job: StreamJob) -> list[dict[str, Any]]:
    """Train and score the maps of one job: the map on pairs, or one map per trace constant on
    the stream of ``(seed, dwell)``; one dict per map (``seed``, ``dwell``, ``trace``, the
    :data:`METRICS`, ``folded``, ``seconds``)."""
    maps = 1 if job.dwell is None else len(job.traces)
    what = "pairs" if job.dwell is None else f"dwell {job.dwell}"
    desc = f"stream seed {job.seed} {what}"
    work = functools.partial(_stream_job, job)
    return counted(job.show, maps * job.cfg.iterations, desc, work, "it")


def _stream_job(job: StreamJob, tick: Tick | None) -> list[dict[str, Any]]:
    out = []
    its = job.cfg.iterations

    def scored(model: SigmaPiSOM, trace: float | None, start: float) -> dict[str, Any]:
        m = evaluate(model, n_test=job.n_test)
        row: dict[str, Any] = {"seed": job.seed, "dwell": job.dwell, "trace": trace}
        row.update({k: float(getattr(m, k)) for k in METRICS})
        row.update(folded=bool(m.folded), seconds=time.perf_counter() - start)
        return row

    if job.dwell is None:
        start = time.perf_counter()
        model = SigmaPiSOM(job.cfg, seed=job.seed)
        return [scored(model.fit(callback=iterations_counted(tick, "pairs", its)), None, start)]
    model = SigmaPiSOM(job.cfg, seed=job.seed)
    rng = PLAN.rng(job.seed, "frames", job.dwell)
    frames = model.sampler.stream(job.cfg.iterations + 1, job.dwell, rng)
    for lam in job.traces:
        start = time.perf_counter()
        model = SigmaPiSOM(job.cfg, seed=job.seed).fit_stream(
            (frames.x, frames.y),
            trace=lam,
            callback=iterations_counted(tick, f"trace {lam:g}", its),
        )
        out.append(scored(model, lam, start))
    return out


def run_stream(
    config: StreamConfig,
    seeds: Sequence[int],
    executor: Executor | None = None,
    progress: Progress | None = None,
) -> StreamResult:
    """Every map of ``config`` on each of ``seeds`` (one job per seed and dwell time, and one
    per seed on pairs), scored; the :class:`StreamResult`."""
    seeds = check_seeds(seeds)
    cfg = config.som_config
    start = time.perf_counter()
    jobs = [(f"seed {s} pairs", StreamJob(s, cfg, None, (), config.n_test)) for s in seeds]
    jobs += [
        (f"seed {s} dwell {d}", StreamJob(s, cfg, d, config.traces, config.n_test))
        for s in seeds
        for d in config.dwells
    ]
    frames = 8 * (cfg.iterations + 1) * 2 * (int(np.prod(cfg.x_shape)) + int(np.prod(cfg.y_shape)))

    def describe(key: str, rows: list[dict[str, Any]]) -> str:
        return f"{key}: same unit " + ", ".join(f"{r['view_consistency']:.3f}" for r in rows)

    done = run_all(
        stream_job,
        jobs,
        executor=executor,
        per_job=job_memory(cfg, config.n_test) + frames,
        progress=progress,
        desc="stream",
        describe=describe,
        verbose=lambda job: dataclasses.replace(job, show=progress),
    )
    runs = [r for rows in done.values() for r in rows]
    return StreamResult(config, seeds, runs, time.perf_counter() - start)


class StreamExperiment(Experiment[StreamConfig]):
    """Maps learned from a stream of frames (the trace rule) over dwell times and trace
    constants, against the map learned from explicit pairs, on the same seeds."""

    name = "stream"
    summary = "learning from a stream of frames (trace rule) against explicit view pairs"
    config_type = StreamConfig
    quick = QUICK
    seeds = tuple(range(800, 810))
    quick_seeds = (0,)
    quick_time = "about 45 s on two busy cores"
    default_out = "stream"
    writes = (FIGURE, Path(FIGURE).with_suffix(".txt").name)
    """The files written into --out besides result.json (checked before the work)."""

    def run(
        self,
        config: StreamConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> StreamResult:
        return run_stream(config, seeds, executor, progress)


STREAM = register(StreamExperiment())
