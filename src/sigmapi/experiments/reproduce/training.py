"""The training of ``sigmapi reproduce``: one job per (preset, seed) (:func:`train_seed`: its
learning curve, the map before and after the refinement, its times taken apart), the kernels
compiled once per process on a small run of the same rules (:func:`compile_once`), and every
job run through the executor, longest first (:func:`train_all`)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from sigmapi.config import SOMConfig
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import run_all
from sigmapi.experiments.reproduce.results import ReproduceOptions, SeedRun
from sigmapi.kernels import DEFINITION, get_backend
from sigmapi.metrics import Metrics, evaluate
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress


@dataclass(frozen=True)
class SeedJob:
    """One training run of ``reproduce``: preset ``name``'s config, trained from ``seed``."""

    name: str
    cfg: SOMConfig
    seed: int
    opts: ReproduceOptions
    """The run's options: its measurements' sizes."""
    progress: bool = False
    measure_first: bool = False
    """Compile the kernels that refine and measure a map before those that train it
    (:func:`compile_once`); :func:`train_all` sets it on every other job."""

    @property
    def key(self) -> str:
        return f"{self.name} seed {self.seed}"


COMPILED_BY = (
    "backend", "winner_rule", "ordering", "refine_sigma", "refine_tol", "periodic", "map_periodic",
    "same_view", "threads",
)  # fmt: skip
"""The config fields that choose the compiled code (with the dimensions and whether it refines)."""

_COMPILED: set[tuple[object, ...]] = set()
"""The rule combinations this process has compiled (:func:`compile_once`)."""


def compile_once(cfg: SOMConfig, measure_first: bool = False) -> float:
    """Compile the kernel functions ``cfg`` trains, refines and is measured with, once per
    process, on a 3-unit map of the same rules and dimensions (numba compiles a function on
    its first call, whatever the arrays' sizes), so that :func:`train_seed`'s times hold no
    compile; the wall seconds it took (0 if done before). ``measure_first``: the kernels that
    refine and measure first (:func:`_compile_measuring`; docs/guide/reproduce.md, "Times",
    says why)."""
    from sigmapi.analysis.curves import LearningCurve

    dims = (cfg.refine_rounds > 0, len(cfg.map_shape), len(cfg.x_shape))
    key = (*(getattr(cfg, k) for k in COMPILED_BY), *dims)
    if key in _COMPILED:
        return 0.0
    t0 = time.perf_counter()
    small = cfg.replace(
        map_shape=(3,) * len(cfg.map_shape),
        x_shape=(4,) * len(cfg.x_shape),
        y_shape=(4,) * len(cfg.y_shape),
        iterations=2000,
        seed=0,
        refine_rounds=min(cfg.refine_rounds, 1),
        refine_pairs=min(cfg.refine_pairs, 500),
    )
    if measure_first and not _COMPILED:
        _compile_measuring(small)
    model = SigmaPiSOM(small).fit(callback=LearningCurve(at=[small.iterations], n_test=50))
    evaluate(model, n_test=50)
    _COMPILED.add(key)
    return time.perf_counter() - t0


def _compile_measuring(small: SOMConfig) -> None:
    """Call the kernels that refine and evaluate a trained map of config ``small`` without
    calling the one that trains it: a short run on the reference kernel (NumPy) gives the
    weights, moved onto ``small``'s own kernel, which refines them (``small``'s rounds) and
    evaluates them."""
    backend = SigmaPiSOM(small).backend
    if not get_backend(backend).COMPILES:
        return
    short = small.replace(backend=DEFINITION, iterations=50, refine_rounds=0)
    header, arrays = SigmaPiSOM(short).fit().to_arrays()
    header = {**header, "config": {**small.to_dict(), "backend": DEFINITION}}
    model = SigmaPiSOM.from_arrays(header, arrays, backend=backend, source="compile")
    model.refine()
    evaluate(model, n_test=50)


Trained = tuple[SeedRun, dict[str, object], dict[str, NDArray[np.generic]]]
"""What :func:`train_seed` returns: the run and its model as a header and arrays."""


