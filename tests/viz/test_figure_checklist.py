"""Every figure an experiment writes passes a checklist read from matplotlib's object model.

The checklist (:func:`check_figure`), on the drawn figure:

1. **Every mark explained**: each drawn line, patch, collection and image is named in a legend
   (by its label), by the caption (its label appears in the caption text), or shares its style
   (kind, colour, line style or marker) with a mark that is; a bar or an error bar counts by
   its container's label; an RGB image (a camera frame) is its own explanation; colour that
   carries a value (a scalar image, a scatter coloured by an array) has a colour bar (its own,
   or one of the same colour map and limits). Where every unnamed mark of an Axes has one
   colour and the Axes no legend, they are its one series, named by its title and axis labels.
2. **Legends off the data**: no legend's box covers a data point, a point on a data line, a bar,
   a text label inside the Axes, or a title, axis label or tick label (reference lines across
   the whole Axes, spans and background patches may run under a legend).
3. **Tick labels readable**: no two visible tick labels of one axis overlap.
4. **No series hidden**: of two data lines at the same display points (within a pixel), the
   one below has a marker :data:`BIGGER` times the size of the one above (or the one above
   has none), so it shows round it; and the legend or the caption says they coincide
   ("coincide").
5. **A caption file** (``NAME.txt``, :func:`sigmapi._outputs.save_captioned`) beside every
   figure an experiment writes.

The figures are drawn through each experiment's own ``figure(out_dir)`` from a small result
(:data:`RESULTS`: synthetic records, a measured result read back from ``tests/data`` or
``benchmarks/results``, or a run of a few seconds); every figure saved is caught at
``Figure.savefig`` and checked, so a new figure of these experiments is checked too, and a new
experiment fails :func:`test_every_experiment_is_checked` until it has a result here. The
report's figures are checked through :data:`sigmapi.viz.figures.REGISTRY` on the tiny models
of ``conftest.py``.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import Collection, LineCollection
from matplotlib.colors import to_rgb
from matplotlib.container import Container, ErrorbarContainer
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from sigmapi.analysis.map_data import receptive_field_centres
from sigmapi.viz.figures import FIGURES, REGISTRY, DrawInputs, RunInfo, caption

BIGGER = 1.3
"""Of two lines at the same points, the one below shows round the one above: its marker is
at least this many times the size (or the one above has no marker)."""

COINCIDE = "coincide"
"""The word a legend entry or the caption uses for series drawn on top of one another."""


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


# ---------------------------------------------------------------------------- the checklist


def _panels(fig: Figure) -> list[Axes]:
    """The figure's data Axes (inset panels included), colour bars left out."""
    out: list[Axes] = []
    for ax in fig.axes:
        if getattr(ax, "_colorbar", None) is None:
            out.extend([ax, *[c for c in ax.child_axes if getattr(c, "_colorbar", None) is None]])
    return list(dict.fromkeys(out))


def _legends(fig: Figure) -> list[Any]:
    legends = [*fig.legends]
    for ax in fig.axes:
        legends.extend(a.get_legend() for a in [ax, *ax.child_axes] if a.get_legend())
    return [lg for lg in legends if lg.get_visible()]


def _legend_labels(fig: Figure) -> set[str]:
    return {t.get_text() for lg in _legends(fig) for t in lg.get_texts()}


def _empty(artist: Any) -> bool:
    if isinstance(artist, Line2D):
        return len(artist.get_xdata()) == 0
    if isinstance(artist, Collection):
        return len(artist.get_paths()) == 0 and len(artist.get_offsets()) == 0
    return False


def _marks(ax: Axes) -> list[Any]:
    """The Axes' drawn marks (lines, patches, collections, images), visible and not empty."""
    arts = [*ax.lines, *ax.patches, *ax.collections, *ax.images]
    return [a for a in arts if a.get_visible() and not _empty(a)]


def _colour(c: Any) -> tuple[float, ...]:
    if isinstance(c, str):
        return tuple(np.round(to_rgb(c), 3))
    arr = np.asarray(c, dtype=float).reshape(-1)
    return tuple(np.round(to_rgb(arr[:4]), 3)) if arr.size >= 3 else ()


