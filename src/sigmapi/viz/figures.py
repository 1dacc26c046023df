# Over 500 lines: the registry of the report's figures, each a draw function and the caption
# computed from its facts, kept beside one another so a figure and its words change together.
"""The figures of the report: a registry from figure name to a draw function and a caption.

:data:`REGISTRY` maps each name of :data:`FIGURES` to a :class:`FigureSpec`: ``draw(model,
inputs)`` returns the matplotlib figure and the facts its caption states (JSON-able), and
``caption(run, facts)`` the caption text. :func:`draw_figure` draws one figure into a file;
:func:`caption` words its caption. A new figure is one more entry, not one more branch.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from sigmapi.metrics import ORDERED_R2, chebyshev

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from sigmapi.config import SOMConfig
    from sigmapi.model.som import SigmaPiSOM

__all__ = [
    "DPI",
    "FIGURES",
    "REGISTRY",
    "DrawInputs",
    "FigureSpec",
    "RunInfo",
    "caption",
    "draw_figure",
    "sigma_schedule",
]

DPI = 100
"""Resolution of raster figures by default (``draw_figure(..., dpi=300)`` for print; a
``.pdf`` or ``.svg`` path gives vector graphics)."""
SAME_RESPONSE = 0.5
"""Fig. 8 caption: responses "agree" when the largest distance between the responses, each
scaled to unit length, is at most this (0 = the same shape; sqrt 2 = 1.41 for non-negative
responses with no unit in common)."""
CURVE_REFERENCES = ("view_consistency", "z_error", "z_error_floor")
"""Reference keys the curves figure draws as lines (plots.plot_learning_curves)."""
CURVE_CEILING = ("view_consistency", "z_error")
"""Metrics of the rule's ceiling the curves figure draws as lines."""

Facts = dict[str, Any]


@dataclass(frozen=True)
class DrawInputs:
    """What a draw function may use besides the model.

    ``curves``: learning-curve columns, one mapping per seed (the curves figure);
    ``reference``: reference lines for it; ``label``: how titles name the model; ``seed``:
    seed of sampled inputs; ``centres``: receptive-field centres (computed when needed);
    ``ceiling``: the rule's ceiling (metrics of :func:`sigmapi.analysis.fixed_point.fixed_point`),
    drawn as lines in the curves.
    """

    curves: Sequence[dict[str, list[float]]] | None = None
    reference: dict[str, float] | None = None
    label: str = ""
    seed: int = 0
    centres: ArrayLike | None = None
    ceiling: Mapping[str, float] | None = None

    @property
    def tag(self) -> str:
        """`` (label)`` for a title: the label as plain text (a ``$`` is no mathtext)."""
        return " (" + self.label.replace("$", r"\$") + ")" if self.label else ""


@dataclass(frozen=True)
class RunInfo:
    """What a caption says about the run: preset, config, seeds, the seed shown (index into
    ``seeds``), test size, and why that seed is shown (computed from the data)."""

    preset: str
    config: SOMConfig
    seeds: tuple[int, ...]
    shown: int
    curve_test: int = 0
    why: str = ""

    @property
    def procedure(self) -> str:
        """The run's training, and its refinement where it has one."""
        cfg = self.config
        refined = (
            f", then {cfg.refine_rounds} x {cfg.refine_pairs:,} refinement pairs"
            if cfg.refine_rounds > 0
            else ", no refinement"
        )
        return f"{cfg.iterations:,} iterations{refined}"

    @property
    def what(self) -> str:
        cfg, seeds = self.config, self.seeds
        shape = "x".join(map(str, cfg.map_shape)) + ("-unit" if len(cfg.map_shape) == 1 else "")
        which = f": {self.why}" if self.why else ""
        return f"{self.preset} ({shape} map, {self.procedure}; seed {seeds[self.shown]}{which})"


@dataclass(frozen=True)
class FigureSpec:
    """One figure: how to draw it, how to caption it, and what it needs."""

    draw: Callable[[SigmaPiSOM, DrawInputs], tuple[Figure, Facts]]
    caption: Callable[[RunInfo, Facts], str]
    needs_centres: Callable[[int], bool] = lambda d: False
    tight: bool = True
    """Crop to the drawn area (False for figures whose panels already fill the canvas)."""


def _figure(size: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=size)


