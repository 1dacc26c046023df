"""Results pages from data: tables and numbers read from the JSON the experiments write.

Two pieces of markup, for the MyST pages under ``docs/results/``:

- the directive ``results-table`` with a table's name renders that table from its JSON
  (``benchmarks/results/*.json``, or a CSV an experiment wrote), with a line naming the file::

      ```{results-table} ceiling
      ```

- the role ``result`` quotes one number: ``{result}`FILE:KEY.PATH|FORMAT```, e.g.
  ``{result}`files:bytes.v2|,``` (``FILE`` under ``benchmarks/results/`` without ``.json``, or a
  path from the repository root; ``KEY.PATH`` dots into objects and lists; ``FORMAT`` a
  Python format spec, default ``.3g``).

So a number is typed once, by the run that measured it. A table reads the keys it shows and
ignores the others, so JSON files may gain keys; a key it needs and does not find fails the
build with the file and key named. A new table is one function decorated with ``@table``.

The gallery's helpers live here too (``gallery_argv``, ``scrape_example_figure``): each example
runs at its small size, and the figure it writes with ``--out`` joins its gallery page.
"""

from __future__ import annotations

import csv
import functools
import importlib
import json
import re
import shutil
import statistics
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.errors import ExtensionError
from sphinx.util.docutils import SphinxDirective, SphinxRole

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results"


# -- reading ---------------------------------------------------------------------------------
def _path(name: str) -> Path:
    p = Path(name)
    if p.suffix in (".json", ".csv") and (ROOT / p).is_file():
        return ROOT / p
    return RESULTS / f"{name}.json"


@cache
def _load_cached(path: Path, mtime: float) -> Any:
    try:
        if path.suffix == ".csv":
            with path.open(newline="", encoding="utf-8") as f:
                return list(csv.DictReader(f))
        return json.loads(path.read_text("utf-8"))
    except (ValueError, RecursionError, csv.Error, OSError) as exc:  # UnicodeError, JSON too
        raise ExtensionError(
            f"results file {path.name!r} cannot be read ({type(exc).__name__}: "
            f"{str(exc)[:160]}); run the command that writes it again"
        ) from None


_read: list[str] = []
"""The results files read by the table being rendered (named in its errors)."""


def load(name: str) -> Any:
    """The parsed JSON (or CSV rows) of a results file; an error naming it if it is missing."""
    path = _path(name)
    if not path.is_file():
        raise ExtensionError(
            f"results file {_rel(name)} not found; run the command that writes it "
            "(named on its results page) or remove the table that reads it"
        )
    _read.append(_rel(name))
    return _load_cached(path, path.stat().st_mtime)


_EXPERIMENTS = "sigmapi.experiments"
READERS: dict[str, tuple[str, str]] = {
    "chain": ("chain.run:ChainResult", ""),
    "chain-winner": ("chain.run:ChainResult", ""),
    "compare": ("compare.run:CompareResult", ""),
    "icub": ("icub.result:ICubResult", ""),
    "icub-check": ("icub.result:ICubResult", ""),
    "neurons": ("neurons.result:NeuronsResult", ""),
    "paper-1d-procedures": ("sweep.run:SweepResult", ""),
    "paper-2d-procedures": ("sweep.run:SweepResult", ""),
    "reach": ("reach.result:ReachResult", ""),
    "reproduce": ("reproduce.results:ReproduceResult", "metrics"),
    "robot-docking": ("robot.result:RobotResult", "result"),
    "robot-docking-quick": ("robot.result:RobotResult", "result"),
    "robot-docking-tuning": ("robot.result:RobotResult", "result"),
    "stream": ("stream.run:StreamResult", ""),
}
"""The results files an experiment wrote: the class (under :mod:`sigmapi.experiments`) whose
``from_dict`` reads each, and the key the result sits under where the script that kept it
wrapped it ("": the file is the result, with the keeper's keys beside its own)."""


def result(name: str) -> Any:
    """The experiment result of the results file ``name`` (:data:`READERS`), read by its
    class's ``from_dict``: a result's keys are read in one place, its experiment's
    ``result`` module."""
    target, key = READERS[name]
    module, _, cls = target.partition(":")
    reader = getattr(importlib.import_module(f"{_EXPERIMENTS}.{module}"), cls)
    data = load(name)
    return reader.from_dict(get(data, key, name) if key else data)


def read(name: str) -> Any:
    """What the ``result`` role quotes from: a file of :data:`READERS` as its result's JSON
    form (the keeper's keys beside it), any other file as it is."""
    data = load(name)
    if name not in READERS:
        return data
    form = json.loads(json.dumps(result(name).to_dict()))
    key = READERS[name][1]
    return {**data, key: form} if key else {**data, **form}


def get(data: Any, key: str, name: str = "?") -> Any:
    """``data`` dotted into by ``key`` (``a.b.0.c``); an error naming file and key."""
    cur = data
    parts = key.split(".")
    for i, part in enumerate(parts):
        if part == "*" and isinstance(cur, list):  # every entry of a list
            rest = ".".join(parts[i + 1 :])
            return [get(item, rest, name) if rest else item for item in cur]
        try:
            cur = cur[int(part)] if isinstance(cur, list) else cur[part]
        except (KeyError, IndexError, ValueError, TypeError):
            raise ExtensionError(
                f"results file {name!r} has no key {key!r} (at {part!r})"
            ) from None
    return cur