def _style(a: Any) -> tuple[Any, ...]:
    """What tells a mark from another in a legend: kind, colour (not alpha or width), line
    style or, for dots, marker."""
    if isinstance(a, Line2D):  # a drawn line by its colour and dashes, dots by their marker
        if a.get_linestyle() not in ("None", "", " "):
            return ("line", _colour(a.get_color()), a.get_linestyle())
        return ("dots", _colour(a.get_markerfacecolor()), str(a.get_marker()))
    if isinstance(a, Patch):
        face = _colour(a.get_facecolor()) if a.get_fill() else None
        return ("patch", face, _colour(a.get_edgecolor()), a.get_linestyle())
    if isinstance(a, Collection):
        fc, ec = a.get_facecolor(), a.get_edgecolor()
        return (
            "collection",
            type(a).__name__,
            _colour(fc[0]) if len(fc) else None,
            _colour(ec[0]) if len(ec) else None,
        )
    return (type(a).__name__,)


def _container_children(c: Container) -> Iterator[Any]:
    for child in c:
        if isinstance(child, (list, tuple)):
            yield from child
        elif child is not None:
            yield child


def _colourbar_mappables(fig: Figure) -> list[Any]:
    every = [a for ax in fig.axes for a in (ax, *ax.child_axes)]
    return [ax._colorbar.mappable for ax in every if getattr(ax, "_colorbar", None)]


def _same_scale(a: Any, bar: Any) -> bool:
    """Whether the colour bar of ``bar`` reads the colours of ``a`` (the same mappable, or the
    same colour map and limits: one colour bar for a row of panels)."""
    return a is bar or (
        a.get_cmap().name == bar.get_cmap().name and np.allclose(a.get_clim(), bar.get_clim())
    )


def _unexplained(fig: Figure, caption: str) -> list[str]:
    """Marks with no legend entry, no mention in the caption and no style they share with a
    mark that has one; value-coloured marks without a colour bar."""
    named = _legend_labels(fig)
    text = caption.lower()
    bars = _colourbar_mappables(fig)
    problems: list[str] = []

    def said(label: str) -> bool:
        label = label.strip()
        return (
            bool(label) and not label.startswith("_") and (label in named or label.lower() in text)
        )

    for ax in _panels(fig):
        explained: set[int] = set()
        for c in ax.containers:
            if said(c.get_label()):
                explained.update(id(a) for a in _container_children(c))
        arts = [*ax.lines, *ax.patches, *ax.collections, *ax.images]
        explained.update(id(a) for a in arts if said(a.get_label()))
        styles = {_style(a) for a in arts if id(a) in explained}
        marks, unnamed = _marks(ax), []
        for a in marks:
            if isinstance(a, AxesImage) and np.asarray(a.get_array()).ndim == 3:
                continue  # a camera frame: its own explanation
            valued = (
                isinstance(a, (AxesImage, Collection))
                and not isinstance(a, LineCollection)
                and a.get_array() is not None
                and np.size(a.get_array()) > 0
            )
            if valued and not any(_same_scale(a, b) for b in bars):
                problems.append(f"{ax.get_title()!r}: {a} carries values in colour, no colour bar")
            if not (valued or id(a) in explained or _style(a) in styles):
                unnamed.append(a)
        one_series = (
            len(unnamed) == len(marks)
            and ax.get_legend() is None
            and len({_style(a)[1] for a in unnamed}) == 1
        )
        if not one_series:
            problems += [
                f"{ax.get_title()!r}: {type(a).__name__} {a.get_label()!r} unexplained"
                for a in unnamed
            ]
    return problems


def _on_data_coords(ax: Axes, a: Any) -> bool:
    """Whether the mark is placed in data coordinates (not a line across the Axes)."""
    if isinstance(a, Collection):
        return a.get_offset_transform() == ax.transData or a.get_transform() == ax.transData
    return a.get_transform() == ax.transData


def _line_points(line: Line2D, step: float = 3.0) -> np.ndarray:
    """The line's points in display coordinates, its segments sampled every ``step`` pixels
    when it is drawn with a line style."""
    xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if line.get_linestyle() in ("None", "", " ") or len(xy) < 2:
        return xy
    out = [xy[:1]]
    for p, q in itertools.pairwise(xy):
        n = max(1, int(np.hypot(*(q - p)) / step))
        out.append(p + (q - p) * np.linspace(0, 1, n + 1)[1:, None])
    return np.concatenate(out)