def sigma_schedule(model: SigmaPiSOM, n: int = 400) -> tuple[list[float], list[float]]:
    """``(t, sigma)`` of the model's whole neighbourhood schedule, for the curves figure."""
    t = np.unique(np.geomspace(1, model.config.iterations, n).round().astype(np.int64))
    return t.astype(float).tolist(), np.asarray(model.sigma_at(t), dtype=float).tolist()


# ----------------------------------------------------------------------------- Fig. 8


def _draw_fig8(model: SigmaPiSOM, inp: DrawInputs) -> tuple[Figure, Facts]:
    from sigmapi.analysis import map_data as analysis
    from sigmapi.viz import plots

    d = len(model.x_shape)
    data = analysis.fig8_data(model, inp.seed, centres=inp.centres)
    pairs = slice(0, data.n_pairs)
    winners = model.winner(data.x[pairs], data.y[pairs], hard=True)
    unit, count = np.unique(winners, return_counts=True)
    top = int(unit[np.argmax(count)])
    apart = chebyshev(model.map_coords, winners, np.full_like(winners, top))
    fig = _figure((11.0, 5.6) if d == 2 else (12.0, 5.2))
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    zs = ", ".join(f"{v:.2f}" for v in data.z)
    which = "refined map" if model.refined_ else "map"
    plots.plot_fig8(
        data,
        ax=ax,
        title=f"Fig. 8 of the {which}{inp.tag}\nleft: map response h to {data.n_pairs} (x, y) "
        f"pairs with the same z = ({zs}), the same winner in {int(count.max())} of "
        f"{data.n_pairs}; right: to patterns\nmap polarity: {data.polarity.name}",
    )
    return fig, {
        "z": data.z.tolist(),
        "polarity": data.polarity.name,
        "polarity_r2": data.polarity.r2,
        "invariance_spread": data.invariance_spread,
        "winners": [int(w) for w in winners],
        "same_winner": int(count.max()),
        "within_one": int(np.sum(apart <= 1.0)),
        "refined_pairs": int(model.refined_),
    }


def _caption_fig8(run: RunInfo, facts: Facts) -> str:
    if len(run.config.x_shape) == 2:
        pattern = 'an "L" on x with a single hill on y (and the reverse)'
    else:
        pattern = "two hills on x with a single hill on y (and the reverse)"
    spread, r2 = facts["invariance_spread"], facts["polarity_r2"]
    agree = "agree" if spread <= SAME_RESPONSE else "differ"
    n = len(facts.get("winners", [])) or 4
    if "same_winner" in facts:
        k, near = facts["same_winner"], facts["within_one"]
        units = ", ".join(map(str, facts["winners"]))
        alike = (
            f"The same unit wins all {n} pairs (hard winners {units}); the"
            if k == n
            else f"The same unit wins {k} of the {n} pairs ({near} of {n} within one unit of "
            f"it; hard winners {units}); the"
        )
    else:
        alike = "The"
    refined = facts.get("refined_pairs", 0)
    map_is = f"the refined map (after {refined:,} refinement pairs)" if refined else "the map"
    if r2 >= ORDERED_R2:
        shown = (
            f"the pattern reappears on the map, {facts['polarity']} relative to the input "
            f"(affine order R² of the receptive-field centres {r2:.2f})"
        )
    else:
        shown = (
            f"this map is twisted (affine order R² of the receptive-field centres {r2:.2f} < "
            f"{ORDERED_R2}), so the pattern does not reappear as one piece"
        )
    return (
        f"Fig. 8 of the chapter on {map_is}, {run.what}. Left: {n} random (x, y) pairs that "
        f"share one body-centred z = ({', '.join(f'{v:.2f}' for v in facts['z'])}); rows x, "
        f"y and the map activation h. {alike} responses {agree}: the largest distance between "
        f"two of them, each response scaled to unit length, is {spread:.2f} (0 = the same "
        f"shape, 1.41 = no unit in common; they agree up to {SAME_RESPONSE}). "
        f"Right: {pattern}; {shown}. "
        "The paper's 2-D run came out rotated by 180 degrees: the orientation is arbitrary "
        "before learning and consistent after it."
    )


# ----------------------------------------------------------------------------- weights


