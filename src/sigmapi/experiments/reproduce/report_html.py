"""The HTML of the reproduction report (:func:`render`): one self-contained page, which links
only files beside it (:func:`linked_files`: the report checks that each exists).
"""

from __future__ import annotations

import html
import re
from collections.abc import Iterable
from typing import TYPE_CHECKING

from sigmapi.experiments.reproduce.results import METRIC_KEYS, ORDERED_R2, OTHER_PROCEDURE, plural
from sigmapi.metrics import FOLD_THRESHOLD

if TYPE_CHECKING:
    from sigmapi.experiments.kit.report import Section
    from sigmapi.experiments.reproduce.results import PresetResult, ReproduceResult, Stage

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

_PROCEDURE = {
    "none": "ordering <code>none</code> (the paper's random start and schedule)",
    "crossview": "ordering <code>crossview</code> (sigmapi's ordered start from the views)",
}

_QUICK_NOTE = (
    "<b>quick run</b> (fewer iterations: a first look, not the paper setting; maps this short "
    "are ordered but not converged, and the fold detector flags some of them: its signs, "
    "views of one z won by distant units, also mark a coarse map)"
)


_LABEL = {
    "view_consistency": "view consistency",
    "view_within_one": "view within one",
    "z_error": "z error (grid spacings)",
    "order_r2": "order R²",
    "usage": "usage",
    "fold_score": (
        "fold score<br><small>starved units, or the far-apart views over their limit; "
        f"folded at &ge; {FOLD_THRESHOLD:g}</small>"
    ),
}


def _html_table(head: Iterable[str], rows: Iterable[Iterable[str]]) -> str:
    """A table of the header's cells and a row of cells per row (each cell HTML already)."""
    cells = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return "<table><tr>" + "".join(f"<th>{h}</th>" for h in head) + f"</tr>{cells}</table>"


def _summary(result: ReproduceResult) -> str:
    """Per task, one table: sigmapi's map after and before its refinement (the same runs),
    the authors' procedure, the rule's ceiling and the paper's reference, side by side."""
    out = []
    twins = {OTHER_PROCEDURE.get(name) for name in result.presets}  # beside their presets
    for name in (n for n in result.presets if n not in twins):
        group = [n for n in (name, OTHER_PROCEDURE.get(name)) if n in result.presets]
        first = result.presets[name]
        ceiling, ref = first.ceiling, first.reference
        cols = [_column(n, result.presets[n], s) for n in group for s in result.presets[n].stages()]
        if ceiling is not None:
            at = f"fixed point from {html.escape(ceiling['preset'])} seed {ceiling['seed']}"
            values = (f"{float(ceiling[k]):.3f}" if k in ceiling else "" for k in METRIC_KEYS)
            cols.append([f"the rule's ceiling<br>{at}", *values, ""])
        if ref:
            floor = first.z_error_floor
            notes = {} if floor is None else {"z_error": f" (floor {floor:.2f})"}
            values = ((f"{ref[k]:.3f}" if k in ref else "") + notes.get(k, "") for k in METRIC_KEYS)
            cols.append(["reference<br>(docs/algorithm.md)", *values, ""])
        labels = ["median <small>(worst seed)</small>", *(_LABEL[k] for k in METRIC_KEYS)]
        labels.append(f"seeds ordered (R² &ge; {ORDERED_R2})")
        head, *rows = zip(labels, *cols, strict=True)  # the columns as rows
        out.append(_html_table(head, rows))
    return "".join(out)


def _column(name: str, res: PresetResult, stage: Stage) -> list[str]:
    """A preset's column of the summary at ``stage``: its head, its cell per metric (median
    and worst seed), its seeds ordered."""
    n, med = len(res.runs), res.median(stage)
    worst = {k: "" if n == 1 else f" <small>({v:.3f})</small>" for k, v in res.worst(stage).items()}
    what = f"{'refined' if res.refines else 'final map'}, {n} seed{plural(n)}"
    if stage == "unrefined":
        what = "before refinement (same runs)"
    cells = [f"{med[k]:.3f}{worst[k]}" for k in METRIC_KEYS]
    ordered = f"{res.ordered_count(stage)} of {n}{_flagged(res.folded_seeds(stage))}"
    return [f"{html.escape(name)}<br>{what}", *cells, ordered]


def _flagged(seeds: list[int]) -> str:
    if not seeds:
        return ", none flagged folded"
    return f", flagged folded: seed{plural(len(seeds))} {', '.join(map(str, seeds))}"