def _data_points(ax: Axes) -> np.ndarray:
    pts: list[np.ndarray] = [np.empty((0, 2))]
    for a in _marks(ax):
        if not _on_data_coords(ax, a):
            continue
        if isinstance(a, Line2D):
            pts.append(_line_points(a))
        elif isinstance(a, Collection):
            if isinstance(a, LineCollection):
                for seg in a.get_segments():
                    pts.append(a.get_transform().transform(np.asarray(seg, dtype=float)))
            elif len(a.get_offsets()):
                pts.append(a.get_offset_transform().transform(np.asarray(a.get_offsets())))
    pts = [p for p in pts if len(p)]
    xy = np.concatenate(pts) if pts else np.empty((0, 2))
    inside = ax.get_window_extent()
    keep = (
        (xy[:, 0] >= inside.x0)
        & (xy[:, 0] <= inside.x1)
        & (xy[:, 1] >= inside.y0)
        & (xy[:, 1] <= inside.y1)
    )
    return xy[keep]


def _boxes(ax: Axes, renderer: Any) -> list[tuple[str, Bbox]]:
    """Bars (patches of a container) and text labels inside the Axes, in display space."""
    out: list[tuple[str, Bbox]] = []
    for c in ax.containers:
        for a in _container_children(c):
            if isinstance(a, Patch) and a.get_visible() and a.get_height() != 0:
                out.append((f"bar of {c.get_label()!r}", a.get_window_extent(renderer)))
    for t in ax.texts:
        if t.get_visible() and t.get_text().strip():
            out.append((f"text {t.get_text()!r}", t.get_window_extent(renderer)))
    return out


def _axis_texts(ax: Axes, renderer: Any) -> list[tuple[str, Bbox]]:
    """The Axes' title, axis labels and tick labels, in display space."""
    texts = [ax.title, ax.xaxis.label, ax.yaxis.label]
    texts += _tick_labels(ax.xaxis) + _tick_labels(ax.yaxis)
    return [
        (f"label {t.get_text()!r}", t.get_window_extent(renderer))
        for t in texts
        if t.get_visible() and t.get_text().strip()
    ]


def _shrunk(box: Bbox, px: float = 1.0) -> Bbox:
    return Bbox.from_extents(box.x0 + px, box.y0 + px, box.x1 - px, box.y1 - px)


def _legends_on_data(fig: Figure, renderer: Any) -> list[str]:
    problems = []
    for lg in _legends(fig):
        box = _shrunk(lg.get_window_extent(renderer))
        for ax in _panels(fig):
            pts = _data_points(ax)
            hit = (
                (pts[:, 0] > box.x0) & (pts[:, 0] < box.x1)
                & (pts[:, 1] > box.y0) & (pts[:, 1] < box.y1)
            )  # fmt: skip
            if hit.any():
                problems.append(
                    f"legend {[t.get_text() for t in lg.get_texts()]} covers {int(hit.sum())} "
                    f"data points of {ax.get_title()!r}"
                )
            for what, other in [*_boxes(ax, renderer), *_axis_texts(ax, renderer)]:
                if box.overlaps(_shrunk(other, 0.5)):
                    problems.append(
                        f"legend {[t.get_text() for t in lg.get_texts()]} covers the {what} of "
                        f"{ax.get_title()!r}"
                    )
    return problems


def _tick_labels(axis: Any) -> list[Text]:
    lo, hi = sorted(axis.get_view_interval())
    pad = 1e-9 * max(1.0, abs(hi - lo))
    out: list[Text] = []
    for locs, ticks in (
        (axis.get_majorticklocs(), axis.get_major_ticks),
        (axis.get_minorticklocs(), axis.get_minor_ticks),
    ):
        for loc, tick in zip(locs, ticks(len(locs)), strict=True):
            if not lo - pad <= loc <= hi + pad:
                continue
            for lab in (tick.label1, tick.label2):
                if lab.get_visible() and lab.get_text().strip():
                    out.append(lab)
    return out


