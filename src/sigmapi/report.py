"""The reproduction report: ``sigmapi reproduce --out DIR``, the project's main job.

Trains the paper presets (``paper-1d``, and ``paper-2d`` where that preset ships) for a few
seeds, recording learning curves at checkpoints, evaluates them, draws the figures of the
paper and writes into ``DIR``:

- ``report.html``: self-contained (it links only the PNG files beside it), with the measured
  metrics beside the reference figures of ALGORITHM.md and a caption per figure;
- ``metrics.json``: every number of the report (metrics per seed, learning curves, facts shown
  in the captions);
- the figures, ``<figure>-<preset>.png`` for the figures of :data:`FIGURES`;
- the trained models, ``<preset>-seed<S>.npz``: by default the one the figures show (the
  best-ordered seed; ``sigmapi figure`` redraws from it), or every seed's, or none
  (``--models shown|all|none``; a paper-2d model file is about 140 MB).

``sigmapi figure NAME MODEL --out FILE`` draws one of the figures for a model file.

Other parts of the package add sections to the report: a module named in
:data:`SECTION_MODULES` that imports offers ``report_section(ctx: ReportContext) -> Section |
None`` (e.g. the reach experiment of ``sigmapi.reach``); the report never depends on them.
"""

from __future__ import annotations

import argparse
import html
import importlib
import json
import re
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.io import atomic_write_bytes
from sigmapi.metrics import evaluate

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from sigmapi.som import SigmaPiSOM

__all__ = [
    "FIGURES",
    "QUICK_ITERATIONS",
    "REFERENCE",
    "SECTION_MODULES",
    "ReportContext",
    "Section",
    "draw_figure",
    "linked_files",
    "register",
    "reproduce",
]

REFERENCE: dict[str, dict[str, float]] = {
    "paper-1d": {"view_consistency": 0.87, "view_within_one": 0.988, "z_error": 0.32},
}
"""Reference figures of ALGORITHM.md (the authors' 1-D script re-stated in NumPy, 4 seeds)."""

Z_ERROR_FLOOR: dict[str, float] = {"paper-1d": 0.27}
"""Smallest z error a map of that many units can reach (quantisation into 15 units)."""

PAPER_PRESETS = ("paper-1d", "paper-2d")

QUICK_ITERATIONS: dict[str, int] = {"paper-1d": 60_000, "paper-2d": 6_000}
"""Iterations of each preset in ``--quick`` runs (the schedule is compressed to fit)."""

FIGURES = ("fig8", "weights", "net", "invariance", "curves")
"""Names of the figures (``sigmapi figure NAME``), in report order."""

SECTION_MODULES = ("sigmapi.reach.report",)
"""Modules that may add a report section (``report_section(ctx)``); skipped if absent."""

N_CHECKPOINTS = 20
"""Checkpoints of the learning curves per run (log-spaced); ``--quick``: :data:`QUICK_SIZES`."""

CURVE_TEST = 1000
"""Test (and calibration) set size at each learning-curve checkpoint."""

QUICK_SIZES = {"n_checkpoints": 12, "curve_test": 300, "n_test": 2000}
"""Smaller measurements of ``--quick`` runs (checkpoints, their test sets, the final test set)."""

DPI = 100


# ----------------------------------------------------------------------------- sections


@dataclass(frozen=True)
class Section:
    """A section of the report.

    Attributes
    ----------
    title : str
        Heading (plain text; escaped).
    html : str
        Body, an HTML fragment (trusted: write it with :func:`html.escape` on your values).
    figures : list of (str, str)
        ``(file name relative to the report folder, caption)`` per image; the files must
        exist when the report is written.
    data : dict
        Numbers to store in ``metrics.json`` under ``sections[title]``.
    """

    title: str
    html: str = ""
    figures: list[tuple[str, str]] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)


@dataclass
class ReportContext:
    """What a section module gets: the report folder, the run settings and the trained models.

    ``models`` maps each preset name to its trained models, one per seed (in ``seeds`` order).
    """

    out: Path
    quick: bool
    seeds: list[int]
    progress: bool
    models: dict[str, list[SigmaPiSOM]]
    results: dict[str, Any]