def _table(result: ReproduceResult) -> str:
    """Every seed's value of every metric, per preset and stage, with the statistics."""
    rows = []
    for name, res in result.presets.items():
        for stage in res.stages():
            label = html.escape(name if stage == "refined" else f"{name}, before refinement")
            mean, sd, n = res.mean(stage), res.sd(stage), len(res.runs)
            med, worst = res.median(stage), res.worst(stage)
            for key in METRIC_KEYS:
                stats = (f"{med[key]:.3f}", f"{worst[key]:.3f}", _mean_sd(mean[key], sd[key], n))
                values = [(f"{r.metric(key, stage):.3f}", r.at(stage).folded) for r in res.runs]
                seeds = ", ".join(f"<b>{v}</b>" if folded else v for v, folded in values)
                ref = f"{res.reference[key]:.3f}" if key in res.reference else ""
                rows.append([label, key, *stats, seeds, ref, _note(res, key, stage)])
    head = ("run", "metric", "median", "worst seed", "mean ± sd",
            "per seed (<b>bold</b>: flagged folded)", "reference", "")  # fmt: skip
    return _html_table(head, rows)


def _note(res: PresetResult, key: str, stage: Stage) -> str:
    """What the per-seed table says beside a metric's median: close to the reference or off,
    the z error's floor, the seeds ordered and flagged folded."""
    r, note = res.reference.get(key), ""
    if r is not None:
        value = res.median(stage)[key]
        better = value <= r * 1.1 if key == "z_error" else value >= r - 0.05
        cls, word = ("good", "close") if better else ("bad", "off")
        note = f"<span class='{cls}'>{word}</span>"
    if key == "z_error" and res.z_error_floor is not None:
        note += f" (floor {res.z_error_floor:.2f})"
    if key == "order_r2":
        n, count = len(res.runs), res.ordered_count(stage)
        cls = "good" if count == n else "bad"
        note += (
            f"<span class='{cls}'>{count} of {n} ordered (R<sup>2</sup> &ge; {ORDERED_R2})</span>"
        ) + _flagged(res.folded_seeds(stage)).replace(", ", "; ", 1)
    return note


def _mean_sd(mean: float, sd: float, n: int) -> str:
    """``mean ± sd`` over seeds; one seed has no spread to show (never "± 0.000")."""
    return f"{mean:.3f} ± {sd:.3f}" if n > 1 else f"{mean:.3f} (one seed)"


def _fewer(result: ReproduceResult) -> str:
    """Which presets trained fewer of the seeds (the 2-D ones: ``seeds_2d``), if any."""
    n = len(result.options.seeds)
    fewer = [(k, len(p.runs)) for k, p in result.presets.items() if len(p.runs) < n]
    text = ", ".join(f"{html.escape(k)}: the first {m}" for k, m in fewer)
    return f" ({text})" if fewer else ""


def _bullet(name: str, res: PresetResult) -> str:
    """One preset's line, every fact computed from its own config and runs: how it trains
    (ordering, training, refinement), its seeds' statistics and times, the seed the figures
    show, and the preset's own note on where its settings come from, if it has one."""
    cfg, n, rounds = res.config, len(res.runs), res.config.refine_rounds
    seeds = ", ".join(str(r.seed) for r in res.runs)
    med, worst = res.median(), res.worst()
    refine = "no refinement"
    if rounds > 0:
        pairs = f"of {cfg.refine_pairs:,} pairs (section 6.3)"
        refine = f"then {rounds} refinement round{plural(rounds)} {pairs}"
    procedure = f"{_PROCEDURE[cfg.ordering]}, {cfg.iterations:,} iterations per seed, {refine}"
    source = (cfg.extra or {}).get("source")
    note = f" Values from: {html.escape(str(source))}." if source else ""
    secs = res.median_seconds()
    times = f"training {secs['train_seconds']:.1f} s"
    if res.refines:
        times += f", refinement {secs['refine_seconds']:.1f} s"
    compiled = sum(r.compile_seconds for r in res.runs)
    if compiled >= 0.5:
        cpu = sum(r.compile_cpu_seconds for r in res.runs)
        times += f"; numba's one-time compile {compiled:.0f} s ({cpu:.0f} CPU s) in all, apart"
    before = res.median("unrefined")["view_consistency"]
    gain = f" (before refinement {before:.3f})" if res.refines else ""
    return (
        f"<li><b>{html.escape(name)}</b>: map {'x'.join(map(str, cfg.map_shape))}, inputs "
        f"{'x'.join(map(str, cfg.x_shape))} + {'x'.join(map(str, cfg.y_shape))}, "
        f"{procedure}; backend {res.runs[0].backend}. "
        f"{n} seed{plural(n)} ({seeds}): {res.ordered_count()} of {n} ordered, "
        f"median view consistency {med['view_consistency']:.3f}{gain}, worst seed "
        f"{worst['view_consistency']:.3f}; per seed (median) {times}. Figures: "
        f"seed {res.shown_seed}, {html.escape(res.shown_reason)}.{note}</li>"
    )