def _ticks_overlap(fig: Figure, renderer: Any) -> list[str]:
    problems = []
    for ax in fig.axes:
        if not ax.axison:
            continue
        for axis in (ax.xaxis, ax.yaxis):
            labels = _tick_labels(axis)
            boxes = [_shrunk(lab.get_window_extent(renderer), 0.5) for lab in labels]
            for (a, ba), (b, bb) in itertools.combinations(zip(labels, boxes, strict=True), 2):
                if ba.overlaps(bb):
                    problems.append(
                        f"{ax.get_title() or ax.get_ylabel()!r}: tick labels {a.get_text()!r} "
                        f"and {b.get_text()!r} overlap"
                    )
    return problems


def _marker_size(line: Line2D) -> float:
    return 0.0 if line.get_marker() in ("None", "", " ", None) else float(line.get_markersize())


def _hidden_lines(fig: Figure, caption: str) -> list[str]:
    problems = []
    said = COINCIDE in caption.lower() or any(COINCIDE in t for t in _legend_labels(fig))
    for ax in _panels(fig):
        caps = {  # an error bar's caps: where its error is 0, its two caps meet
            id(a) for c in ax.containers if isinstance(c, ErrorbarContainer) for a in c.lines[1]
        }
        lines = [
            a for a in ax.lines if a in _marks(ax) and _on_data_coords(ax, a) and id(a) not in caps
        ]
        for below, above in itertools.combinations(sorted(lines, key=lambda a: a.zorder), 2):
            p = below.get_transform().transform(np.asarray(below.get_xydata(), dtype=float))
            q = above.get_transform().transform(np.asarray(above.get_xydata(), dtype=float))
            if p.shape != q.shape or not np.allclose(p, q, atol=1.0):
                continue
            shows = _marker_size(below) >= BIGGER * _marker_size(above) > 0 or (
                _marker_size(below) > 0 and _marker_size(above) == 0
            )
            name = f"{ax.get_title()!r}: {below.get_label()!r} under {above.get_label()!r}"
            if not shows:
                problems.append(f"{name} is hidden (same points, no marker of its own)")
            if not said:
                problems.append(f"{name}: coincide, and neither legend nor caption says so")
    return problems


def check_figure(fig: Figure, caption: str) -> list[str]:
    """Every problem the checklist finds in ``fig`` (with its ``caption``), as lines."""
    if not isinstance(fig.canvas, FigureCanvasAgg):  # closed by pyplot after it was saved
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return [
        *_unexplained(fig, caption),
        *_legends_on_data(fig, renderer),
        *_ticks_overlap(fig, renderer),
        *_hidden_lines(fig, caption),
    ]


# ------------------------------------------------------------- the checklist can fail


def test_the_checklist_finds_each_fault_it_names():
    fig, ax = plt.subplots()
    ax.plot([0, 1, 2], [1, 1, 1], "o-", label="a")
    ax.plot([0, 1, 2], [1, 1, 1], "o-", label="b")  # same points, same marker: a is hidden
    ax.axvspan(0.2, 0.4, color="0.8")  # no label, no caption
    ax.legend(loc="center")  # on the data
    problems = check_figure(fig, "two series")
    assert any("'a' under 'b' is hidden" in p for p in problems)
    assert any("neither legend nor caption says so" in p for p in problems)
    assert any("Rectangle" in p and "unexplained" in p for p in problems)
    assert any("covers" in p and "data points" in p for p in problems)

    fig, ax = plt.subplots(figsize=(2, 2))
    ax.set_xticks(np.arange(30), [f"{t:.3f}" for t in np.arange(30)])
    ax.set_xlim(0, 29)
    ax.scatter([1, 2], [1, 2], c=[0.0, 1.0], label="units")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1))
    problems = check_figure(fig, "")
    assert any("tick labels" in p and "overlap" in p for p in problems)
    assert any("no colour bar" in p for p in problems)


def test_a_figure_that_follows_the_checklist_passes():
    fig, ax = plt.subplots(figsize=(7, 3))
    a = ax.plot([0, 1, 2], [1, 1, 1], "o-", ms=9, label="a")[0]
    b = ax.plot([0, 1, 2], [1, 1, 1], "s-", ms=6, label="b (coincides with a)")[0]
    band = ax.axvspan(0.2, 0.4, color="0.8", label="a band")
    for x in (0.5, 1.5):  # named by the caption, the second by the style it shares
        ax.axvline(x, color="0.5", ls=":", label="guide" if x < 1 else "_guide")
    ax.legend(handles=[a, b, band], loc="upper left", bbox_to_anchor=(1.02, 1))
    assert check_figure(fig, "Dotted, the guide: where the bins end.") == []