def _draw_weights(model: SigmaPiSOM, inp: DrawInputs) -> tuple[Figure, Facts]:
    from sigmapi.analysis import map_data as analysis
    from sigmapi.viz import plots

    if len(model.x_shape) == 1:
        tiles = analysis.weight_tiles(model)
        k = tiles.shape[0]
        fig = _figure((max(6.0, 1.1 * np.ceil(k / np.ceil(np.sqrt(k / 2.0))) + 2.0), 4.8))
        plots.plot_weight_tiles(
            tiles,
            model.map_shape,
            ax=fig.add_subplot(),
            title=f"Sigma-Pi weights w_kij of each map unit k{inp.tag} (Fig. 6a):\nan invariant "
            "unit has its weight on an anti-diagonal i + j = const",
        )
    else:
        fig = _figure((16.0, 7.6))
        axes = fig.subplots(1, 2, gridspec_kw={"wspace": 0.3})
        for a, ax in enumerate(axes):
            other = 1 - a
            plots.plot_weight_tiles(
                analysis.weight_tiles(model, axis=a),
                model.map_shape,
                ax=ax,
                title=f"weights of every unit{inp.tag}, summed over axis {other} of x and y:\n"
                f"x{a} against y{a}; anti-diagonals = invariance along axis {a}",
                x_label=f"x{a} unit",
                y_label=f"y{a} unit",
            )
    return fig, {"weight_abs_max": float(np.abs(model.weights_).max())}


def _caption_weights(run: RunInfo, facts: Facts) -> str:
    tiles = (
        "each unit's full 15x15 matrix"
        if len(run.config.x_shape) == 1
        else ("for each unit, its weights summed over the other axis of x and of y")
    )
    return (
        f"Sigma-Pi weights in the style of Fig. 6a, {run.what}: {tiles}, x on rows and y on "
        "columns. A unit that responds to one z = (x + y) / 2 holds its weight on an "
        "anti-diagonal i + j = const; in an ordered map, neighbouring units hold neighbouring "
        "anti-diagonals."
    )


# ----------------------------------------------------------------------------- net


def _draw_net(model: SigmaPiSOM, inp: DrawInputs) -> tuple[Figure, Facts]:
    from sigmapi.analysis import map_data as analysis
    from sigmapi.viz import plots

    fig = _figure((6.4, 4.4) if len(model.x_shape) == 1 else (7.4, 6.0))
    plots.plot_net(
        np.asarray(inp.centres),
        model.map_shape,
        ax=fig.add_subplot(),
        z_range=model.sampler.relation.z_range,
        title=f"The map in input space{inp.tag}:\neach unit at the z it responds to",
    )
    pol = analysis.map_polarity(model, centres=inp.centres)
    return fig, {"polarity": pol.name, "order_r2_centres": pol.r2}


def _caption_net(run: RunInfo, facts: Facts) -> str:
    return (
        f"The map in input space, {run.what}: every unit placed at the z it responds to (centre "
        "of mass of the upper half of its receptive field in z), grid neighbours joined, as "
        f"in the classic SOM net plot. "
        + (
            f"Map polarity: {facts['polarity']}, i.e. how a picture in z appears on the map "
            "image (rows down, columns right, as in Fig. 8's right panel), not how this net "
            f"looks in z (R² of the affine fit of the centres to the grid: "
            f"{facts['order_r2_centres']:.2f})."
            if facts["order_r2_centres"] >= ORDERED_R2
            else f"The net is twisted (R² of the affine fit of the centres to the grid: "
            f"{facts['order_r2_centres']:.2f} < {ORDERED_R2}): no single polarity."
        )
    )


# ----------------------------------------------------------------------------- invariance


def _draw_invariance(model: SigmaPiSOM, inp: DrawInputs) -> tuple[Figure, Facts]:
    from sigmapi.analysis import map_data as analysis
    from sigmapi.viz import plots

    if len(model.x_shape) == 1:
        inv = analysis.invariance_matrix(model)
        fig = _figure((6.0, 5.0))
        plots.plot_invariance(inv, ax=fig.add_subplot())
        return fig, {"constancy": inv.constancy}
    fig = _figure((12.0, 5.0))
    axes = fig.subplots(1, 2, gridspec_kw={"wspace": 0.3})
    facts: Facts = {}
    for a, ax in enumerate(axes):
        inv = analysis.invariance_matrix(model, axis=a, centres=inp.centres)
        plots.plot_invariance(
            inv,
            ax=ax,
            title=f"Winner as a function of x{a} and y{a} (x{1 - a}, y{1 - a} at 0.5)"
            f"\n{100 * inv.constancy:.1f} % of cells agree with their anti-diagonal",
        )
        facts[f"constancy_axis{a}"] = inv.constancy
    return fig, facts


