"""The reproduction run: ``sigmapi reproduce --out DIR``, the project's main job.

Trains the paper presets (``paper-1d``, and ``paper-2d`` where that preset ships) for a few
seeds, recording learning curves at checkpoints, evaluates them, draws the figures of the
paper and writes into ``DIR``:

- ``report.html``: self-contained (it links only the PNG files beside it), with the measured
  metrics beside the reference figures of docs/algorithm.md and a caption per figure;
- ``metrics.json``: every number of the report (metrics per seed, learning curves, facts shown
  in the captions);
- the figures, ``<figure>-<preset>.png`` for the figures of :data:`~sigmapi.viz.figures.FIGURES`;
- the trained models, ``<preset>-seed<S>.npz``: by default the one the figures show (the
  best-ordered seed; ``sigmapi figure`` redraws from it), or every seed's, or none
  (``save_models``; a paper-2d file holds its 225 x 225 x 225 weights, so it is large).

Experiments add sections to the report: a section is a function ``section(ctx:
ReportContext) -> Section | None``; the default, :data:`SECTIONS`, is the reach experiment.

The experiment ``reproduce`` (:class:`Reproduce`, settings :class:`ReproduceConfig`) is
:func:`reproduce` with the seeds, executor and progress given apart; each (preset, seed) is one
job of the executor.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import Experiment, register, run_all
from sigmapi.experiments.reach_section import reach_section
from sigmapi.experiments.report_html import linked_files, render
from sigmapi.experiments.results import (
    REPORT,
    PresetResult,
    ReportContext,
    ReproduceConfig,
    ReproduceOptions,
    ReproduceResult,
    Section,
    SeedRun,
)
from sigmapi.io import atomic_write_bytes
from sigmapi.metrics import evaluate
from sigmapi.progress import Progress
from sigmapi.som import SigmaPiSOM
from sigmapi.viz import figures as figs

__all__ = [
    "QUICK_ITERATIONS", "REFERENCE", "REPRODUCE", "SECTIONS", "Reproduce", "SeedJob",
    "paper_presets", "reproduce", "train_seed",
]  # fmt: skip

REFERENCE: dict[str, dict[str, float]] = {
    "paper-1d": {"view_consistency": 0.87, "view_within_one": 0.988, "z_error": 0.32},
}
"""Reference figures of docs/algorithm.md (the authors' 1-D script re-stated in NumPy, 4 seeds)."""

Z_ERROR_FLOOR: dict[str, float] = {"paper-1d": 0.27}
"""Smallest z error a map of that many units can reach (quantisation into 15 units)."""

PAPER_PRESETS = ("paper-1d", "paper-2d")

OTHER_PROCEDURE = {"paper-1d": "paper-1d-authors", "paper-2d": "paper-2d-authors"}
"""Each paper preset (sigmapi's procedure: ordered start, then refinement) beside the
authors' procedure at the same sizes (random start, no refinement), on the same seeds."""

REFERENCE["paper-1d-authors"] = REFERENCE["paper-1d"]
Z_ERROR_FLOOR["paper-1d-authors"] = Z_ERROR_FLOOR["paper-1d"]

QUICK_REFINE_PAIRS = 20_000
"""Refinement pairs per round in quick runs."""

QUICK_ITERATIONS: dict[str, int] = {"paper-1d": 60_000, "paper-2d": 20_000}
"""Iterations of each preset in quick runs (the schedule is compressed to fit).

paper-2d's quick run is long enough for its map to order but not to converge, so the fold
detector may flag it; a much shorter one leaves the map partly twisted."""

SectionFn = Callable[[ReportContext], Section | None]

SECTIONS: tuple[SectionFn, ...] = (reach_section,)
"""The sections every full report adds after the figures."""


def paper_presets(quick: bool) -> list[tuple[str, SOMConfig]]:
    """The paper presets that ship, shortened to :data:`QUICK_ITERATIONS` when ``quick``."""
    out: list[tuple[str, SOMConfig]] = []
    for name in (n for n in PAPER_PRESETS if n in list_presets()):
        for preset in (name, OTHER_PROCEDURE[name]):
            cfg = load_preset(preset)
            if quick:
                it = QUICK_ITERATIONS.get(name, max(1000, cfg.iterations // 10))
                pairs = min(cfg.refine_pairs, QUICK_REFINE_PAIRS)
                cfg = cfg.replace(iterations=min(cfg.iterations, it), refine_pairs=pairs)
            out.append((preset, cfg))
    return out


def _reference(name: str) -> dict[str, float]:
    ref = dict(REFERENCE.get(name, {}))
    if name in Z_ERROR_FLOOR:
        ref["z_error_floor"] = Z_ERROR_FLOOR[name]
    return ref


def reproduce(
    out: Path,
    options: ReproduceOptions | None = None,
    *,
    presets: Sequence[tuple[str, SOMConfig]] | None = None,
    sections: Sequence[SectionFn] | None = None,
    executor: Executor | None = None,
) -> ReproduceResult:
    """Train and evaluate each paper preset for the seeds; write the report into ``out``.

    Parameters
    ----------
    out : Path
        Report folder (created).
    options : ReproduceOptions, optional
        Seeds, quick mode, progress bars, which models to save, test size.
    presets : list of (name, SOMConfig), optional
        What to run instead of the paper presets (tests use tiny configs).
    sections : sequence of callables, optional
        Functions that add report sections (default :data:`SECTIONS`, the reach
        experiment); ``()`` for none.
    executor : Executor, optional
        Where the training runs go (default: this machine, ``options.workers`` at once).

    Returns
    -------
    ReproduceResult
        What ``metrics.json`` holds (``result.to_dict()``).
    """
    opts = options or ReproduceOptions()
    ex = executor if executor is not None else Executor(workers=opts.workers)
    started = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs_of = paper_presets(opts.quick) if presets is None else list(presets)
    result = ReproduceResult(opts, out=out)
    progress = Progress() if opts.progress else None
    models: dict[str, list[SigmaPiSOM]] = {}
    figures: dict[str, list[tuple[str, str]]] = {}
    trained = _train_all(runs_of, opts, ex, progress)
    for name, cfg in runs_of:
        runs, models[name] = trained[name]
        # figures show the best-ordered seed (the first on ties), and say which
        shown = max(range(len(runs)), key=lambda i: (runs[i].metrics.order_r2, -i))
        entry = PresetResult(cfg, runs, REFERENCE.get(name, {}), Z_ERROR_FLOOR.get(name),
                             opts.seeds[shown])  # fmt: skip
        result.presets[name] = entry
        for i, seed in enumerate(opts.seeds):
            if opts.save_models == "all" or (opts.save_models == "shown" and i == shown):
                models[name][i].save(out / f"{name}-seed{seed}.npz")
        run = figs.RunInfo(name, cfg, opts.seeds, shown, opts.curve_test)
        figures[name] = _draw(run, models[name][shown], entry, out, opts, progress)
        result.figure_files += [out / file for file, _ in figures[name]]
    ctx = ReportContext(out, opts, models)
    added = [s for s in (fn(ctx) for fn in (SECTIONS if sections is None else sections)) if s]
    for s in added:
        result.sections[s.title] = s.data
        result.figure_files += [out / file for file, _ in s.figures]
    result.total_seconds = time.perf_counter() - started
    atomic_write_bytes(out / "metrics.json", json.dumps(result.to_dict(), indent=2).encode())
    text = render(result, figures, added)
    missing = [f for f in linked_files(text) if not (out / f).is_file()]
    if missing:
        raise RuntimeError(f"report links files that were not written: {missing}")
    atomic_write_bytes(out / REPORT, text.encode())
    return result


class Reproduce(Experiment[ReproduceConfig]):
    """Train the paper presets (each under both ordering procedures) for the seeds, evaluate
    them, draw the figures of the paper and write the report: report.html, metrics.json, the
    figures and the trained models the figures show."""

    name = "reproduce"
    summary = "train the paper presets and write the report"
    config_type = ReproduceConfig
    quick = ReproduceConfig(quick=True)
    seeds = tuple(range(10))
    quick_seeds = (0,)
    default_out = "report"

    def run(
        self,
        config: ReproduceConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> ReproduceResult:
        """:func:`reproduce` into ``out`` (required: the report's folder)."""
        if out is None:
            raise ConfigError("out must be the report's folder, got None; e.g. Path('report')")
        ex = executor if executor is not None else Executor(workers=1)
        fields = {f.name: getattr(config, f.name) for f in dataclasses.fields(ReproduceConfig)}
        opts = ReproduceOptions(**fields, seeds=tuple(seeds),
                                progress=Progress.of(progress).enabled,
                                workers=ex.workers)  # fmt: skip
        return reproduce(out, opts, executor=ex)


REPRODUCE = register(Reproduce())


@dataclass(frozen=True)
class SeedJob:
    """One training run of ``reproduce``: preset ``name``'s config, trained from ``seed``."""

    name: str
    cfg: SOMConfig
    seed: int
    n_checkpoints: int
    curve_test: int
    test_size: int
    progress: bool = False


def train_seed(job: SeedJob) -> tuple[SeedRun, dict[str, Any], dict[str, Any]]:
    """Train one seed with learning-curve checkpoints and evaluate it (a job of
    :func:`~sigmapi.executor.run_jobs`); ``(run, header, arrays)`` of the model."""
    from sigmapi.viz.curves import LearningCurve, checkpoints

    cfg = job.cfg
    model = SigmaPiSOM(cfg, seed=job.seed)
    callback, bar = Progress(disable=not job.progress or None).training(
        cfg.iterations, f"{job.name} seed {job.seed}"
    )
    curve = LearningCurve(at=checkpoints(cfg.iterations, job.n_checkpoints),
                          n_test=job.curve_test, then=callback)  # fmt: skip
    t0 = time.perf_counter()
    with bar:
        model.fit(callback=curve)
    seconds = time.perf_counter() - t0
    metrics = evaluate(model, n_test=job.test_size)
    header, arrays = model.to_arrays()
    return SeedRun(job.seed, seconds, model.backend, metrics, curve.to_dict()), header, arrays


def _train_all(
    runs_of: Sequence[tuple[str, SOMConfig]],
    opts: ReproduceOptions,
    executor: Executor,
    progress: Progress | None,
) -> dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]]:
    """Train every (preset, seed), in parallel where cores and memory allow."""
    jobs = [(f"{name} seed {seed}", SeedJob(name, cfg, seed, opts.n_checkpoints,
                                            opts.curve_test, opts.test_size))
            for name, cfg in runs_of for seed in opts.seeds]  # fmt: skip
    per_job = max(job_memory(cfg, opts.test_size) for _, cfg in runs_of)

    def describe(key: str, value: tuple[SeedRun, Any, Any]) -> str:
        run, m = value[0], value[0].metrics
        return (f"{key}: {run.train_seconds:.0f} s, order R^2 {m.order_r2:.3f}"
                f"{', FOLDED' if m.folded else ''}")  # fmt: skip

    done = run_all(train_seed, jobs, executor=executor, per_job=per_job, progress=progress,
                   desc="reproduce", describe=describe,
                   verbose=lambda job: replace(job, progress=True))  # fmt: skip
    out: dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]] = {}
    for name, _ in runs_of:
        runs, models = [], []
        for seed in opts.seeds:
            key = f"{name} seed {seed}"
            run, header, arrays = done[key]
            runs.append(run)
            models.append(SigmaPiSOM.from_arrays(header, arrays, source=key))
        out[name] = (runs, models)
    return out


def _draw(
    run: figs.RunInfo,
    model: SigmaPiSOM,
    entry: PresetResult,
    out: Path,
    opts: ReproduceOptions,
    progress: Progress | None,
) -> list[tuple[str, str]]:
    """Draw every figure of one preset into ``out``; ``(file, caption)`` per figure.

    The facts each caption states are stored in ``entry.figures``.
    """
    from sigmapi.viz.analysis import receptive_field_centres

    centres = receptive_field_centres(model, seed=0)
    curves = [r.curve for r in entry.runs]
    seeds = run.seeds
    drawn = []
    bar = Progress.of(progress).each(figs.FIGURES, f"{run.preset} figures")
    for fig_name in bar:
        file = f"{fig_name}-{run.preset}.png"
        label = f"{run.preset}, seed {seeds[run.shown]}"
        if fig_name == "curves":
            label = (
                f"{run.preset}, seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}"
            )
        facts = figs.draw_figure(fig_name, model, out / file, curves=curves,
                                 reference=_reference(run.preset), label=label,
                                 centres=centres, dpi=opts.dpi)  # fmt: skip
        entry.figures[fig_name] = {"file": file, **facts}
        drawn.append((file, figs.caption(fig_name, run, facts)))
    return drawn