# -- formatting ------------------------------------------------------------------------------
def num(v: Any, fmt: str = ".3f") -> str:
    """A number as a table shows it (``,`` for thousands in integer formats)."""
    if v is None or v == "":
        return ""
    return format(float(v) if "d" not in fmt else round(float(v)), fmt)


def mw(stats: dict[str, Any], fmt: str = ".3f") -> str:
    """``median / worst`` of a summary entry."""
    return f"{num(stats['median'], fmt)} / {num(stats['worst'], fmt)}"


def seeds_label(seeds: Sequence[int]) -> str:
    """The seeds as runs: ``100-119``, ``700-704, 710-714``; a run of two or fewer is listed."""
    s = sorted({int(x) for x in seeds})
    runs: list[list[int]] = []
    for x in s:
        if runs and x == runs[-1][-1] + 1:
            runs[-1].append(x)
        else:
            runs.append([x])
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 2 else ", ".join(map(str, r)) for r in runs)


def median_worst(values: Iterable[float], higher_is_better: bool = True) -> tuple[float, float]:
    v = [float(x) for x in values]
    return statistics.median(v), (min(v) if higher_is_better else max(v))


def mw_of(values: Iterable[float], fmt: str = ".3f", higher_is_better: bool = True) -> str:
    med, worst = median_worst(values, higher_is_better)
    return f"{num(med, fmt)} / {num(worst, fmt)}"


# -- the tables ------------------------------------------------------------------------------
@dataclass
class Table:
    """A rendered table: column heads, rows of cells (MyST inline markup), sources."""

    header: list[str]
    rows: list[list[str]]
    sources: list[str]
    note: str = ""
    commands: list[str] = field(default_factory=list)

    def markdown(self) -> str:
        def line(cells: Sequence[str]) -> str:
            return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

        out = [line(self.header), "|" + "---|" * len(self.header)]
        out += [line(r) for r in self.rows]
        src = ", ".join(f"`{s}`" for s in self.sources)
        tail = f"Rendered from {src}"
        if self.commands:
            tail += ", written by " + "; ".join(f"`{c}`" for c in self.commands)
        out += ["", tail + "." + (f" {self.note}" if self.note else "")]
        return "\n".join(out)


TABLES: dict[str, Callable[[], Table]] = {}
"""Table name -> the function that renders it from its files."""


_DATA_ERRORS = (KeyError, IndexError, TypeError, ValueError, AttributeError, ZeroDivisionError,
                RecursionError)  # fmt: skip
"""What a table's code raises on a file lacking a key or holding another type than it reads."""


def table(name: str) -> Callable[[Callable[[], Table]], Callable[[], Table]]:
    """Register the table ``name``; a file that lacks a key it reads, or holds another type
    there, fails with an ExtensionError naming the table, the files and the key."""

    def register(fn: Callable[[], Table]) -> Callable[[], Table]:
        @functools.wraps(fn)
        def checked() -> Table:
            _read.clear()
            try:
                return fn()
            except _DATA_ERRORS as exc:
                files = ", ".join(dict.fromkeys(_read)) or "its results files"
                what = f"no key {exc}" if isinstance(exc, KeyError) else f"{exc}"[:200]
                raise ExtensionError(
                    f"results table {name!r}: {files}: {what} ({type(exc).__name__}); run the "
                    "command that writes it again, or fix the file"
                ) from None

        TABLES[name] = checked
        return checked

    return register


def _rel(name: str) -> str:
    path = _path(name)
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def _command(data: Any) -> list[str]:
    """The command a file records, with this machine's paths and labels made generic."""
    if not (isinstance(data, dict) and "command" in data):
        return []
    cmd = re.sub(r"--baseline-label .*?(?= --|$)", "", str(data["command"]))
    cmd = re.sub(r"--baseline-src \S+", "--baseline-src OLD/src", cmd)
    cmd = re.sub(r"--model \S+", "--model MODEL.npz", cmd)
    return [re.sub(r"\s+", " ", cmd).strip()]


# reproduction ----------------------------------------------------------------------------
def _ceiling_seeds(runs: Sequence[dict[str, Any]], n: int) -> str:
    """`` (seeds 700-704)`` when only some runs have their fixed point, else ``""``."""
    seeds = [r["seed"] for r in runs if "ceiling" in r]
    return "" if len(seeds) == n else f" (seeds {seeds_label(seeds)})"