def _caption_invariance(run: RunInfo, facts: Facts) -> str:
    d = len(run.config.x_shape)
    if d == 1:
        score = f"{100 * facts['constancy']:.1f} %"
    else:
        score = " and ".join(f"{100 * facts[f'constancy_axis{a}']:.1f} %" for a in range(d))
    return (
        f"Invariance matrix, {run.what}: the winning unit for every x and y on the input grid "
        f"(2-D: along one axis, the other at the centre). Constant z lies on the "
        f"anti-diagonals; {score} of the cells agree with the most common winner of their "
        "anti-diagonal (100 % = perfectly invariant)."
    )


# ----------------------------------------------------------------------------- curves


def _draw_curves(model: SigmaPiSOM, inp: DrawInputs) -> tuple[Figure, Facts]:
    from sigmapi.viz import plots

    curves = inp.curves
    if not curves:
        raise ValueError("the curves figure needs learning curves (curves=...)")
    ceiling = {k: float(v) for k, v in (inp.ceiling or {}).items() if k in CURVE_CEILING}
    trained = [int(sum(1 for r in c.get("refined", []) if r == 0) or len(c["t"])) for c in curves]
    title = _wrap(
        f"Learning curves{inp.tag}, measured at {trained[0]} training checkpoints"
        + (" and after every refinement round" if plots.has_refinement(curves) else "")
    )
    extra = 0.2 * title.count("\n")  # inches above the panels for each further title line
    fig = _figure((10.5, 9.0 + extra))
    top = 9.0 / (9.0 + extra)
    if extra:  # the title above the panels' box, so that its lines clear their labels
        fig.suptitle(title, fontsize=12, y=1.0 - 0.05 / (9.0 + extra), va="top")
    plots.plot_learning_curves(
        curves,
        ax=fig.add_axes((0.0, 0.0, 1.0, top)),
        reference=inp.reference,
        schedule=sigma_schedule(model),
        ceiling=ceiling,
        title=" " if extra else title,
    )
    rounds = [int(sum(1 for r in c.get("refined", []) if r > 0)) for c in curves]
    return fig, {
        "checkpoints": trained[0],
        "refinement_rounds": rounds[0],
        "final": {k: v[-1] for k, v in curves[0].items()},
        "reference_lines": sorted(k for k in (inp.reference or {}) if k in CURVE_REFERENCES),
        "ceiling": ceiling,
        "ceiling_from": {k: (inp.ceiling or {}).get(k) for k in ("preset", "seed")},
    }


def _wrap(title: str, width: int = 90) -> str:
    """A title that fits the figure (about ``width`` characters at 12 pt): a long one in
    lines, broken before ``measured`` and then at words."""
    import textwrap

    if len(title) <= width:
        return title
    head, sep, tail = title.partition(", measured")
    parts = [head + ",", sep.lstrip(", ") + tail] if sep else [title]
    return "\n".join(line for part in parts for line in textwrap.wrap(part, width))


def _caption_curves(run: RunInfo, facts: Facts) -> str:
    rounds = facts.get("refinement_rounds", 0)
    refine = (
        f" Right of the training axis, on its own axis: the {rounds} refinement "
        f"round{'s' if rounds != 1 else ''} after the training (x: refinement pairs done; 0 "
        "= the end of the training)."
        if rounds
        else ""
    )
    ceiling = facts.get("ceiling") or {}
    source = facts.get("ceiling_from") or {}
    line = (
        " Dash-dot lines: the learning rule's ceiling, the fixed point of Eq. 7 reached from "
        f"seed {source.get('seed')} of {source.get('preset')} (view consistency "
        f"{ceiling['view_consistency']:.3f}"
        + (f", z error {ceiling['z_error']:.3f}" if "z_error" in ceiling else "")
        + "; each unit the mean of x' y'^T over the views it wins, computed on a grid, "
        "sigmapi.analysis.fixed_point)."
        if "view_consistency" in ceiling
        else ""
    )
    return (
        f"Learning curves of {run.preset} over seeds {list(run.seeds)} (thin: each seed, thick: "
        f"mean), measured on {run.curve_test} test z's at {facts['checkpoints']} log-spaced "
        "training checkpoints: view consistency, z error, the approximate cost of section 6.3 "
        "(at the sigma of the moment, and with the winner alone) and the neighbourhood width "
        f"sigma with its schedule.{refine}{_table_gap(run, facts)}"
        + (
            " Dashed lines: reference figures of docs/algorithm.md "
            f"({', '.join(facts['reference_lines'])})."
            if facts.get("reference_lines")
            else ""
        )
        + line
    )


