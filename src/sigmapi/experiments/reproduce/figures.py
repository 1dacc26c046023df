"""The report's figures of one preset: which seed they show (:func:`figure_seed`) and the
drawing of every figure with its caption (:func:`draw_preset`)."""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from pathlib import Path

from sigmapi.config import SOMConfig
from sigmapi.experiments.reproduce.results import PresetResult, SeedRun
from sigmapi.metrics import ORDERED_R2, evaluate
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.viz import figures as figs

__all__ = ["draw_preset", "figure_seed"]


def figure_seed(runs: Sequence[SeedRun], cfg: SOMConfig) -> tuple[int, str]:
    """The run the figures show, and why: the worst-ordered seed (lowest order R^2 of the
    final map, the first on ties).

    For the authors' procedure (random start) the comparison is about twisted maps, so its
    worst-ordered map is the one to see; for sigmapi's, the worst-ordered map is the case a
    reader would doubt (the others are at least as ordered). The reason names the seeds
    and the values it was chosen from.
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


def _table_gap(runs: Sequence[SeedRun], n_test: int) -> dict[str, float]:
    """Median over seeds of each curve's last point minus the table's value (the same map,
    measured on the curves' smaller sets): what the curves caption states."""
    gap = {
        k: statistics.median(r.curve[k][-1] - getattr(r.metrics, k) for r in runs)
        for k in ("z_error", "view_consistency")
    }
    return {**gap, "n_test": n_test}


def _decoding_cause(
    model: SigmaPiSOM, run: SeedRun, curve_test: int, test_size: int
) -> dict[str, object]:
    """The shown map's z error on the table's test z's but with the curves' decoding table
    (their calibration z's): beside the table's and the curve's last point, how much of the
    curve's gap the decoding table's size makes."""
    from sigmapi.analysis.curves import LearningCurve
    from sigmapi.metrics import evaluation_sets

    calibration, _ = evaluation_sets(model, curve_test, LearningCurve.seed)
    _, test = evaluation_sets(model, test_size)
    small = evaluate(model, test=test, calibration=calibration).z_error
    return {
        "seed": run.seed,
        "z_error_curve_table": float(small),
        "z_error_table": float(run.metrics.z_error),
        "z_error_curve": float(run.curve["z_error"][-1]),
    }


def draw_preset(
    run: figs.RunInfo,
    model: SigmaPiSOM,
    entry: PresetResult,
    out: Path,
    dpi: int,
    reference: dict[str, float],
    progress: Progress | None,
    *,
    test_size: int,
    curve_test: int,
) -> list[tuple[str, str]]:
    """Draw every figure of one preset into ``out`` (``reference``: the published values the
    curves mark; ``test_size`` and ``curve_test``: the table's and the curves' evaluation sizes,
    whose gap the curves caption states); ``(file, caption)`` per figure.

    The facts each caption states are stored in ``entry.figures``.
    """
    from sigmapi.analysis.map_data import receptive_field_centres

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
        facts = figs.draw_figure(
            fig_name,
            model,
            out / file,
            curves=curves,
            reference=reference,
            label=label,
            centres=centres,
            dpi=dpi,
            ceiling=entry.ceiling,
        )
        if fig_name == "curves":
            facts["table_gap"] = _table_gap(entry.runs, test_size)
            facts["table_gap"]["decoding"] = _decoding_cause(
                model, entry.runs[run.shown], curve_test, test_size
            )
        entry.figures[fig_name] = {"file": file, **facts}
        drawn.append((file, figs.caption(fig_name, run, facts)))
    return drawn