@table("ceiling")
def _ceiling() -> Table:
    rows, sources, commands = [], [], []
    for name in ("ceiling-1d", "ceiling-2d"):
        data = load(name)
        sources.append(_rel(name))
        commands += _command(data)
        for preset, entry in data["presets"].items():
            s = entry["summary"]
            seeds = [r["seed"] for r in entry.get("runs", [])]
            rows.append([
                f"`{preset}`", f"{seeds_label(seeds)} ({s['seeds']})" if seeds else str(s["seeds"]),
                mw(s["view_consistency"]), mw(s["view_within_one"]), mw(s["z_error"]),
                mw(s["order_r2"], ".4f"), mw(s["fold_score"], ".2f"),
                f"**{s['ordered']} of {s['seeds']}**",
                (f"{mw(s['ceiling']['view_consistency'])}; z {mw(s['ceiling']['z_error'])}"
                 + _ceiling_seeds(entry.get("runs", []), s["seeds"]) if "ceiling" in s else "-"),
                f"{num(s['train_s']['median'], '.1f')} / {num(s['refine_s']['median'], '.1f')} s"
                f" ({num(s['cpu_s']['median'], '.1f')} s CPU)",
            ])  # fmt: skip
    return Table(
        ["preset", "seeds", "view consistency", "view within one", "z error", "order R²",
         "fold score", "ordered", "each map's fixed point: view consistency; z error",
         "training / refinement, wall (CPU of both)"],
        rows, sources,
        "Each cell is median / worst seed. The fixed point (Eq. 7, reached from each map, "
        "`--ceiling`) is computed for every 1-D map and, at about 70 CPU s per 2-D map, for "
        "the 2-D maps of the seeds the JSON gives it for.",
        commands,
    )  # fmt: skip


@table("torus")
def _torus() -> Table:
    """The torus variants (``benchmarks/bench_torus.py``): each at the end of its training,
    then after its refinement."""
    data = load("ceiling-torus")
    rows = []
    for name, v in data["variants"].items():
        runs, cfg = v["runs"], v["config"]
        seeds = [r["seed"] for r in runs]

        def arrow(key: str, fmt: str = ".2f", runs: Any = runs) -> str:
            b = statistics.median(float(r["before"][key]) for r in runs)
            a = statistics.median(float(r["after"][key]) for r in runs)
            return f"{num(b, fmt)} -> {num(a, fmt)}"

        start = "cross-view" if cfg.get("ordering") == "crossview" else "random"
        floor = cfg["sigma"][-1][1] if isinstance(cfg["sigma"], list) else cfg["sigma"]
        ok = v["summary"]["after"]["seamless_and_order_circular_0.95"]
        head, _, tail = name.partition(",")
        rows.append([
            f"`{head}`" + (f",{tail}" if tail else ""),
            seeds_label(seeds), start, num(cfg["code_width"], ".1f"), f"{floor:g}",
            f"{cfg['refine_rounds']} x sigma {cfg['refine_sigma']:g}",
            arrow("view_consistency"), arrow("view_within_one"), arrow("order_circular", ".3f"),
            arrow("seam_gap", ".1f"), f"**{ok} of {len(runs)}**",
        ])  # fmt: skip
    return Table(
        ["variant", "seeds", "start", "code width", "last sigma", "refinement rounds",
         "view consistency", "within one", "circular order", "seam gap",
         "seamless, circular order >= 0.95"],
        rows, [_rel("ceiling-torus")],
        "Medians over the seeds, at the end of the training -> after the refinement.",
        _command(data),
    )  # fmt: skip


@table("reproduce")
def _reproduce() -> Table:
    """The default ``sigmapi reproduce``: each preset refined, before its refinement (the
    same runs at the end of their training) and at the rule's ceiling."""
    data = load("reproduce")
    rows = []
    for preset, p in result("reproduce").presets.items():
        med, worst, unref = p.median(), p.worst(), p.median("unrefined") if p.refines else None
        ceiling = p.ceiling or {}

        def before(key: str, unref: Any = unref) -> str:
            return num(unref[key]) if unref else "-"

        rows.append([
            f"`{preset}`", seeds_label([r.seed for r in p.runs]),
            f"{num(med['view_consistency'])} / {num(worst['view_consistency'])}",
            before("view_consistency"),
            num(ceiling["view_consistency"]) if "view_consistency" in ceiling else "-",
            f"{num(med['z_error'])} / {num(worst['z_error'])}", before("z_error"),
            f"{num(med['order_r2'])} / {num(worst['order_r2'])}",
            f"{p.ordered_count()} of {len(p.runs)}",
        ])  # fmt: skip
    note = (
        f"Median / worst seed; 'before' is the median of the same runs at the end of their "
        f"training. The run took {num(get(data, 'wall_seconds', 'reproduce') / 60, '.1f')} min "
        f"wall and {num(get(data, 'cpu_seconds', 'reproduce'), '.0f')} CPU s (1-minute load "
        f"average {num(get(data, 'load_average_1min.median', 'reproduce'), '.1f')} median, "
        f"{num(get(data, 'load_average_1min.max', 'reproduce'), '.1f')} at most); numba's "
        f"cache {data.get('numba_cache', 'as found')}."
    )
    return Table(
        ["preset", "seeds", "view consistency", "before refinement", "ceiling", "z error",
         "before refinement", "order R²", "ordered"],
        rows, [_rel("reproduce")], note, _command(data),
    )  # fmt: skip