# ----------------------------------------------------------------------------- figures


def _figure(size: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=size)


def _save(fig: Figure, path: Path, tight: bool = True) -> None:
    """Write ``fig``; ``tight=False`` for figures whose panels already fill the canvas."""
    fig.savefig(Path(path), dpi=DPI, bbox_inches="tight" if tight else None, facecolor="white")


def sigma_schedule(model: SigmaPiSOM, n: int = 400) -> tuple[list[float], list[float]]:
    """``(t, sigma)`` of the model's whole neighbourhood schedule, for the curves figure."""
    t = np.unique(np.geomspace(1, model.config.iterations, n).round().astype(np.int64))
    return t.astype(float).tolist(), np.asarray(model.sigma_at(t), dtype=float).tolist()


def draw_figure(
    name: str,
    model: SigmaPiSOM,
    path: str | Path,
    *,
    curves: Sequence[dict[str, list[float]]] | None = None,
    reference: dict[str, float] | None = None,
    label: str = "",
    seed: int = 0,
    centres: Any = None,
) -> dict[str, Any]:
    """Draw figure ``name`` (one of :data:`FIGURES`) of ``model`` into ``path``.

    ``curves`` (learning-curve columns, one mapping per seed) is needed for ``"curves"``;
    ``reference`` adds reference lines to it; ``label`` names the model in titles; ``seed``
    draws the Fig. 8 inputs and the receptive-field sampling; ``centres`` reuses computed
    receptive-field centres. Returns the facts the caption states (JSON-able).
    """
    from sigmapi import analysis, plots

    if name not in FIGURES:
        raise ValueError(f"figure name must be one of {FIGURES}, got {name!r}")
    tag = f" ({label})" if label else ""
    d = len(model.x_shape)
    need_centres = name in ("fig8", "net") or (name == "invariance" and d == 2)
    if centres is None and need_centres:
        centres = analysis.receptive_field_centres(model, seed)
    facts: dict[str, Any] = {}
    if name == "fig8":
        data = analysis.fig8_data(model, seed, centres=centres)
        fig = _figure((11.0, 5.6) if d == 2 else (12.0, 5.2))
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        zs = ", ".join(f"{v:.2f}" for v in data.z)
        plots.plot_fig8(
            data, ax=ax,
            title=f"Fig. 8{tag}\nleft: map response h to {data.n_pairs} (x, y) pairs with the "
            f"same z = ({zs}); right: to patterns\nmap polarity: {data.polarity.name}",
        )  # fmt: skip
        facts = {
            "z": data.z.tolist(),
            "polarity": data.polarity.name,
            "polarity_r2": data.polarity.r2,
            "invariance_spread": data.invariance_spread,
        }
    elif name == "weights":
        if d == 1:
            tiles = analysis.weight_tiles(model)
            k = tiles.shape[0]
            fig = _figure((max(6.0, 1.1 * np.ceil(k / np.ceil(np.sqrt(k / 2.0))) + 2.0), 4.8))
            plots.plot_weight_tiles(
                tiles, model.map_shape, ax=fig.add_subplot(),
                title=f"Sigma-Pi weights w_kij of each map unit k{tag} (Fig. 6a):\nan invariant "
                "unit has its weight on an anti-diagonal i + j = const",
            )  # fmt: skip
        else:
            fig = _figure((16.0, 7.6))
            axes = fig.subplots(1, 2, gridspec_kw={"wspace": 0.3})
            for a, ax in enumerate(axes):
                other = 1 - a
                plots.plot_weight_tiles(
                    analysis.weight_tiles(model, axis=a), model.map_shape, ax=ax,
                    title=f"weights of every unit{tag}, summed over axis {other} of x and y:\n"
                    f"x{a} against y{a}; anti-diagonals = invariance along axis {a}",
                    x_label=f"x{a} unit", y_label=f"y{a} unit",
                )  # fmt: skip
        facts = {"weight_abs_max": float(np.abs(model.weights_).max())}
    elif name == "net":
        fig = _figure((6.4, 4.4) if d == 1 else (7.4, 6.0))
        plots.plot_net(
            np.asarray(centres), model.map_shape, ax=fig.add_subplot(),
            z_range=model.sampler.relation.z_range,
            title=f"The map in input space{tag}:\neach unit at the z it responds to",
        )  # fmt: skip
        pol = analysis.map_polarity(model, centres=centres)
        facts = {"polarity": pol.name, "order_r2_centres": pol.r2}
    elif name == "invariance":
        if d == 1:
            inv = analysis.invariance_matrix(model)
            fig = _figure((6.0, 5.0))
            plots.plot_invariance(inv, ax=fig.add_subplot())
            facts = {"constancy": inv.constancy}
        else:
            fig = _figure((12.0, 5.0))
            axes = fig.subplots(1, 2, gridspec_kw={"wspace": 0.3})
            facts = {}
            for a, ax in enumerate(axes):
                inv = analysis.invariance_matrix(model, axis=a, centres=centres)
                plots.plot_invariance(
                    inv, ax=ax,
                    title=f"Winner as a function of x{a} and y{a} (x{1 - a}, y{1 - a} at 0.5)"
                    f"\n{100 * inv.constancy:.1f} % of cells agree with their anti-diagonal",
                )  # fmt: skip
                facts[f"constancy_axis{a}"] = inv.constancy
    else:  # curves
        if not curves:
            raise ValueError("the curves figure needs learning curves (curves=...)")
        fig = _figure((8.5, 9.0))
        plots.plot_learning_curves(
            curves, ax=fig.add_axes((0.0, 0.0, 1.0, 1.0)), reference=reference,
            schedule=sigma_schedule(model),
            title=f"Learning curves{tag}, measured at {len(curves[0]['t'])} checkpoints",
        )  # fmt: skip
        facts = {
            "checkpoints": len(curves[0]["t"]),
            "final": {k: v[-1] for k, v in curves[0].items()},
        }
    _save(fig, Path(path), tight=name not in ("fig8", "curves"))
    return facts