# -------------------------------------------------------- every experiment's figures


def _icub_result() -> Any:
    """A two-seed iCub result of synthetic records (no simulator): 40 reaches a seed, the
    learned method's success equal to the true direction's (the case that once hid it)."""
    from sigmapi.experiments.icub.config import ICubConfig
    from sigmapi.experiments.icub.reaching import METHODS
    from sigmapi.experiments.icub.result import ICubResult

    cfg = ICubConfig(map_shape=(4, 5))
    rng = np.random.default_rng(0)
    per_seed = []
    for _ in range(2):
        n = 40
        ball = np.column_stack([rng.uniform(0.15, 0.3, n), rng.uniform(-0.1, 0.3, n)])
        gaze = rng.normal(0.0, 0.2, (n, 6))
        success = {
            m: rng.random(n) < p for m, p in zip(METHODS, (1, 1, 0.5, 0.7, 1, 0.3), strict=True)
        }
        success["learned"] = success["true_direction"].copy()
        cuts = np.unique(np.geomspace(50, 800, 6).astype(int))  # the quick run's (log axis)
        curves = {m: [[c, 0.3 / np.sqrt(c) + 0.02 * i] for c in cuts]
                  for i, m in enumerate(METHODS[:4])}  # fmt: skip
        curves["learned"] = curves["true_direction"]
        u, v = np.meshgrid(np.linspace(0.15, 0.3, 4), np.linspace(-0.1, 0.3, 5), indexing="ij")
        frame = rng.integers(0, 255, (32, 32, 3), dtype=np.uint8)
        per_seed.append(
            {
                "maps": {"map2": {"order_r2": 0.91, "folded": False, "fold_score": 0.4}},
                "ball": ball,
                "gaze": gaze,
                "success": success,
                "servo": {m: rng.random(n) < 0.8 for m in METHODS[:4]},
                "curves": curves,
                "unit_table": np.column_stack([u.ravel(), v.ravel()]),
                "film": [frame] * 8,
                "eyes": {
                    "l_eye": frame,
                    "r_eye": frame,
                    "l_eye_ball": (10.0, 12.0),
                    "l_eye_palm": (20.0, 18.0),
                    "r_eye_ball": (12.0, 12.0),
                    "r_eye_palm": (22.0, 18.0),
                },
            }
        )
    return ICubResult(cfg, (3, 4), {}, per_seed)


def _neurons_result(tmp_path: Path) -> Any:
    """The result of ``sigmapi neurons --quick`` (one seed), read back from tests/data."""
    import json

    from sigmapi.experiments.neurons.result import NeuronsResult

    data = Path(__file__).parents[1] / "data" / "neurons-quick.json"
    return NeuronsResult.from_dict(json.loads(data.read_text()))


def _physiology_result(tmp_path: Path) -> Any:
    """The physiology of a tiny trained 1-D map (5 units)."""
    from sigmapi import SigmaPiSOM
    from sigmapi.experiments.physiology.run import PhysiologyConfig, PhysiologyResult, record_model

    model = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0).fit()
    path = model.save(tmp_path / "m.npz") or tmp_path / "m.npz"
    cfg = PhysiologyConfig(model=str(path))
    return PhysiologyResult(cfg, record_model(cfg), 0.0)


def _stored(name: str, result_type: Any) -> Callable[[Path], Any]:
    """A result read back from the project's measured ``benchmarks/results/NAME.json``."""

    def read(tmp_path: Path) -> Any:
        import json

        path = Path(__file__).parents[2] / "benchmarks" / "results" / f"{name}.json"
        return result_type.from_dict(json.loads(path.read_text()))

    return read


def _stream(tmp_path: Path) -> Any:
    from sigmapi.experiments.stream.run import StreamResult

    return _stored("stream", StreamResult)(tmp_path)