@table("headline")
def _headline() -> Table:
    """The README's one table: the presets as shipped, on seeds nothing was chosen on."""
    rows, sources = [], []
    for name in ("ceiling-1d", "ceiling-2d"):
        data = load(name)
        sources.append(_rel(name))
        for preset, entry in data["presets"].items():
            s = entry["summary"]
            seeds = [r["seed"] for r in entry.get("runs", [])]
            rows.append(
                [
                    f"`{preset}`",
                    seeds_label(seeds),
                    mw(s["view_consistency"]),
                    mw(s["z_error"]),
                    mw(s["order_r2"]),
                    f"{s['ordered']} of {s['seeds']}",
                ]
            )
    torus = load("ceiling-torus")
    sources.append(_rel("ceiling-torus"))
    for name, v in torus["variants"].items():
        if not name.endswith("(the preset angles-2d)"):
            continue
        after = [r["after"] for r in v["runs"]]
        ok = v["summary"]["after"]["seamless_and_order_circular_0.95"]
        rows.append([
            "`angles-2d` (torus)", seeds_label([r["seed"] for r in v["runs"]]),
            mw_of(_column(after, "view_consistency")),
            mw_of(_column(after, "z_error"), higher_is_better=False),
            mw_of(_column(after, "order_circular")) + " (circular)",
            f"{ok} of {len(after)} seamless",
        ])  # fmt: skip
    return Table(
        ["preset", "fresh seeds", "view consistency", "z error", "order R²", "ordered"],
        rows,
        sources,
        "Median / worst seed.",
    )


def _column(runs: Sequence[dict[str, Any]], key: str) -> list[float]:
    return [float(r[key]) for r in runs]


def _sweep_rows(name: str) -> list[dict[str, Any]]:
    if name.endswith(".csv"):  # a sweep's table itself
        rows = load(name)
    else:
        rows = result(name).rows
    bad = [r for r in rows if r.get("status", "ok") != "ok"]
    if bad:
        raise ExtensionError(f"{name}: {len(bad)} failed runs in the table; rerun them")
    return rows


def _group(rows: list[dict[str, Any]], keys: Sequence[str]) -> dict[tuple[str, ...], list[dict]]:
    groups: dict[tuple[str, ...], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(str(r[k]) for k in keys), []).append(r)
    return groups


def _procedures(name: str, labels: dict[str, str], fold_list: bool) -> Table:
    sweep = result(name)
    rows_in, keys = _sweep_rows(name), list(sweep.spec.grid)
    out = []
    for group, runs in _group(rows_in, keys).items():
        label = labels.get("/".join(group), "/".join(group))
        r2 = [float(r["order_r2"]) for r in runs]
        folded = sorted(int(r["seed"]) for r in runs if float(r["order_r2"]) < 0.95)
        ordered = f"**{len(runs) - len(folded)} of {len(runs)}**"
        if folded and fold_list:
            ordered += f" (below: {', '.join(map(str, folded))})"
        out.append([
            label, seeds_label([r["seed"] for r in runs]),
            mw_of(r["view_consistency"] for r in runs),
            mw_of(r["view_within_one"] for r in runs),
            mw_of((r["z_error"] for r in runs), higher_is_better=False),
            mw_of(r2), mw_of(r["usage"] for r in runs), ordered,
            f"{sum(1 for r in runs if str(r['folded']) in ('True', 'true', '1'))} of {len(runs)}",
        ])  # fmt: skip
    return Table(
        ["procedure", "seeds", "view consistency", "view within one", "z error", "order R²",
         "usage", "ordered (R² ≥ 0.95)", "flagged folded"],
        out, [_rel(name)], "Each cell is median / worst seed.",
    )  # fmt: skip


@table("paper-1d-procedures")
def _paper_1d() -> Table:
    labels = {
        "none": 'the authors\' (`paper-1d-authors`, `ordering = "none"`)',
        "crossview": "sigmapi's ordering (`paper-1d-authors --set ordering=crossview`)",
    }
    t = _procedures("paper-1d-procedures", labels, fold_list=True)
    t.commands = ["sigmapi sweep benchmarks/specs/paper-1d-procedures.toml --out OUT"]
    return t


@table("paper-2d-procedures")
def _paper_2d() -> Table:
    labels = {"crossview": "sigmapi's ordering before the refinement "
                           "(`paper-2d --set refine_rounds=0`)",
              "none": "the paper's random start (`--set ordering=none`)"}  # fmt: skip
    t = _procedures("paper-2d-procedures", labels, fold_list=False)
    t.commands = ["sigmapi sweep benchmarks/specs/paper-2d-procedures.toml --out OUT"]
    return t