def render(
    result: ReproduceResult, figures: dict[str, list[tuple[str, str]]], sections: list[Section]
) -> str:
    """The report page: metrics table, figures per preset (``(file, caption)``), sections."""
    from sigmapi._version import __version__

    title = "sigmapi reproduction of Weber &amp; Wermter (2007)"
    runs = [_bullet(name, res) for name, res in result.presets.items()]
    opts = result.options
    body = [
        f"<h1>{title}</h1>",
        "<p>C. Weber and S. Wermter, <i>A self-organizing map of Sigma-Pi units</i>, "
        "Neurocomputing 70 (2007) 2552-2560, and section 6 of <i>Neural control of actions "
        "involving different coordinate systems</i> (Humanoid Robots, Human-like Machines, 2007). "
        "A map of Sigma-Pi units learns, without a teacher, to respond to the body-centred "
        "position z = (x + y) / 2 of an object seen at retinal position x with gaze y.</p>",
        f"<p>sigmapi {__version__}; seeds {list(opts.seeds)}{_fewer(result)}; "
        f"{_QUICK_NOTE if opts.quick else 'full paper runs'}; "
        f"{result.total_seconds:.0f} s in all.</p><ul>{''.join(runs)}</ul>",
        "<h2>Metrics</h2>",
        "<p>Definitions in docs/algorithm.md: <i>view consistency</i>, the fraction of test z's "
        "whose two independent views give the same winner (and winners within one unit); <i>z "
        "error</i>, RMSE of z decoded from the winner, in input grid spacings; <i>order</i>, R² "
        "of an affine fit from winner coordinates to z; <i>usage</i>, the fraction of units that "
        "win. Reference: the authors' 1-D script re-stated in NumPy, 300,000 iterations, 4 "
        "seeds.</p>",
        "<p>Medians over the seeds, the worst seed in brackets (the largest z error and fold "
        "score, else the smallest value). <i>Before refinement</i>: the same runs' maps at the "
        "end of the training, evaluated there, before the batch refinement of section 6.3. "
        "<i>The rule's ceiling</i>: the fixed point of Eq. 7 (each unit the mean of x' y'^T "
        "over the views it wins, with the winners of those weights) reached from one map of "
        "the task, computed on a grid of z and views without sampling "
        "(sigmapi.analysis.fixed_point): "
        "where the rule's weights go from that map when no noise of a learning rate or of "
        "finitely many pairs is left.</p>",
        _summary(result),
        "<h3>Every seed</h3>",
        _table(result),
        "<p>All numbers, per seed, and the learning curves: <a href='metrics.json'>metrics.json"
        "</a>.</p>",
    ]
    parts = [(f"Figures: {name}", "", figs) for name, figs in figures.items()]
    for heading, text, figs in parts + [(s.title, s.html, s.figures) for s in sections]:
        body.append(f"<h2>{html.escape(heading)}</h2>{text}")
        for file, caption in figs:
            f, alt = html.escape(file, quote=True), html.escape(caption[:80], quote=True)
            body.append(f"<figure><a href='{f}'><img src='{f}' alt='{alt}'></a>")
            body.append(f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    return (
        f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{title}</title>"
        f"<style>{_STYLE}</style></head><body>{''.join(body)}</body></html>\n"
    )


def linked_files(text: str) -> list[str]:
    """The local files an HTML text links (``src`` and ``href`` that are not URLs or anchors)."""
    found = re.findall(r"""(?:src|href)\s*=\s*['"]([^'"]+)['"]""", text)
    local = [html.unescape(f) for f in found if not re.match(r"^(?:[a-z]+:|#|//)", f)]
    return list(dict.fromkeys(local))