def _compare(tmp_path: Path) -> Any:
    """The measured comparison (benchmarks/results/compare.json), its medians as one seed."""
    import json

    from sigmapi.experiments.compare.run import CompareResult, MethodScore

    path = Path(__file__).parents[2] / "benchmarks" / "results" / "compare.json"
    data = json.loads(path.read_text())
    read = CompareResult.from_dict(data)
    scores = {
        m["name"]: MethodScore(
            m["name"],
            [m["view_consistency"]],
            [m["unit_consistency"]],
            [{int(n): e for n, e in m["z_error_by_labels"].items()}],
            [1.0],
        )
        for m in data["methods"]
    }
    return CompareResult(read.config, scores, 1.0, read.seeds[:1])


def _reach(dim: int) -> Callable[[Path], Any]:
    """A tiny reach run (seconds): a 6-unit map, 20 episodes per state, two seeds."""

    def run(tmp_path: Path) -> Any:
        from sigmapi.experiments.reach.config import ReachConfig
        from sigmapi.experiments.reach.run import REACH

        shape = (6,) if dim == 1 else (3, 3)
        cfg = ReachConfig().replace(dim=dim, grid=7, map_shape=shape, iterations=500,
                                    episodes=20, block=10, final_episodes=10,
                                    max_episode_steps=30, backend="reference")  # fmt: skip
        return REACH.run(cfg, seeds=[0, 1])

    return run


def _reward(tmp_path: Path) -> Any:
    """A tiny reward run (seconds): a 5x5 map, 40 episodes per method, two seeds."""
    from sigmapi.experiments.reward.config import RewardConfig
    from sigmapi.experiments.reward.run import REWARD

    cfg = RewardConfig().replace(grid=5, map_shape=(5, 5), iterations=500, episodes=40,
                                 block=10, final_episodes=20, n_test=300,
                                 max_episode_steps=30)  # fmt: skip
    return REWARD.run(cfg, seeds=[0, 1])


def _sweep(tmp_path: Path) -> Any:
    """A sweep's table of synthetic rows: 2 code widths x 2 orderings x 3 seeds, one failed
    run and one folded."""
    from sigmapi.experiments.sweep.run import SweepResult, SweepSpec

    spec = SweepSpec.from_dict({"preset": "tiny-1d", "seeds": [0, 1, 2],
                                "grid": {"code_width": [0.5, 1.0],
                                         "ordering": ["none", "crossview"]}})  # fmt: skip
    rng = np.random.default_rng(0)
    rows = []
    for i, (width, ordering, seed) in enumerate(
        itertools.product((0.5, 1.0), ("none", "crossview"), (0, 1, 2))
    ):
        r2 = 0.9 + 0.05 * (ordering == "crossview") + 0.02 * rng.random()
        rows.append({"run_id": str(i), "seed": str(seed), "code_width": str(width),
                     "ordering": ordering, "status": "failed" if i == 5 else "ok",
                     "order_r2": f"{r2 - 0.5 * (i == 2):.3f}", "folded": str(i == 2)})  # fmt: skip
    return SweepResult(spec, rows)


def _robot(tmp_path: Path) -> Any:
    """A two-seed robot result of synthetic records on the measured quick run's config
    (the map on the table reads the scene's geometry: MuJoCo)."""
    import json

    pytest.importorskip("mujoco")
    from sigmapi.experiments.robot.config import RobotConfig
    from sigmapi.experiments.robot.result import RobotResult

    path = Path(__file__).parents[2] / "benchmarks" / "results" / "robot-docking-quick.json"
    cfg = RobotConfig.from_dict(json.loads(path.read_text())["result"]["config"])
    rng = np.random.default_rng(0)
    n, episodes = 2, cfg.run.episodes
    states = cfg.run.states
    success = {
        s: rng.random((n, episodes)) < p for s, p in zip(states, (0.8, 0.3, 0.4, 0.8), strict=True)
    }
    success[states[-1]] = success[states[0]].copy()  # two states' curves coincide
    docked = {s: success[s] | (rng.random((n, episodes)) < 0.5) for s in states}
    steps = {s: rng.integers(5, 100, (n, episodes)) for s in states}
    k = int(np.prod(cfg.map.map_shape))
    unit_z = [rng.uniform(0.1, 0.9, (k, 2)) for _ in range(n)]
    metrics = [{"order_r2": 0.97, "folded": False, "fold_score": 0.2} for _ in range(n)]
    return RobotResult(
        cfg, (5, 6), success, steps=steps, docked=docked, map_metrics=metrics, unit_z=unit_z
    )


