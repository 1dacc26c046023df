"""The reproduction run: ``sigmapi reproduce --out DIR``, the project's main job.

Trains the paper presets (``paper-1d``, and ``paper-2d`` where that preset ships) for a few
seeds, recording learning curves at checkpoints, evaluates them, draws the figures of the
paper and writes into ``DIR``:

- ``report.html``: self-contained (it links only the PNG files beside it), with the measured
  metrics beside the reference figures of docs/algorithm.md and a caption per figure;
- ``metrics.json``: every number of the report (metrics per seed, learning curves, facts shown
  in the captions);
- the figures, ``<figure>-<preset>.png`` for the figures of :data:`~sigmapi.figures.FIGURES`;
- the trained models, ``<preset>-seed<S>.npz``: by default the one the figures show (the
  best-ordered seed; ``sigmapi figure`` redraws from it), or every seed's, or none
  (``--models shown|all|none``; a paper-2d model file is about 140 MB).

Experiments add sections to the report: a section is a function ``section(ctx:
ReportContext) -> Section | None``; the default, :data:`SECTIONS`, is the reach experiment.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from sigmapi import figures as figs
from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.experiments.executor import job_memory, plan_workers, run_jobs
from sigmapi.experiments.reach_section import reach_section
from sigmapi.experiments.report_html import linked_files, render
from sigmapi.experiments.results import (
    PresetResult,
    ReportContext,
    ReproduceOptions,
    ReproduceResult,
    Section,
    SeedRun,
)
from sigmapi.io import atomic_write_bytes
from sigmapi.metrics import evaluate
from sigmapi.progress import each, jobs_done, progress_callback
from sigmapi.som import SigmaPiSOM

__all__ = [
    "QUICK_ITERATIONS", "REFERENCE", "SECTIONS", "SeedJob", "paper_presets", "reproduce",
    "train_seed",
]  # fmt: skip

REFERENCE: dict[str, dict[str, float]] = {
    "paper-1d": {"view_consistency": 0.87, "view_within_one": 0.988, "z_error": 0.32},
}
"""Reference figures of docs/algorithm.md (the authors' 1-D script re-stated in NumPy, 4 seeds)."""

Z_ERROR_FLOOR: dict[str, float] = {"paper-1d": 0.27}
"""Smallest z error a map of that many units can reach (quantisation into 15 units)."""

PAPER_PRESETS = ("paper-1d", "paper-2d")

OTHER_PROCEDURE = {"paper-1d": ("paper-1d-crossview", "crossview"),
                   "paper-2d": ("paper-2d-none", "none")}  # fmt: skip
"""Each paper preset's run under the other ordering procedure, on the same seeds: the
authors' 1-D run with sigmapi's ordered start, and the 2-D preset with the paper's random one."""

REFERENCE["paper-1d-crossview"] = REFERENCE["paper-1d"]
Z_ERROR_FLOOR["paper-1d-crossview"] = Z_ERROR_FLOOR["paper-1d"]

QUICK_ITERATIONS: dict[str, int] = {"paper-1d": 60_000, "paper-2d": 20_000}
"""Iterations of each preset in ``--quick`` runs (the schedule is compressed to fit).

paper-2d at 20,000 (seeds 0-2, default ordering): ordered (order R^2 0.981-0.983) but not
converged (within one 0.94, z error 0.69), so the fold detector flags it (fold score 1.6-1.8);
at 6,000 the map was still partly twisted (R^2 0.92)."""

SectionFn = Callable[[ReportContext], Section | None]

SECTIONS: tuple[SectionFn, ...] = (reach_section,)
"""The sections every full report adds after the figures."""


def paper_presets(quick: bool) -> list[tuple[str, SOMConfig]]:
    """The paper presets that ship, shortened to :data:`QUICK_ITERATIONS` when ``quick``."""
    out: list[tuple[str, SOMConfig]] = []
    for name in (n for n in PAPER_PRESETS if n in list_presets()):
        cfg = load_preset(name)
        if quick:
            it = QUICK_ITERATIONS.get(name, max(1000, cfg.iterations // 10))
            cfg = cfg.replace(iterations=min(cfg.iterations, it))
        out.append((name, cfg))
        other, ordering = OTHER_PROCEDURE[name]
        out.append((other, cfg.replace(ordering=ordering)))
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

    Returns
    -------
    ReproduceResult
        What ``metrics.json`` holds (``result.to_dict()``).
    """
    opts = options or ReproduceOptions()
    started = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs_of = paper_presets(opts.quick) if presets is None else list(presets)
    result = ReproduceResult(opts)
    models: dict[str, list[SigmaPiSOM]] = {}
    figures: dict[str, list[tuple[str, str]]] = {}
    trained = _train_all(runs_of, opts)
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
        figures[name] = _draw(run, models[name][shown], entry, out, opts.progress)
    ctx = ReportContext(out, opts, models)
    added = [s for s in (fn(ctx) for fn in (SECTIONS if sections is None else sections)) if s]
    for s in added:
        result.sections[s.title] = s.data
    result.total_seconds = time.perf_counter() - started
    atomic_write_bytes(out / "metrics.json", json.dumps(result.to_dict(), indent=2).encode())
    text = render(result, figures, added)
    missing = [f for f in linked_files(text) if not (out / f).is_file()]
    if missing:
        raise RuntimeError(f"report links files that were not written: {missing}")
    atomic_write_bytes(out / "report.html", text.encode())
    return result


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
    :func:`~sigmapi.experiments.executor.run_jobs`); ``(run, header, arrays)`` of the model."""
    from sigmapi.curves import LearningCurve, checkpoints

    cfg = job.cfg
    model = SigmaPiSOM(cfg, seed=job.seed)
    callback, bar = progress_callback(
        cfg.iterations, f"{job.name} seed {job.seed}", disable=not job.progress or None
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
    runs_of: Sequence[tuple[str, SOMConfig]], opts: ReproduceOptions
) -> dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]]:
    """Train every (preset, seed), in parallel where cores and memory allow."""
    jobs = [(f"{name} seed {seed}", SeedJob(name, cfg, seed, opts.n_checkpoints,
                                            opts.curve_test, opts.test_size))
            for name, cfg in runs_of for seed in opts.seeds]  # fmt: skip
    per_job = max(job_memory(cfg, opts.test_size) for _, cfg in runs_of)
    plan = plan_workers(opts.workers, per_job, n_jobs=len(jobs))
    if plan.workers == 1:  # in this process, with a bar per run
        jobs = [(key, replace(job, progress=opts.progress)) for key, job in jobs]
    elif opts.progress:
        print(f"reproduce: {len(jobs)} training runs, {plan.reason}", file=sys.stderr)
    done, bar = jobs_done(len(jobs), "reproduce", disable=not opts.progress or plan.workers == 1)
    finished: dict[str, tuple[SeedRun, SigmaPiSOM]] = {}
    with bar:
        for o in run_jobs(train_seed, jobs, workers=plan.workers):
            if not o.ok:
                raise RuntimeError(f"training {o.key} failed: {o.error}")
            run, header, arrays = o.value
            finished[o.key] = (run, SigmaPiSOM.from_arrays(header, arrays, source=o.key))
            m = run.metrics
            done(True, f"{o.key}: {run.train_seconds:.0f} s, order R^2 {m.order_r2:.3f}"
                       f"{', FOLDED' if m.folded else ''}")  # fmt: skip
    out: dict[str, tuple[list[SeedRun], list[SigmaPiSOM]]] = {}
    for name, _ in runs_of:
        pairs = [finished[f"{name} seed {seed}"] for seed in opts.seeds]
        out[name] = ([p[0] for p in pairs], [p[1] for p in pairs])
    return out


def _draw(
    run: figs.RunInfo, model: SigmaPiSOM, entry: PresetResult, out: Path, progress: bool
) -> list[tuple[str, str]]:
    """Draw every figure of one preset into ``out``; ``(file, caption)`` per figure.

    The facts each caption states are stored in ``entry.figures``.
    """
    from sigmapi.analysis import receptive_field_centres

    centres = receptive_field_centres(model, seed=0)
    curves = [r.curve for r in entry.runs]
    seeds = run.seeds
    drawn = []
    bar = each(figs.FIGURES, f"{run.preset} figures", disable=not progress or None)
    for fig_name in bar:
        file = f"{fig_name}-{run.preset}.png"
        label = f"{run.preset}, seed {seeds[run.shown]}"
        if fig_name == "curves":
            label = (
                f"{run.preset}, seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}"
            )
        facts = figs.draw_figure(fig_name, model, out / file, curves=curves,
                                 reference=_reference(run.preset), label=label,
                                 centres=centres)  # fmt: skip
        entry.figures[fig_name] = {"file": file, **facts}
        drawn.append((file, figs.caption(fig_name, run, facts)))
    return drawn