CURVE_TABLE_CLOSE = 0.02
"""A curve's last z error this close to the table's needs no cause (the caption says so)."""


def _table_gap(run: RunInfo, facts: Facts) -> str:
    """What separates the curves' last points from the table (measured in the report: the
    ``table_gap`` fact, medians over the seeds of last point minus table)."""
    gap = facts.get("table_gap")
    if not gap:
        return (
            " The table's metrics use a larger test set and decoding table than the curves;"
            " their last points are not the table's values."
        )
    per_unit = run.curve_test / max(1, int(np.prod(run.config.map_shape)))
    text = (
        f" The curves' last points lie {gap['z_error']:+.3f} in z error and "
        f"{gap['view_consistency']:+.3f} in view consistency from the table's values (median "
        f"over seeds), which use {gap['n_test']:,} test and calibration z's."
    )
    d = gap.get("decoding")
    if not d:
        return text
    last, table, mixed = d["z_error_curve"], d["z_error_table"], d["z_error_curve_table"]
    measured = (
        f"with the table's test z's but the curves' decoding table ({run.curve_test:,} "
        f"calibration z's, {per_unit:.0f} per unit) its map scores z error {mixed:.3f} against "
        f"the table's {table:.3f} (its curve ends at {last:.3f})"
    )
    if abs(last - table) <= CURVE_TABLE_CLOSE:
        return text + f" Seed {d['seed']}, within {CURVE_TABLE_CLOSE} of the table: {measured}."
    share = (mixed - table) / (last - table)
    return text + (
        f" The cause, measured on seed {d['seed']}: {measured}; the smaller decoding table "
        f"makes {share:.0%} of that seed's gap."
    )


# ----------------------------------------------------------------------------- registry

REGISTRY: dict[str, FigureSpec] = {
    "fig8": FigureSpec(_draw_fig8, _caption_fig8, needs_centres=lambda d: True, tight=False),
    "weights": FigureSpec(_draw_weights, _caption_weights),
    "net": FigureSpec(_draw_net, _caption_net, needs_centres=lambda d: True),
    "invariance": FigureSpec(_draw_invariance, _caption_invariance, needs_centres=lambda d: d == 2),
    "curves": FigureSpec(_draw_curves, _caption_curves, tight=False),
}
"""Figure name -> :class:`FigureSpec`, in report order."""

FIGURES = tuple(REGISTRY)
"""Names of the figures (``sigmapi figure NAME``), in report order."""


def _spec(name: str) -> FigureSpec:
    if name not in REGISTRY:
        raise ValueError(f"figure name must be one of {FIGURES}, got {name!r}")
    return REGISTRY[name]


def draw_figure(
    name: str,
    model: SigmaPiSOM,
    path: str | Path,
    *,
    curves: Sequence[dict[str, list[float]]] | None = None,
    reference: dict[str, float] | None = None,
    label: str = "",
    seed: int = 0,
    centres: ArrayLike | None = None,
    dpi: int = DPI,
    ceiling: Mapping[str, float] | None = None,
) -> Facts:
    """Draw figure ``name`` (one of :data:`FIGURES`) of ``model`` into ``path``.

    ``curves`` (learning-curve columns, one mapping per seed) is needed for ``"curves"``;
    ``reference`` adds reference lines to it; ``label`` names the model in titles; ``seed``
    draws the Fig. 8 inputs and the receptive-field sampling; ``centres`` reuses computed
    receptive-field centres; ``ceiling`` (metrics of the rule's fixed point,
    :func:`sigmapi.analysis.fixed_point.fixed_point`, with its ``preset`` and ``seed``) adds the
    ceiling lines to ``"curves"``. Returns the facts the caption states (JSON-able).
    """
    spec = _spec(name)
    if centres is None and spec.needs_centres(len(model.x_shape)):
        from sigmapi.analysis.map_data import receptive_field_centres

        centres = receptive_field_centres(model, seed)
    inputs = DrawInputs(curves, reference, label, seed, centres, ceiling)
    fig, facts = spec.draw(model, inputs)
    tight = "tight" if spec.tight else None
    from sigmapi._outputs import save_figure  # atomic, never through a link

    save_figure(fig, Path(path), dpi=dpi, bbox_inches=tight, facecolor="white")
    return facts


def caption(name: str, run: RunInfo, facts: Facts) -> str:
    """The caption of figure ``name`` for ``run``, stating ``facts`` (from :func:`draw_figure`)."""
    return _spec(name).caption(run, facts)