# angles ------------------------------------------------------------------------------------
@table("angles")
def _angles() -> Table:
    name = "docs/angles-sweep.csv"
    rows_in = _sweep_rows(name)
    out = []
    for (periodic, ordering), runs in _group(rows_in, ("map_periodic", "ordering")).items():
        shape = "ring" if periodic == "True" else "bounded map"
        col = functools.partial(_column, runs)
        seamless = sum(r["seamless"] == "True" for r in runs)
        vc80 = sum(float(r["view_consistency"]) >= 0.8 for r in runs)
        out.append([
            f"{shape}, `{ordering}`", mw_of(col("view_consistency")),
            mw_of(col("view_within_one")), mw_of(col("z_error"), higher_is_better=False),
            mw_of(col("order_circular")), mw_of(col("seam_jump"), ".2f", higher_is_better=False),
            mw_of(col("seam_gap"), ".0f", higher_is_better=False),
            f"{seamless} of {len(runs)}", f"{vc80} of {len(runs)}",
        ])  # fmt: skip
    seeds = seeds_label(sorted({int(r["seed"]) for r in rows_in}))
    return Table(
        ["map, start", "view consistency", "within one", "z error (circular)", "circular order",
         "seam: largest jump", "seam gap", "seamless", "view consistency ≥ 0.8"],
        out, [name], f"Seeds {seeds}; each cell is median / worst seed.",
        ["sigmapi sweep docs/angles-sweep.toml --out angles-sweep"],
    )  # fmt: skip


# speed -------------------------------------------------------------------------------------
@table("kernels-speed")
def _kernels_speed() -> Table:
    data = load("kernels-speed")
    rows = []
    for preset, s in data["speed"].items():
        rows.append([
            f"`{preset}`", f"{num(s['reference_it_per_s'], ',.1f')} it/s",
            f"{num(s['fast_it_per_s'], ',.0f')} it/s", f"{num(s['ratio'], '.0f')}x",
            f"{num(s['fast_threads_it_per_s'], ',.0f')} it/s",
            f"{s['iterations_timed']['reference']:,} / {s['iterations_timed']['fast']:,}",
        ])  # fmt: skip
    return Table(
        ["preset", "dense reference", "fast kernel (numba)", "ratio", "fast, 2 threads",
         "iterations timed (reference / fast)"],
        rows, [_rel("kernels-speed")], "", _command(data),
    )  # fmt: skip


@table("bandwidth")
def _bandwidth() -> Table:
    data = load("bandwidth")
    names = {"fast": "**fast kernel (as shipped)**", "fast-noprefetch": "without prefetching",
             "fast-threads": "threaded (`threads = true`, 2 threads)",
             "baseline": "baseline: the kernel before its loops were vectorised"}  # fmt: skip
    rows = []
    for preset, p in data["presets"].items():
        for key, v in p["variants"].items():
            rows.append([
                f"`{preset}`", names.get(key, key),
                f"{num(v['bytes_per_iteration'] / 1e6, '.2f')} MB",
                num(v["it_per_s"], ",.0f"), f"{num(v['seconds_estimated'], '.1f')} s",
                num(v["gb_per_s"], ".1f"), f"{num(100 * v['share_of_one_thread_triad'], '.0f')} %",
            ])  # fmt: skip
        rows.append([f"`{preset}`", "dense reference kernel", "",
                     num(p["reference_it_per_s"], ",.1f"), "", "", ""])  # fmt: skip
    tri = data["triad"]
    note = (f"Triad (STREAM-like, same run): {num(tri['one_thread_gb_s'], '.1f')} GB/s on one "
            f"thread, {num(tri['all_threads_gb_s'], '.1f')} GB/s on all.")  # fmt: skip
    return Table(
        ["preset", "variant", "bytes / iteration", "iterations/s (whole run, estimated)",
         "100,000 in", "GB/s", "share of the one-thread triad"],
        rows, [_rel("bandwidth")], note, _command(data),
    )  # fmt: skip


INFERENCE = {
    "respond_one_random_us": ("`respond`, one pair (a new pair each call)", "us"),
    "respond_one_same_us": ("`respond`, the same pair again (weights in cache)", "us"),
    "winner_one_random_us": ("`winner`, one pair", "us"),
    "transform_one_random_us": ("`transform`, one pair", "us"),
    "respond_1000_ms": ("`respond`, 1,000 pairs", "ms"),
    "winner_1000_ms": ("`winner`, 1,000 pairs", "ms"),
    "evaluate_s": ("`evaluate` (10,000 test and calibration pairs, their data given)", "s"),
}


@table("inference")
def _inference() -> Table:
    data = load("inference")
    med = data["medians"]
    cols = [c for c in ("fast", "baseline", "reference") if c in med]
    rows = []
    for key, (label, unit) in INFERENCE.items():
        fmt = ",.0f" if unit == "us" else ".2f" if unit == "s" else ",.0f"
        cells = [f"{num(med[c][key], fmt)} {unit}" if key in med[c] else "" for c in cols]
        rows.append([label, *cells])
    heads = {"fast": "**fast kernel**", "baseline": "baseline (before the vectorised loops)",
             "reference": "dense reference"}  # fmt: skip
    return Table(["call", *(heads[c] for c in cols)], rows, [_rel("inference")],
                 f"Model: {data['model']['note']}.", _command(data))  # fmt: skip


FLOORS = {
    "respond_one_random_us": (
        "`respond`, one pair",
        "us",
        "read_one_random_us",
        "bandwidth_one_us",
    ),
    "winner_one_random_us": ("`winner`, one pair", "us", "read_one_random_us", "bandwidth_one_us"),
    "respond_1000_ms": ("`respond`, 1,000 pairs", "ms", None, "bandwidth_1000_ms"),
    "winner_1000_ms": ("`winner`, 1,000 pairs", "ms", None, "bandwidth_1000_ms"),
}


