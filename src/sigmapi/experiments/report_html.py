"""The HTML of the reproduction report: one self-contained page (it links only files beside it).

:func:`render` turns a :class:`~sigmapi.experiments.results.ReproduceResult`, the captioned
figures and the added sections into the page; :func:`linked_files` lists the local files a
page links (the report checks that each exists before writing it).
"""

from __future__ import annotations

import html
import re
from typing import TYPE_CHECKING

from sigmapi.experiments.results import METRIC_KEYS, ORDERED_R2

if TYPE_CHECKING:
    from sigmapi.config import SOMConfig
    from sigmapi.experiments.results import ReproduceResult, Section

__all__ = ["linked_files", "render"]

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
    "<b>quick run</b> (fewer iterations: a first look, not the paper setting; 2-D maps this "
    "short are ordered but not converged, and the fold detector, which reads within-one and "
    "the topographic error, flags them too)"
)


def _table(result: ReproduceResult) -> str:
    rows = []
    for name, res in result.presets.items():
        ref = res.reference
        mean, sd, med, worst = res.mean(), res.sd(), res.median(), res.worst()
        for key in METRIC_KEYS:
            value = med[key]
            per_seed = ", ".join(_seed_value(r.metric(key), r.metrics.folded) for r in res.runs)
            r = ref.get(key)
            note = ""
            if r is not None:
                better = value <= r * 1.1 if key == "z_error" else value >= r - 0.05
                cls, word = ("good", "close") if better else ("bad", "off")
                note = f"<span class='{cls}'>{word}</span>"
            if key == "z_error" and res.z_error_floor is not None:
                note += f" (floor {res.z_error_floor:.2f})"
            if key == "order_r2":
                n, folded = len(res.runs), res.folded_seeds()
                cls = "good" if res.ordered_count() == n else "bad"
                note += (
                    f"<span class='{cls}'>{res.ordered_count()} of {n} ordered "
                    f"(R<sup>2</sup> &ge; {ORDERED_R2})</span>"
                )
                if folded:
                    note += f"; flagged folded: seed{'s' if len(folded) != 1 else ''} "
                    note += ", ".join(map(str, folded))
                else:
                    note += "; none flagged folded"
            rows.append(
                f"<tr><td>{html.escape(name)}</td><td>{key}</td><td>{value:.3f}</td>"
                f"<td>{worst[key]:.3f}</td><td>{mean[key]:.3f} ± {sd[key]:.3f}</td>"
                f"<td>{per_seed}</td><td>{'' if r is None else f'{r:.3f}'}</td>"
                f"<td>{note}</td></tr>"
            )
    return (
        "<table><tr><th>run</th><th>metric</th><th>median</th><th>worst seed</th>"
        "<th>mean ± sd</th><th>per seed (<b>bold</b>: flagged folded)</th><th>reference</th>"
        "<th></th></tr>" + "".join(rows) + "</table>"
    )


def _seed_value(value: float, folded: bool) -> str:
    return f"<b>{value:.3f}</b>" if folded else f"{value:.3f}"


def _figure_html(file: str, caption: str) -> str:
    f = html.escape(file, quote=True)
    return (
        f"<figure><a href='{f}'><img src='{f}' alt='{html.escape(caption[:80], quote=True)}'></a>"
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _source(cfg: SOMConfig) -> str:
    """The preset's own note on where its values come from, if it has one."""
    extra = cfg.extra or {}
    parts = [str(extra[k]) for k in ("source", "evidence") if extra.get(k)]
    return f"; preset: {html.escape('; '.join(parts))}" if parts else ""


def render(
    result: ReproduceResult, figures: dict[str, list[tuple[str, str]]], sections: list[Section]
) -> str:
    """The report page: metrics table, figures per preset (``(file, caption)``), sections."""
    from sigmapi._version import __version__

    title = "sigmapi reproduction of Weber &amp; Wermter (2007)"
    runs = []
    for name, res in result.presets.items():
        cfg = res.config
        secs = sum(r.train_seconds for r in res.runs)
        runs.append(
            f"<li><b>{html.escape(name)}</b>: map {'x'.join(map(str, cfg.map_shape))}, inputs "
            f"{'x'.join(map(str, cfg.x_shape))} + {'x'.join(map(str, cfg.y_shape))}, "
            f"{cfg.iterations:,} iterations per seed, {_PROCEDURE[cfg.ordering]}, "
            f"backend {res.runs[0].backend}, "
            f"{secs:.0f} s of training in all{_source(cfg)}</li>"
        )
    opts = result.options
    body = [
        f"<h1>{title}</h1>",
        "<p>C. Weber and S. Wermter, <i>A self-organizing map of Sigma-Pi units</i>, "
        "Neurocomputing 70 (2007) 2552-2560, and section 6 of <i>Neural control of actions "
        "involving different coordinate systems</i> (Humanoid Robots, Human-like Machines, 2007). "
        "A map of Sigma-Pi units learns, without a teacher, to respond to the body-centred "
        "position z = (x + y) / 2 of an object seen at retinal position x with gaze y.</p>",
        f"<p>sigmapi {__version__}; seeds {list(opts.seeds)}; "
        f"{_QUICK_NOTE if opts.quick else 'full paper runs'}; "
        f"{result.total_seconds:.0f} s in all.</p><ul>{''.join(runs)}</ul>",
        "<h2>Metrics</h2>",
        "<p>Definitions in docs/algorithm.md: <i>view consistency</i>, the fraction of test z's "
        "whose two independent views give the same winner (and winners within one unit); <i>z "
        "error</i>, RMSE of z decoded from the winner, in input grid spacings; <i>order</i>, R² "
        "of an affine fit from winner coordinates to z; <i>usage</i>, the fraction of units that "
        "win. Reference: the authors' 1-D script re-stated in NumPy, 300,000 iterations, 4 "
        "seeds.</p>",
        _table(result),
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


def linked_files(text: str) -> list[str]:
    """The local files an HTML text links (``src`` and ``href`` that are not URLs or anchors)."""
    found = re.findall(r"""(?:src|href)\s*=\s*['"]([^'"]+)['"]""", text)
    local = [html.unescape(f) for f in found if not re.match(r"^(?:[a-z]+:|#|//)", f)]
    return list(dict.fromkeys(local))