def train_seed(job: SeedJob) -> Trained:
    """Train one seed with learning-curve checkpoints and evaluate its map at the end of the
    training, before the refinement, and at the end (a job of :func:`train_all`); ``(run,
    header, arrays)`` of the model, the times taken apart (:class:`SeedRun`)."""
    from sigmapi.analysis.curves import LearningCurve, checkpoints

    cfg = job.cfg
    compile_c0 = time.process_time()
    compile_s = compile_once(cfg, job.measure_first)
    c0 = time.process_time()
    compile_cpu = c0 - compile_c0
    model = SigmaPiSOM(cfg, seed=job.seed)
    callback, bar = Progress(disable=not job.progress or None).training(cfg.iterations, job.key)
    at = checkpoints(cfg.iterations, job.opts.n_checkpoints)
    curve = LearningCurve(at=at, n_test=job.opts.curve_test, then=callback)
    marks: dict[str, float] = {}  # times at the end of the training
    unrefined: list[Metrics] = []  # the map there, where the preset refines

    def step(m: SigmaPiSOM) -> None:
        curve(m)
        if "trained" not in marks and m.t_ >= cfg.iterations and m.refined_ == 0:
            marks["trained"] = time.perf_counter()
            marks["curve_s"] = curve.seconds
            if cfg.refine_rounds > 0:
                unrefined.append(evaluate(m, n_test=job.opts.test_size))
            marks["eval_s"] = time.perf_counter() - marks["trained"]

    t0 = time.perf_counter()
    with bar:
        model.fit(callback=step)
    end = time.perf_counter()
    metrics = evaluate(model, n_test=job.opts.test_size)
    final_eval = time.perf_counter() - end
    trained = marks.get("trained", end)
    train_s = trained - t0 - marks.get("curve_s", curve.seconds)
    refine_s = end - trained - marks.get("eval_s", 0.0) - (curve.seconds - marks.get("curve_s", 0))
    header, arrays = model.to_arrays()
    run = SeedRun(
        job.seed,
        train_s,
        model.backend,
        metrics,
        curve.to_dict(),
        unrefined=unrefined[0] if unrefined else None,
        refine_seconds=max(refine_s, 0.0),
        compile_seconds=compile_s,
        compile_cpu_seconds=compile_cpu,
        measure_seconds=curve.seconds + marks.get("eval_s", 0.0) + final_eval,
        cpu_seconds=time.process_time() - c0,
    )
    return run, header, arrays


FLAG_NOTE = (
    ", flagged by the fold detector (a sign of a fold or of a coarse map; order R^2 decides)"
)
"""What a console line adds for a map the z-free fold detector flags: the flag is no verdict
that the map is folded (a short run's coarse map raises it too); ``ordered`` is order R^2."""


def _job_cost(cfg: SOMConfig) -> float:
    """A job's work, to start the longest first: weights times the pairs they learn from."""
    weights = math.prod(cfg.map_shape) * math.prod(cfg.x_shape) * math.prod(cfg.y_shape)
    return float(weights) * (cfg.iterations + cfg.refine_rounds * cfg.refine_pairs)


def train_all(
    runs_of: Sequence[tuple[str, SOMConfig]],
    opts: ReproduceOptions,
    executor: Executor,
    progress: Progress | None,
) -> dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]]:
    """Train every (preset, seed), in parallel where cores and memory allow."""
    jobs = [SeedJob(name, cfg, seed, opts) for name, cfg in runs_of for seed in opts.seeds_of(cfg)]
    longest = sorted(jobs, key=lambda job: -_job_cost(job.cfg))  # no lone job at the end
    # every other job compiles the other half first: two workers share numba's compile
    keyed = [(job.key, replace(job, measure_first=i % 2 == 1)) for i, job in enumerate(longest)]

    def describe(key: str, value: Trained) -> str:
        run, m = value[0], value[0].metrics
        refine = f" + refinement {run.refine_seconds:.0f} s" if run.unrefined else ""
        before = f" (before refinement {run.unrefined.order_r2:.3f})" if run.unrefined else ""
        compiled = f"; compile {run.compile_seconds:.0f} s apart" if run.compile_seconds else ""
        return (
            f"{key}: training {run.train_seconds:.0f} s{refine}{compiled}, order R^2 "
            f"{m.order_r2:.3f}{before}{FLAG_NOTE if m.folded else ''}"
        )

    done = run_all(
        train_seed,
        keyed,
        executor=executor,
        per_job=max(job_memory(cfg, opts.test_size) for _, cfg in runs_of),
        progress=progress,
        desc="reproduce",
        describe=describe,
        verbose=lambda job: replace(job, progress=True),
    )
    out: dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]] = {n: ([], []) for n, _ in runs_of}
    for job in jobs:  # each preset's runs and models in the order of its seeds
        run, header, arrays = done[job.key]
        out[job.name][0].append(run)
        out[job.name][1].append(SigmaPiSOM.from_arrays(header, arrays, source=job.key))
    return out