@table("inference-floors")
def _inference_floors() -> Table:
    data = load("inference-floors")
    med = data["medians"]["fast"]
    rows = []
    for key, (label, unit, read, band) in FLOORS.items():
        cells = [f"{num(med[key], ',.1f')} {unit}"]
        cells.append(f"{num(med[read], ',.1f')} {unit}" if read else "")
        cells.append(f"{num(med[band], ',.1f')} {unit}")
        cells.append(num(data["fast_over_floors"][f"{key}_over_{band}"], ".2f"))
        rows.append([label, *cells])
    note = (
        f"The fast kernel on a {data['model']['note']}; floors measured in the same processes: "
        f"a triad of {num(data['triad_one_thread_gb_s'], '.1f')} GB/s (one thread, median), "
        f"{num(med['bytes_one_mean'] / 1e6, '.2f')} MB of weight rows per pair."
    )
    return Table(["call", "measured", "reading its rows only", "its bytes at the triad's rate",
                  "measured / bytes at the triad"], rows, [_rel("inference-floors")], note,
                 _command(data))  # fmt: skip


@table("files")
def _files() -> Table:
    data = load("files")
    labels = {"v1": "format version 1 (float64 weights + the fast kernel's float32 copy)",
              "v2": "**version 2** (weights once, in the backend's precision)",
              "v2_compressed": "version 2, `save(path, compress=True)`"}  # fmt: skip
    rows = []
    for key, size in data["bytes"].items():
        t = data["median_seconds"][key]
        rows.append([labels.get(key, key), f"{num(size / 1e6, '.1f')} MB",
                     f"{num(t['save'], '.2f')} s", f"{num(t['load'], '.2f')} s"])  # fmt: skip
    note = (f"A paper-2d model on the `{data['backend']}` backend, {data['weights']:,} weights; "
            f"medians of {data['repeats']} rounds; version 2 round trip exact: "
            f"{'yes' if data['v2_round_trip_exact'] else 'no'}.")  # fmt: skip
    return Table(["file", "size", "save", "load"], rows, [_rel("files")], note,
                 ["python benchmarks/bench_files.py"])  # fmt: skip


@table("sweep-throughput")
def _sweep_throughput() -> Table:
    data = load("sweep")
    rows = []
    for key, label in (("one_at_a_time", "one run at a time"),
                       ("local_executor", "local executor")):  # fmt: skip
        v = data[key]
        rows.append(
            [
                label,
                str(v["workers"]),
                f"{num(v['wall_seconds'], '.1f')} s",
                num(v["runs_per_hour"], ".1f"),
                f"{num(v['median_train_seconds'], '.1f')} s",
            ]
        )
    note = (f"`{data['preset']}`, {data['seeds']} seeds of {data['iterations']:,} iterations; "
            f"speed-up {num(data['speedup'], '.2f')}x; the same metrics run for run: "
            f"{'yes' if data['same_metrics'] else 'no'}.")  # fmt: skip
    return Table(["engine", "workers", "wall", "runs / hour", "median training"], rows,
                 [_rel("sweep")], note, ["python benchmarks/bench_sweep.py"])  # fmt: skip


# baselines, chain, reach -------------------------------------------------------------------
COMPARE_NAMES = {"sigma-pi": '**Sigma-Pi map** (`ordering = "crossview"`)'}


@table("compare")
def _compare() -> Table:
    res = result("compare")
    data = res.to_dict()
    rows = []
    for m in data["methods"]:
        match = m["labels_to_match_sigma_pi"]
        per = m["per_seed"]["z_error"]
        rows.append([
            COMPARE_NAMES.get(m["name"], m["description"]), num(m["view_consistency"]),
            num(m["unit_consistency"]), f"{num(m['z_error'])} (worst {num(max(per))})",
            f"{m['labels_needed']:,}", "never" if match is None else f"{match:,}",
        ])  # fmt: skip
    cfg = res.config
    note = (f"`{cfg.preset}` task, {cfg.train_pairs:,} recorded view pairs per seed, seeds "
            f"{seeds_label(res.seeds)}, medians; z error with {m['labels_used']:,} labels, in "
            f"{data['z_error_unit']} (a map's winner alone cannot beat "
            f"{num(data['quantisation_floor'])}).")  # fmt: skip
    return Table(
        [
            "method",
            "same place",
            "same unit (no label)",
            "z error",
            "labels needed",
            "labels to match the map",
        ],
        rows,
        [_rel("compare")],
        note,
        _command(load("compare")),
    )