# ----------------------------------------------------------------------------- the run


def _presets(quick: bool) -> list[tuple[str, SOMConfig]]:
    out: list[tuple[str, SOMConfig]] = []
    for name in (n for n in PAPER_PRESETS if n in list_presets()):
        cfg = load_preset(name)
        if quick:
            it = QUICK_ITERATIONS.get(name, max(1000, cfg.iterations // 10))
            cfg = cfg.replace(iterations=min(cfg.iterations, it))
        out.append((name, cfg))
    return out


def _reference(name: str) -> dict[str, float]:
    ref = dict(REFERENCE.get(name, {}))
    if name in Z_ERROR_FLOOR:
        ref["z_error_floor"] = Z_ERROR_FLOOR[name]
    return ref


METRIC_KEYS = ("view_consistency", "view_within_one", "z_error", "order_r2", "usage")


def reproduce(
    out: Path,
    seeds: list[int],
    quick: bool = False,
    progress: bool = True,
    presets: list[tuple[str, SOMConfig]] | None = None,
    save_models: str = "shown",
    n_test: int | None = None,
    sections: tuple[str, ...] | None = None,
) -> dict[str, Any]:
    """Train and evaluate each paper preset for ``seeds``; write the report into ``out``.

    Parameters
    ----------
    out : Path
        Report folder (created).
    seeds : list of int
        Training seeds; figures other than the learning curves show the model of the seed
        with the highest order R^2 (the first on ties), and say which.
    quick : bool
        Fewer iterations per preset (:data:`QUICK_ITERATIONS`), for a first look.
    progress : bool
        Show progress bars on stderr.
    presets : list of (name, SOMConfig), optional
        What to run instead of the paper presets (tests use tiny configs).
    save_models : {"shown", "all", "none"}
        Which trained models to write beside the report: the one the figures show
        (``"shown"``), all, or none.
    n_test : int, optional
        Test set size of the final metrics (default 10,000; ``quick``: 2,000).
    sections : tuple of str, optional
        Modules that add report sections (default :data:`SECTION_MODULES`, the reach
        experiment); ``()`` for none.

    Returns
    -------
    dict
        What ``metrics.json`` holds.
    """
    if save_models not in ("shown", "all", "none"):
        raise ValueError(f"save_models must be 'shown', 'all' or 'none', got {save_models!r}")
    started = time.perf_counter()
    n_points = QUICK_SIZES["n_checkpoints"] if quick else N_CHECKPOINTS
    curve_test = QUICK_SIZES["curve_test"] if quick else CURVE_TEST
    if n_test is None:
        n_test = QUICK_SIZES["n_test"] if quick else 10_000
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs_of = _presets(quick) if presets is None else list(presets)
    results: dict[str, Any] = {
        "quick": quick, "seeds": list(seeds), "n_test": n_test, "curve_test": curve_test,
        "presets": {}, "sections": {},
    }  # fmt: skip
    models: dict[str, list[SigmaPiSOM]] = {}
    figures: dict[str, list[tuple[str, str]]] = {}
    for name, cfg in runs_of:
        runs, models[name] = _train(
            name, cfg, seeds, out, save_models, progress, n_points, curve_test, n_test
        )
        entry: dict[str, Any] = {
            "config": cfg.to_dict(), "runs": runs,
            "mean": {k: statistics.fmean(float(r[k]) for r in runs) for k in METRIC_KEYS},
            "sd": {k: statistics.pstdev(float(r[k]) for r in runs) for k in METRIC_KEYS},
            "reference": REFERENCE.get(name, {}), "z_error_floor": Z_ERROR_FLOOR.get(name),
            "figures": {},
        }  # fmt: skip
        results["presets"][name] = entry
        # figures show the best-ordered seed (the first on ties), and say which
        shown = max(range(len(seeds)), key=lambda i: (runs[i]["order_r2"], -i))
        entry["shown_seed"] = seeds[shown]
        for i, seed in enumerate(seeds):
            if save_models == "all" or (save_models == "shown" and i == shown):
                models[name][i].save(out / f"{name}-seed{seed}.npz")
        figures[name] = _draw(name, cfg, seeds, shown, models[name][shown], entry, out, progress,
                              curve_test)  # fmt: skip
    ctx = ReportContext(out, quick, list(seeds), progress, models, results)
    extra = SECTION_MODULES if sections is None else sections
    sections_done = [s for s in _extra_sections(ctx, extra) if s is not None]
    for s in sections_done:
        results["sections"][s.title] = s.data
    results["total_seconds"] = time.perf_counter() - started
    atomic_write_bytes(out / "metrics.json", json.dumps(results, indent=2).encode())
    text = _html(results, figures, sections_done)
    missing = [f for f in linked_files(text) if not (out / f).is_file()]
    if missing:
        raise RuntimeError(f"report links files that were not written: {missing}")
    atomic_write_bytes(out / "report.html", text.encode())
    return results


def _train(
    name: str,
    cfg: SOMConfig,
    seeds: list[int],
    out: Path,
    save_models: str,
    progress: bool,
    n_points: int,
    curve_test: int,
    n_test: int,
) -> tuple[list[dict[str, Any]], list[SigmaPiSOM]]:
    """Train ``cfg`` once per seed with learning-curve checkpoints; (run records, models)."""
    from sigmapi.analysis import LearningCurve, checkpoints
    from sigmapi.cli import progress_callback
    from sigmapi.som import SigmaPiSOM

    runs: list[dict[str, Any]] = []
    models: list[SigmaPiSOM] = []
    for seed in seeds:
        model = SigmaPiSOM(cfg, seed=seed)
        callback, bar = progress_callback(
            cfg.iterations, f"{name} seed {seed}", disable=not progress or None
        )
        curve = LearningCurve(at=checkpoints(cfg.iterations, n_points), n_test=curve_test,
                              then=callback)  # fmt: skip
        t0 = time.perf_counter()
        with bar:
            model.fit(callback=curve)
        seconds = time.perf_counter() - t0
        metrics = evaluate(model, n_test=n_test).to_dict()
        runs.append({"seed": seed, "train_seconds": seconds, "backend": model.backend,
                     **metrics, "curve": curve.to_dict()})  # fmt: skip
        models.append(model)
    return runs, models


def _draw(
    name: str,
    cfg: SOMConfig,
    seeds: list[int],
    shown: int,
    model: SigmaPiSOM,
    entry: dict[str, Any],
    out: Path,
    progress: bool,
    curve_test: int,
) -> list[tuple[str, str]]:
    """Draw every figure of one preset into ``out``; ``(file, caption)`` per figure.

    The facts each caption states are stored in ``entry["figures"]``.
    """
    from tqdm import tqdm

    from sigmapi.analysis import receptive_field_centres

    centres = receptive_field_centres(model, seed=0)
    curves = [r["curve"] for r in entry["runs"]]
    drawn = []
    bar = tqdm(FIGURES, desc=f"{name} figures", disable=not progress or None, file=sys.stderr,
               leave=False)  # fmt: skip
    for fig_name in bar:
        file = f"{fig_name}-{name}.png"
        label = f"{name}, seed {seeds[shown]}"
        if fig_name == "curves":
            label = f"{name}, seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}"
        facts = draw_figure(fig_name, model, out / file, curves=curves,
                            reference=_reference(name), label=label, centres=centres)  # fmt: skip
        entry["figures"][fig_name] = {"file": file, **facts}
        drawn.append(
            (file, _caption(fig_name, name, cfg, seeds, shown, {**facts, "curve_test": curve_test}))
        )
    return drawn


def _extra_sections(ctx: ReportContext, modules: tuple[str, ...]) -> list[Section | None]:
    """Sections from ``modules`` that are installed (none of them is required)."""
    out: list[Section | None] = []
    for mod_name in modules:
        try:
            module = importlib.import_module(mod_name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and mod_name.startswith(exc.name):
                continue  # that part of the package is not in this build
            out.append(Section(mod_name, f"<p>Section skipped: {html.escape(str(exc))}.</p>"))
            continue
        hook: Callable[[ReportContext], Section | None] | None = getattr(
            module, "report_section", None
        )
        if hook is not None:
            out.append(hook(ctx))
    return out


# ----------------------------------------------------------------------------- HTML


def _caption(
    fig: str, preset: str, cfg: SOMConfig, seeds: list[int], shown: int, facts: dict[str, Any]
) -> str:
    shape = "x".join(map(str, cfg.map_shape)) + ("-unit" if len(cfg.map_shape) == 1 else "")
    d = len(cfg.x_shape)
    which = "" if len(seeds) == 1 else f", the best-ordered of seeds {', '.join(map(str, seeds))}"
    what = f"{preset} ({shape} map, {cfg.iterations:,} iterations, seed {seeds[shown]}{which})"
    if fig == "fig8":
        pattern = 'an "L" on x with a single hill on y (and the reverse)' if d == 2 else (
            "two hills on x with a single hill on y (and the reverse)")  # fmt: skip
        return (
            f"Fig. 8 of the chapter, {what}. Left: four random (x, y) pairs that share one "
            f"body-centred z = ({', '.join(f'{v:.2f}' for v in facts['z'])}); rows x, y and the "
            f"map activation h. The responses agree (largest distance between the normalised "
            f"responses: {facts['invariance_spread']:.2f}, 0 = identical). Right: {pattern}; "
            f"the pattern reappears on the map, {facts['polarity']} relative to the input "
            f"(affine order R² of the receptive-field centres {facts['polarity_r2']:.2f}). "
            "The paper's 2-D run came out rotated by 180 degrees: the orientation is arbitrary "
            "before learning and consistent after it."
        )
    if fig == "weights":
        tiles = "each unit's full 15x15 matrix" if d == 1 else (
            "for each unit, its weights summed over the other axis of x and of y")  # fmt: skip
        return (
            f"Sigma-Pi weights in the style of Fig. 6a, {what}: {tiles}, x on rows and y on "
            "columns. A unit that responds to one z = (x + y) / 2 holds its weight on an "
            "anti-diagonal i + j = const; neighbouring units hold neighbouring anti-diagonals."
        )
    if fig == "net":
        return (
            f"The map in input space, {what}: every unit placed at the z it responds to (centre "
            "of mass of the upper half of its receptive field in z), grid neighbours joined, as "
            f"in the classic SOM net plot. Map polarity: {facts['polarity']} (R² of the affine "
            f"fit of the centres to the grid: {facts['order_r2_centres']:.2f})."
        )
    if fig == "invariance":
        if d == 1:
            score = f"{100 * facts['constancy']:.1f} %"
        else:
            score = " and ".join(f"{100 * facts[f'constancy_axis{a}']:.1f} %" for a in range(d))
        return (
            f"Invariance matrix, {what}: the winning unit for every x and y on the input grid "
            f"(2-D: along one axis, the other at the centre). Constant z lies on the "
            f"anti-diagonals; {score} of the cells agree with the most common winner of their "
            "anti-diagonal (100 % = perfectly invariant)."
        )
    return (
        f"Learning curves of {preset} over seeds {seeds} (thin: each seed, thick: mean), "
        f"measured on {facts['curve_test']} test z's at {facts['checkpoints']} log-spaced "
        "checkpoints: view consistency, z error, the approximate cost of section 6.3 (at the "
        "sigma of the moment, and with the winner alone) and the neighbourhood width sigma with "
        "its schedule. Dashed lines: reference figures of ALGORITHM.md."
    )


_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1150px; margin: 2em auto; padding: 0 1em;
       color: #222; line-height: 1.45; }
table { border-collapse: collapse; margin: 1em 0; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #f0f0f0; } td:first-child, td:nth-child(2) { text-align: left; }
figure { margin: 1.5em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; color: #444; max-width: 60em; }
.good { color: #176117; } .bad { color: #a11; } code { background: #f4f4f4; padding: 0 0.2em; }
"""


_QUICK_NOTE = "<b>quick run</b> (fewer iterations: a first look, not the paper setting)"


def _table(results: dict[str, Any]) -> str:
    rows = []
    for name, res in results["presets"].items():
        ref = res["reference"]
        for key in METRIC_KEYS:
            value, sd = res["mean"][key], res["sd"][key]
            per_seed = ", ".join(f"{float(r[key]):.3f}" for r in res["runs"])
            r = ref.get(key)
            note = ""
            if r is not None:
                better = value <= r * 1.1 if key == "z_error" else value >= r - 0.05
                cls, word = ("good", "close") if better else ("bad", "off")
                note = f"<span class='{cls}'>{word}</span>"
            if key == "z_error" and res.get("z_error_floor") is not None:
                note += f" (floor {res['z_error_floor']:.2f})"
            rows.append(
                f"<tr><td>{html.escape(name)}</td><td>{key}</td><td>{value:.3f} ± {sd:.3f}</td>"
                f"<td>{per_seed}</td><td>{'' if r is None else f'{r:.3f}'}</td><td>{note}</td></tr>"
            )
    return (
        "<table><tr><th>preset</th><th>metric</th><th>measured (mean ± sd over seeds)</th>"
        "<th>per seed</th><th>reference</th><th></th></tr>" + "".join(rows) + "</table>"
    )


def _figure_html(file: str, caption: str) -> str:
    f = html.escape(file, quote=True)
    return (
        f"<figure><a href='{f}'><img src='{f}' alt='{html.escape(caption[:80], quote=True)}'></a>"
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _html(
    results: dict[str, Any], figures: dict[str, list[tuple[str, str]]], sections: list[Section]
) -> str:
    from sigmapi import __version__

    title = "sigmapi reproduction of Weber &amp; Wermter (2007)"
    runs = []
    for name, res in results["presets"].items():
        cfg = res["config"]
        secs = sum(r["train_seconds"] for r in res["runs"])
        runs.append(
            f"<li><b>{html.escape(name)}</b>: map {'x'.join(map(str, cfg['map_shape']))}, inputs "
            f"{'x'.join(map(str, cfg['x_shape']))} + {'x'.join(map(str, cfg['y_shape']))}, "
            f"{cfg['iterations']:,} iterations per seed, backend {res['runs'][0]['backend']}, "
            f"{secs:.0f} s of training in all{_source(cfg)}</li>"
        )
    body = [
        f"<h1>{title}</h1>",
        "<p>C. Weber and S. Wermter, <i>A self-organizing map of Sigma-Pi units</i>, "
        "Neurocomputing 70 (2007) 2552-2560, and section 6 of <i>Neural control of actions "
        "involving different coordinate systems</i> (Humanoid Robots, Human-like Machines, 2007). "
        "A map of Sigma-Pi units learns, without a teacher, to respond to the body-centred "
        "position z = (x + y) / 2 of an object seen at retinal position x with gaze y.</p>",
        f"<p>sigmapi {__version__}; seeds {results['seeds']}; "
        f"{_QUICK_NOTE if results['quick'] else 'full paper runs'}; "
        f"{results['total_seconds']:.0f} s in all.</p><ul>{''.join(runs)}</ul>",
        "<h2>Metrics</h2>",
        "<p>Definitions in ALGORITHM.md: <i>view consistency</i>, the fraction of test z's whose "
        "two independent views give the same winner (and winners within one unit); <i>z error"
        "</i>, RMSE of z decoded from the winner, in input grid spacings; <i>order</i>, R² of an "
        "affine fit from winner coordinates to z; <i>usage</i>, the fraction of units that win. "
        "Reference: the authors' 1-D script re-stated in NumPy, 300,000 iterations, 4 seeds.</p>",
        _table(results),
        "<p>All numbers, per seed, and the learning curves: <a href='metrics.json'>metrics.json"
        "</a>.</p>",
    ]  # fmt: skip
    for name, figs in figures.items():
        body.append(f"<h2>Figures: {html.escape(name)}</h2>")
        body.extend(_figure_html(f, c) for f, c in figs)
    for s in sections:
        body.append(f"<h2>{html.escape(s.title)}</h2>{s.html}")
        body.extend(_figure_html(f, c) for f, c in s.figures)
    return (
        f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{title}</title>"
        f"<style>{_STYLE}</style></head><body>{''.join(body)}</body></html>\n"
    )


def _source(cfg: dict[str, Any]) -> str:
    """The preset's own note on where its values come from, if it has one."""
    extra = cfg.get("extra") or {}
    parts = [str(extra[k]) for k in ("source", "evidence") if extra.get(k)]
    return f"; preset: {html.escape('; '.join(parts))}" if parts else ""


def linked_files(text: str) -> list[str]:
    """The local files an HTML text links (``src`` and ``href`` that are not URLs or anchors)."""
    found = re.findall(r"""(?:src|href)\s*=\s*['"]([^'"]+)['"]""", text)
    local = [html.unescape(f) for f in found if not re.match(r"^(?:[a-z]+:|#|//)", f)]
    return list(dict.fromkeys(local))


# ----------------------------------------------------------------------------- CLI


def cmd_reproduce(args: argparse.Namespace) -> int:
    from sigmapi.cli import UsageError

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is a file; give a folder for the report")
    if out.exists() and any(out.iterdir()) and not args.force:
        raise UsageError(f"--out folder {str(out)!r} is not empty; pass --force to write into it")
    seeds = args.seeds if args.seeds is not None else ([0] if args.quick else [0, 1, 2])
    if any(s < 0 for s in seeds):
        raise UsageError(f"--seeds must be non-negative ints, got {seeds}")
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds must be distinct, got {seeds}")
    results = reproduce(out, seeds=seeds, quick=args.quick, progress=not args.quiet,
                        save_models=args.models)  # fmt: skip
    for name, res in results["presets"].items():
        print(
            f"{name}: " + ", ".join(f"{k} {v:.3f}" for k, v in res["mean"].items()), file=sys.stderr
        )
    print(f"wrote {out / 'report.html'} in {results['total_seconds']:.0f} s", file=sys.stderr)
    return 0


def cmd_figure(args: argparse.Namespace) -> int:
    from sigmapi.analysis import LearningCurve, checkpoints
    from sigmapi.cli import UsageError, check_output, progress_callback
    from sigmapi.io import load_model
    from sigmapi.som import SigmaPiSOM

    out = check_output(args.out, args.force, "--out")
    fmt = out.suffix.lower().lstrip(".")
    allowed = ("png", "pdf", "svg")
    if fmt not in allowed:
        raise UsageError(f"--out must end in one of {['.' + a for a in allowed]}, got {str(out)!r}")
    model = load_model(args.model)
    if not model.is_fitted or model.t_ == 0:
        raise UsageError(f"model {args.model!r} has not been trained (0 iterations)")
    if len(model.x_shape) > 2 or len(model.map_shape) > 2:
        raise UsageError("figures exist for 1-D and 2-D maps and inputs only")
    if args.name == "net" and len(model.map_shape) != len(model.x_shape):
        raise UsageError(
            f"the net figure needs a map with as many dimensions as z; this map is "
            f"{len(model.map_shape)}-D and z is {len(model.x_shape)}-D"
        )
    curves = None
    if args.name == "curves":
        # the training data are a pure function of the seed: re-running the model's schedule
        # from its seed replays the same run, now with checkpoints
        twin = SigmaPiSOM(model.config)
        twin.seed_entropy_ = model.seed_entropy_
        callback, bar = progress_callback(model.t_, "replaying the run", disable=args.quiet or None)
        at = checkpoints(model.t_, N_CHECKPOINTS)
        curve = LearningCurve(at=at, n_test=CURVE_TEST, then=callback)
        with bar:
            twin.fit(model.t_, callback=curve)
        if not np.allclose(twin.weights_, model.weights_, rtol=1e-6, atol=1e-9):
            print("note: the replayed run ended with weights that differ from the file's "
                  "(another backend?); curves show the replay", file=sys.stderr)  # fmt: skip
        curves = [curve.to_dict()]
    label = args.label if args.label is not None else Path(args.model).name
    draw_figure(args.name, model, out, curves=curves, label=label, seed=args.seed)
    print(f"wrote {out}", file=sys.stderr)
    return 0


def register(sub: Any) -> None:
    """Add ``sigmapi reproduce`` and ``sigmapi figure`` to the CLI."""
    p = sub.add_parser("reproduce", help="train the paper presets and write the report")
    p.add_argument("--out", default="report", help="folder for the report (default: ./report)")
    p.add_argument("--seeds", type=int, nargs="+", default=None,
                   help="training seeds (default: 0 1 2; with --quick: 0)")  # fmt: skip
    p.add_argument("--quick", action="store_true",
                   help="a short run for a first look (under a minute): fewer iterations, "
                   "one seed")  # fmt: skip
    p.add_argument("--force", action="store_true", help="write into a non-empty --out folder")
    p.add_argument("--models", choices=["shown", "all", "none"], default="shown",
                   help="which trained models to save: the one the figures show (default; the "
                   "best-ordered seed), all, or none")  # fmt: skip
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser("figure", help="draw one figure of a trained model")
    p.add_argument("name", choices=FIGURES, help="which figure")
    p.add_argument("model", help="model file written by `sigmapi train` or `sigmapi reproduce`")
    p.add_argument("--out", required=True, help="image file to write (.png, .pdf or .svg)")
    p.add_argument("--seed", type=int, default=0, help="seed of the figure's sampled inputs")
    p.add_argument("--label", help="how titles name the model (default: the file name)")
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    p.add_argument("--quiet", action="store_true", help="no progress bar (curves replay the run)")
    p.set_defaults(func=cmd_figure)