def _icub_box_result() -> Any:
    """Two seeds of the 3-D task (synthetic reaches: the end-point histogram per method)."""
    from sigmapi.experiments.icub.box import ICubBoxResult
    from sigmapi.experiments.icub.config import ICubConfig
    from sigmapi.experiments.icub.reach3d import METHODS

    rng = np.random.default_rng(0)
    per_seed = []
    for k in range(2):
        ep = {m: rng.gamma(2.0, 0.02 * (1 + i), 20).tolist() for i, m in enumerate(METHODS)}
        per_seed.append({"seed": k, "end_point_m": {"free": ep, "fixated": ep}})
    return ICubBoxResult(ICubConfig(space="box"), (0, 1), per_seed)


RESULTS: dict[str, Callable[[Path], Any]] = {
    "icub": lambda tmp: _icub_result(),
    "icub-box": lambda tmp: _icub_box_result(),
    "neurons": _neurons_result,
    "physiology": _physiology_result,
    "stream": _stream,
    "compare": _compare,
    "reach-1d": _reach(1),
    "reach-2d": _reach(2),
    "reward": _reward,
    "sweep": _sweep,
    "robot": _robot,
}
"""Experiment name -> a small result of it, whose ``figure(out_dir)`` draws every figure."""


ELSEWHERE = {
    "chain": "writes no figure (ChainResult.figure returns [])",
    "reproduce": "its figures are the registry's (test_every_report_figure_passes_the_checklist), "
    "captioned in its report",
}
"""Experiments checked otherwise, and why."""


def test_every_experiment_is_checked():
    """A new experiment (a line of sigmapi.experiments.ENTRIES) gets a small result here, or a
    reason in ELSEWHERE, or this fails."""
    from sigmapi.experiments import ENTRIES

    names = {name for name, _, _ in ENTRIES}
    checked = {n.split("-")[0] for n in RESULTS} | set(ELSEWHERE)
    assert names <= checked, f"no figure checklist for {sorted(names - checked)}"


@pytest.fixture
def saved(monkeypatch) -> list[Figure]:
    """Every figure saved (``Figure.savefig``) while the test runs, in order."""
    figures: list[Figure] = []
    save = Figure.savefig

    def keep(self: Figure, *args: Any, **kwargs: Any) -> Any:
        figures.append(self)
        return save(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


@pytest.mark.parametrize("name", RESULTS)
def test_every_figure_of_an_experiment_passes_the_checklist(name, saved, tmp_path):
    result = RESULTS[name](tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    written = [p for p in result.figure(out) if p.suffix == ".png"]
    assert written and len(written) == len(saved), "a figure written outside savefig"
    problems = []
    for path, fig in zip(written, saved, strict=True):
        caption = path.with_suffix(".txt")
        assert caption.is_file(), f"{name}: no caption file beside {path.name}"
        text = caption.read_text()
        assert len(text.strip()) > 40, f"{name}: {caption.name} says almost nothing"
        problems += [f"{path.name}: {p}" for p in check_figure(fig, text)]
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", FIGURES)
@pytest.mark.parametrize("dims", ["1d", "2d"])
def test_every_report_figure_passes_the_checklist(name, dims, model_1d, model_2d, curves):
    """The figures of ``sigmapi reproduce`` and ``sigmapi figure`` (the registry), with the
    captions the report prints under them."""
    model = model_1d if dims == "1d" else model_2d
    spec = REGISTRY[name]
    centres = receptive_field_centres(model, 0) if spec.needs_centres(len(model.x_shape)) else None
    other = {
        k: vs if k in ("t", "refined", "sigma") else [0.97 * v for v in vs]
        for k, vs in curves[0].items()
    }
    two = [*curves, other]  # two seeds: each seed's line apart from their mean
    inputs = DrawInputs(two, {"z_error": 0.3}, "tiny", 0, centres, None)
    fig, facts = spec.draw(model, inputs)
    run = RunInfo("tiny", model.config, (0,), 0, curve_test=100, why="the only seed")
    problems = check_figure(fig, caption(name, run, facts))
    assert not problems, "\n".join(problems)