@table("chain")
def _chain() -> Table:
    res = result("chain")
    tables = [("chain", "**chain** (A's response -> B)", res)]
    if _path("chain-winner").is_file():
        winner = result("chain-winner")
        tables.append(("chain", "chain, A's winner as a population code", winner))
    tables.append(("single", "single map, third-order units", res))
    rows = []
    for route, label, r in tables:
        seeds = r.per_seed
        col = functools.partial(_column, [s[route] for s in seeds])
        rows.append([
            label, mw_of(col("z_error"), higher_is_better=False), mw_of(col("view_consistency")),
            mw_of(col("view_within_one")), mw_of(col("order_r2")), mw_of(col("usage"), ".2f"),
            f"{int(seeds[0][route]['weights']):,}",
            f"{num(statistics.median(col('train_seconds')), '.1f')} s",
        ])  # fmt: skip
    s = res.summary()
    note = (f"Seeds {seeds_label([r['seed'] for r in res.per_seed])}, {res.train_pairs:,} "
            f"view pairs of triples per seed; median / worst seed. The chain's z error over the "
            f"single map's: median {num(s['ratio_median'], '.2f')}, worst "
            f"{num(s['ratio_worst'], '.2f')}; {s['met']} of {s['n_seeds']} seeds within "
            f"{s['target_ratio']:g}x. Map A alone: order R² at least "
            f"{num(s['map_a_order_r2_min'])}.")  # fmt: skip
    return Table(["route", "z error", "same winner", "within one", "order R²", "usage",
                  "Sigma-Pi weights", "training (median)"], rows,
                 [_rel(n) for n in ("chain", "chain-winner") if _path(n).is_file()], note,
                 _command(load("chain")))  # fmt: skip


REACH_STATES = {
    "map": "learned Sigma-Pi map",
    "retina": "retina code only",
    "retina_gaze": "retina and gaze codes side by side",
    "true_z": "true z as a population code on the map's grid (upper bound)",
}


@table("reach")
def _reach() -> Table:
    res = result("reach")
    data = res.to_dict()
    rows = []
    for state, mean in data["success"].items():
        per = data["success_per_seed"][state]
        shown = f"**{num(mean)}**" if state == "map" else num(mean)
        rows.append([REACH_STATES.get(state, state), shown,
                     " ".join(num(v) for v in per), num(data["lost"][state]),
                     num(data["timed_out"][state])])  # fmt: skip
    run = res.config.run
    note = (f"Seeds {seeds_label(res.seeds)}; final success: the last "
            f"{run.final_episodes} of {run.episodes} episodes, mean over seeds; map / true z "
            f"{num(data['ratio_map_to_true_z'])}.")  # fmt: skip
    return Table(
        ["state the learner sees", "final success", "per seed", "lost the object", "timed out"],
        rows,
        [_rel("reach")],
        note,
        _command(load("reach")),
    )


@table("reach-maps")
def _reach_maps() -> Table:
    res = result("reach")
    ms = res.map_metrics
    keys = [k for k in ("order_r2", "view_within_one", "z_error", "usage", "fold_score")
            if all(k in m for m in ms)]  # fmt: skip
    rows = [[str(seed)] + [num(m[k]) for k in keys] for seed, m in zip(res.seeds, ms, strict=True)]
    return Table(["seed", *keys], rows, [_rel("reach")], "The map each seed's learner sees.")


# robot -------------------------------------------------------------------------------------
STATES = {"map": "learned map", "retina": "retina code", "retina_gaze": "retina and gaze codes",
          "true_z": "true z as a code (upper bound)"}  # fmt: skip


@table("robot-docking")
def _robot_docking() -> Table:
    return _docking("robot-docking")


@table("robot-docking-tuning")
def _robot_docking_tuning() -> Table:
    return _docking("robot-docking-tuning")


def _docking(name: str) -> Table:
    data = load(name)
    robot = result(name)
    res = robot.to_dict()
    rows = []
    for state, per_seed in res["success_per_seed"].items():
        med, worst = median_worst(per_seed)
        rows.append([STATES.get(state, state), f"{num(med, '.2f')} ({num(worst, '.2f')})",
                     " ".join(num(v, ".2f") for v in per_seed),
                     num(res["reach_given_docked"][state], ".2f")])  # fmt: skip
    note = (f"Seeds {seeds_label(robot.seeds)}; final success over the last "
            f"{robot.config.run.final_episodes} of {robot.config.run.episodes} episodes; "
            f"{num(data['cpu_s'] / 60, '.1f')} CPU minutes.")  # fmt: skip
    return Table(["state the learner sees", "success, median (worst seed)", "per seed",
                  "reach touching the ball, of docked"], rows, [_rel(name)], note,
                 _command(data))  # fmt: skip


@table("robot-map")
def _robot_map() -> Table:
    data = load("robot-map")
    groups: dict[float, list[dict[str, Any]]] = {}
    for r in data["rows"]:
        groups.setdefault(float(r["moved_share"]), []).append(r)
    rows = []
    for share, runs in sorted(groups.items()):
        col = functools.partial(_column, runs)
        rows.append(
            [
                f"{num(share, '.1f')}",
                seeds_label([r["seed"] for r in runs]),
                mw_of(col("order_r2")),
                mw_of(col("fold_score"), ".2f", False),
                f"{sum(bool(r['folded']) for r in runs)} of {len(runs)}",
                mw_of(col("view_within_one")),
                mw_of(col("z_error"), higher_is_better=False),
            ]
        )
    return Table(
        [
            "share of pairs spoiled (ball moved)",
            "seeds",
            "order R² (vs true z)",
            "fold score",
            "flagged folded",
            "view within one",
            "z error",
        ],
        rows,
        [_rel("robot-map")],
        "Each cell is median / worst seed.",
        _command(data),
    )


