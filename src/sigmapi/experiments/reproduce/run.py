"""The reproduction run: ``sigmapi reproduce --out DIR`` (:class:`Reproduce`, :func:`reproduce`),
the project's main job: the paper presets beside the authors' procedure (:func:`paper_presets`),
one job per (preset, seed) (:mod:`~sigmapi.experiments.reproduce.training`), the rule's ceiling
once per task, and the report (:mod:`~sigmapi.experiments.reproduce.report_html`) with
``metrics.json``, the figures of the seed :func:`figure_seed` chooses, the models
``save_models`` names and the sections experiments add (:data:`SECTIONS`), each file described
in docs/guide/reproduce.md.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import statistics
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor
from sigmapi.experiments.base import Experiment, Run, register
from sigmapi.experiments.kit.report import ReportContext, Section, SectionFn, section_function
from sigmapi.experiments.reproduce.report_html import linked_files, render
from sigmapi.experiments.reproduce.results import (
    OTHER_PROCEDURE,
    REPORT,
    PresetResult,
    ReproduceConfig,
    ReproduceOptions,
    ReproduceResult,
    SeedRun,
)
from sigmapi.experiments.reproduce.training import train_all
from sigmapi.io import atomic_write_bytes
from sigmapi.metrics import ORDERED_R2, evaluate
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.viz import figures as figs

REFERENCE: dict[str, dict[str, float]] = {
    name: {"view_consistency": 0.87, "view_within_one": 0.988, "z_error": 0.32}
    for name in ("paper-1d", "paper-1d-authors")
}
"""Reference figures of docs/algorithm.md (the authors' 1-D script re-stated in NumPy, 4 seeds)."""

Z_ERROR_FLOOR: dict[str, float] = dict.fromkeys(("paper-1d", "paper-1d-authors"), 0.27)
"""Smallest z error a map of that many units can reach (quantisation into 15 units)."""

PAPER_PRESETS = ("paper-1d", "paper-2d")

QUICK_REFINE_PAIRS = 20_000
"""Refinement pairs per round in quick runs."""

QUICK_ITERATIONS: dict[str, int] = {"paper-1d": 60_000, "paper-2d": 20_000}
"""Iterations of each preset in quick runs (the schedule compressed to fit): paper-2d's map
orders but does not converge (the fold detector may flag it); much shorter, it stays twisted."""

CEILING_ROUNDS = 8
"""At most this many rounds of the fixed-point search for the ceiling (quick runs:
:data:`QUICK_CEILING_ROUNDS`); each round of the 2-D task costs seconds."""
QUICK_CEILING_ROUNDS = 3

SECTIONS: tuple[str | SectionFn, ...] = ("sigmapi.experiments.reach.section:reach_section",)
"""The sections every full report adds after the figures (the reach experiment's): a function
``section(ctx: ReportContext) -> Section | None`` (:mod:`sigmapi.experiments.kit.report`) or
its ``"module:function"`` (imported when the report runs, as experiments are); a section draws
holding ``ctx.drawing``."""


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


def figure_seed(runs: Sequence[SeedRun], cfg: SOMConfig) -> tuple[int, str]:
    """The run the figures show, and why (naming the seeds and values it was chosen from):
    the worst-ordered seed (lowest order R^2 of the final map, the first on ties), for the
    authors' procedure the twisted map the comparison is about, for sigmapi's the map to doubt.
    """
    i = min(range(len(runs)), key=lambda j: (runs[j].metrics.order_r2, j))
    r2 = runs[i].metrics.order_r2
    if len(runs) == 1:
        return i, f"its only seed (order R² {r2:.3f})"
    n_twisted = sum(r.metrics.order_r2 < ORDERED_R2 for r in runs)
    authors = cfg.ordering == "none"
    if r2 < ORDERED_R2:
        state = (
            f"twisted (order R² {r2:.3f} < {ORDERED_R2}; {n_twisted} of {len(runs)} seeds twisted)"
        )
        what = "the comparison is about twisting" if authors else "the map to doubt"
    else:
        state = f"still ordered (order R² {r2:.3f}; every seed ≥ {ORDERED_R2})"
        what = (
            "no seed twisted here; the comparison is about twisting, so the least ordered"
            if authors
            else "the others are at least as ordered"
        )
    return i, f"the worst-ordered of its {len(runs)} seeds, {state}: {what}"


def _table_gap(
    model: SigmaPiSOM, runs: Sequence[SeedRun], shown: int, opts: ReproduceOptions
) -> dict[str, object]:
    """What the curves caption states: the median over seeds of each curve's last point minus
    the table's value (the same map, measured on the curves' smaller sets), and how much of it
    the decoding table's size makes (``decoding``): the shown map's z error on the table's
    test z's but with the curves' decoding table (their calibration z's)."""
    from sigmapi.analysis.curves import LearningCurve
    from sigmapi.metrics import evaluation_sets

    gap = {
        k: statistics.median(r.curve[k][-1] - getattr(r.metrics, k) for r in runs)
        for k in ("z_error", "view_consistency")
    }
    calibration, _ = evaluation_sets(model, opts.curve_test, LearningCurve.seed)
    _, test = evaluation_sets(model, opts.test_size)
    small = evaluate(model, test=test, calibration=calibration).z_error
    run = runs[shown]
    decoding = {
        "seed": run.seed,
        "z_error_curve_table": float(small),
        "z_error_table": float(run.metrics.z_error),
        "z_error_curve": float(run.curve["z_error"][-1]),
    }
    return {**gap, "n_test": opts.test_size, "decoding": decoding}


def reproduce(
    out: Path,
    options: ReproduceOptions | None = None,
    *,
    presets: Sequence[tuple[str, SOMConfig]] | None = None,
    sections: Sequence[str | SectionFn] | None = None,
    executor: Executor | None = None,
) -> ReproduceResult:
    """Train and evaluate each paper preset for the seeds of ``options`` and write the report
    into the folder ``out`` (created); the result is what ``metrics.json`` holds.

    ``presets`` run instead of the paper presets (tests use tiny configs); ``sections`` add
    report sections (default :data:`SECTIONS`; ``()`` for none); ``executor`` runs the
    training (default: this machine, ``options.workers`` at once).
    """
    opts = options or ReproduceOptions()
    ex = executor if executor is not None else Executor(workers=opts.workers)
    started = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs_of = paper_presets(opts.quick) if presets is None else list(presets)
    result = ReproduceResult(opts, out=out)
    progress = Progress() if opts.progress else None
    figures: dict[str, list[tuple[str, str]]] = {}
    trained = train_all(runs_of, opts, ex, progress)
    ctx = ReportContext(out, opts, {name: trained[name][1] for name, _ in runs_of})
    section_fns = [section_function(s) for s in (SECTIONS if sections is None else sections)]
    sectioned = _in_background(lambda: [fn(ctx) for fn in section_fns])  # beside the figures
    try:
        for name, cfg in runs_of:
            figures[name] = _report_preset(name, cfg, trained[name][0], ctx, result, progress)
        added = [s for s in sectioned.result() if s]
    except BaseException:  # an error or an interrupt: end the sections' workers now (the
        # training's have ended), so that their jobs fail at once instead of holding up the exit
        for child in multiprocessing.active_children():
            child.terminate()
        raise
    result.sections.update({s.title: s.data for s in added})
    drawn = [*figures.values(), *(s.figures for s in added)]
    result.figure_files += [out / file for files in drawn for file, _ in files]
    result.total_seconds = time.perf_counter() - started
    atomic_write_bytes(out / "metrics.json", json.dumps(result.to_dict(), indent=2).encode())
    text = render(result, figures, added)
    missing = [f for f in linked_files(text) if not (out / f).is_file()]
    if missing:
        raise RuntimeError(f"report links files that were not written: {missing}")
    atomic_write_bytes(out / REPORT, text.encode())
    return result


def _report_preset(
    name: str,
    cfg: SOMConfig,
    runs: list[SeedRun],
    ctx: ReportContext,
    result: ReproduceResult,
    progress: Progress | None,
) -> list[tuple[str, str]]:
    """Preset ``name``'s entry of ``result`` (statistics, the ceiling), its saved models and
    its figures at the options' dpi, drawn holding ``ctx.drawing``: ``(file, caption)`` per
    figure; the facts each caption states go into the entry's ``figures`` (the curves mark
    the published values and state the gap between the table's and the curves' test sets)."""
    from sigmapi.analysis.map_data import receptive_field_centres

    opts, models = result.options, ctx.models[name]
    shown, why = figure_seed(runs, cfg)
    seeds, model = opts.seeds_of(cfg), models[shown]
    entry = PresetResult(
        cfg, runs, REFERENCE.get(name, {}), Z_ERROR_FLOOR.get(name), seeds[shown], why
    )
    entry.ceiling = _ceiling(name, result, model, seeds[shown], progress)
    result.presets[name] = entry
    for i, seed in enumerate(seeds):
        if opts.save_models == "all" or (opts.save_models == "shown" and i == shown):
            models[i].save(ctx.out / f"{name}-seed{seed}.npz")
    run = figs.RunInfo(name, cfg, seeds, shown, opts.curve_test, why)
    floor = {} if entry.z_error_floor is None else {"z_error_floor": entry.z_error_floor}
    curves = f"{name}, seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}"
    drawn = []
    with ctx.drawing:
        centres = receptive_field_centres(model, seed=0)
        for fig_name in Progress.of(progress).each(figs.FIGURES, f"{name} figures"):
            file = f"{fig_name}-{name}.png"
            facts = figs.draw_figure(
                fig_name,
                model,
                ctx.out / file,
                curves=[r.curve for r in runs],
                reference={**entry.reference, **floor},
                label=curves if fig_name == "curves" else f"{name}, seed {seeds[shown]}",
                centres=centres,
                dpi=opts.dpi,
                ceiling=entry.ceiling,
            )
            if fig_name == "curves":
                facts["table_gap"] = _table_gap(model, runs, shown, opts)
            entry.figures[fig_name] = {"file": file, **facts}
            drawn.append((file, figs.caption(fig_name, run, facts)))
    return drawn


def _in_background(fn: Callable[[], list[Section | None]]) -> Future[list[Section | None]]:
    """``fn()`` run in a daemon thread from now on; the future of its value (or error). The
    sections (the reach experiment: its seeds in a process pool) run so beside the ceilings
    and the figures, whose drawing leaves a core idle. A daemon thread: an interrupted report
    does not wait for it (its pool's workers end with this process)."""
    future: Future[list[Section | None]] = Future()

    def run() -> None:
        try:
            future.set_result(fn())
        except BaseException as e:  # raised again in the caller's thread by result()
            future.set_exception(e)

    threading.Thread(target=run, daemon=True).start()
    return future


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
    quick_time = "about 50 s on two cores, numba's cache empty"
    default_out = "report"

    def execute(self, config: ReproduceConfig, run: Run) -> ReproduceResult:
        """:func:`reproduce` into ``out`` (required: the report's folder)."""
        if run.out is None:
            raise ConfigError("out must be the report's folder, got None; e.g. Path('report')")
        ex = run.executor if run.executor is not None else Executor(workers=1)
        fields = {f.name: getattr(config, f.name) for f in dataclasses.fields(ReproduceConfig)}
        shown = Progress.of(run.progress).enabled
        opts = ReproduceOptions(**fields, seeds=run.seeds, progress=shown, workers=ex.workers)
        return reproduce(run.out, opts, executor=ex)


REPRODUCE = register(Reproduce())


def _ceiling(
    name: str, result: ReproduceResult, model: SigmaPiSOM, seed: int, progress: Progress | None
) -> dict[str, Any]:
    """The rule's ceiling for preset ``name``: its twin's (same task) when the twin ran
    first, else the fixed point reached from ``model``
    (:func:`sigmapi.analysis.fixed_point.fixed_point`)."""
    from sigmapi.analysis.fixed_point import fixed_point

    opts = result.options
    rounds = QUICK_CEILING_ROUNDS if opts.quick else CEILING_ROUNDS
    twin = result.presets.get(next((t for t, o in OTHER_PROCEDURE.items() if o == name), ""))
    if twin is not None and twin.ceiling is not None:
        return twin.ceiling
    t0 = time.perf_counter()
    for _ in Progress.of(progress).each([name], f"{name} ceiling (fixed point of Eq. 7)"):
        # one BLAS thread: the sections' workers run beside it, and BLAS threads that wait
        # for a busy core cost CPU for nothing (the same numbers: BLAS splits the products
        # by rows, not by the sums)
        with threadpool_limits(limits=1, user_api="blas"):
            found = fixed_point(model, n_test=opts.test_size, max_rounds=rounds)
    return {**found.to_dict(), "preset": name, "seed": seed, "seconds": time.perf_counter() - t0}