ROBOT_SPEED = {
    "no_render": "no rendering",
    "render": 'rendering both cameras every step (`render_mode="rgb_array"`)',
    "pixels": 'retina from the rendered head camera (`retina="pixels"`)',
    "learner_map": "the map learner's whole loop (map response, actor-critic)",
}


@table("robot-speed")
def _robot_speed() -> Table:
    data = load("robot-speed")
    this = data["summary"]["this"]
    rows = [[ROBOT_SPEED.get(k, k), num(v["steps_per_s_cpu"], ",.0f"),
             num(v["steps_per_s_wall"], ",.0f"), f"{num(v['max_rss_mb'], ',.0f')} MB"]
            for k, v in this.items() if isinstance(v, dict)]  # fmt: skip
    return Table(["`sigmapi/RobotDock-v0`", "steps per CPU second", "per wall second",
                  "peak memory"], rows, [_rel("robot-speed")],
                 f"Medians of {data['repeats']} runs.", _command(data))  # fmt: skip


# -- the markup ------------------------------------------------------------------------------
class ResultsTable(SphinxDirective):
    """``results-table NAME``: the table ``NAME`` of :data:`TABLES`, rendered from its files."""

    required_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        name = self.arguments[0]
        if name not in TABLES:
            raise self.error(f"no results table {name!r}; known: {', '.join(sorted(TABLES))}")
        try:
            # "median / worst" and seed ranges stay on one line in a narrow column
            text = TABLES[name]().markdown().replace(" / ", "\u00a0/\u00a0")
            text = re.sub(r"(?<=\d)-(?=\d)", "\u2011", text)
        except ExtensionError as e:
            raise self.error(f"results table {name!r}: {e}") from None
        for src in _sources_of(name):
            self.env.note_dependency(str(src))
        container = nodes.container(classes=["results-table"])
        self.state.nested_parse(StringList(text.splitlines(), source=f"results:{name}"),
                                self.content_offset, container)  # fmt: skip
        return [container]


def _sources_of(name: str) -> list[Path]:
    return sorted(p for p in [*RESULTS.glob("*.json"), ROOT / "docs" / "angles-sweep.csv"])


def _quote(value: Any, fmt: str) -> str:
    """A value as prose quotes it; a list (a ``*`` key) as ``range:FMT`` (``lo-hi``),
    ``min:FMT``, ``max:FMT`` or ``median:FMT``."""
    if isinstance(value, list):
        how, _, spec = fmt.partition(":")
        v = [float(x) for x in value]
        spec = spec or ".3g"
        if how == "range":
            return f"{num(min(v), spec)}-{num(max(v), spec)}"
        if how in ("min", "max", "median"):
            return num({"min": min, "max": max, "median": statistics.median}[how](v), spec)
        raise ValueError(f"a list needs the format range:, min:, max: or median:, got {fmt!r}")
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value)
    return num(value, fmt)


class ResultRole(SphinxRole):
    """``{result}`FILE:KEY.PATH|FORMAT```: one number of a results file, as text."""

    def run(self) -> tuple[list[nodes.Node], list[nodes.system_message]]:
        spec, _, fmt = self.text.partition("|")
        name, _, key = spec.partition(":")
        try:
            value = get(read(name.strip()), key.strip(), name)
            text = _quote(value, fmt or ".3g")
        except (ExtensionError, *_DATA_ERRORS) as e:
            what = f"no key {e}" if isinstance(e, KeyError) else str(e)
            msg = self.inliner.reporter.error(f"result {self.text!r}: {what}", line=self.lineno)
            return [self.inliner.problematic(self.rawtext, self.rawtext, msg)], [msg]
        self.env.note_dependency(str(_path(name.strip())))
        return [nodes.Text(text)], []


# -- the gallery -----------------------------------------------------------------------------
def _draws_figure(src: Path) -> bool:
    return re.search(r"add_argument\(\s*\"--out\"", src.read_text("utf-8")) is not None


def gallery_argv(src: Path, out_dir: Path) -> list[str]:
    """An example's arguments in the build: ``--small``, and ``--out FILE`` if it draws."""
    argv = ["--small"]
    if _draws_figure(src):
        out_dir.mkdir(parents=True, exist_ok=True)
        target = out_dir / f"{src.stem}.png"
        target.unlink(missing_ok=True)
        argv += ["--out", str(target)]
    return argv


def scrape_example_figure(
    block_vars: dict[str, Any], gallery_conf: dict[str, Any], out_dir: Path
) -> str:
    """The figure an example wrote to its ``--out`` file, moved into the gallery's images."""
    from sphinx_gallery.scrapers import figure_rst

    written = out_dir / f"{Path(block_vars['src_file']).stem}.png"
    if not written.is_file():
        return ""
    target = Path(next(block_vars["image_path_iterator"]))
    shutil.move(str(written), target)
    return figure_rst([str(target)], gallery_conf["src_dir"])


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("results-table", ResultsTable)
    app.add_role("result", ResultRole())
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}


import sigmapi_results_neurons  # noqa: E402, F401  (its tables register themselves)
