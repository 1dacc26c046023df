"""Parameter and seed sweeps: ``sigmapi sweep SPEC.toml --out DIR``.

A spec names a preset, the seeds, fields fixed for every run (``[set]``) and a grid of values
(``[grid]``); the sweep is the cross product of the grid and the seeds::

    preset = "tiny-1d"          # any preset; [set] fixes other fields for every run
    seeds = [0, 1]
    [set]
    ordering = "none"
    [grid]                      # the cross product of these values
    code_width = [0.5, 1.0]
    iterations = [2000, 3000]

Each run trains and evaluates one model (:func:`sigmapi.evaluate`), its row appended to
``DIR/results.csv`` as it finishes, so that a sweep started again runs only the missing runs
(:mod:`~sigmapi.experiments.sweep.table`). Runs go through :mod:`sigmapi.executor`, at most
:data:`MAX_RUNS` per spec; the table, what is refused and the engines: docs/guide/sweeps.md.

The experiment ``sweep`` (:class:`Sweep`, settings :class:`SweepConfig`: the spec file) is
:func:`run_sweep` on the command line; seeds given to it replace the spec's.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sigmapi import _validate
from sigmapi._lock import output_lock
from sigmapi._outputs import INPUT, claim_folder
from sigmapi.config import SOMConfig, check_map_fits_task, load_preset, parse_toml
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, Outcome, job_memory
from sigmapi.experiments.base import RESULT_FILE, Experiment, Run, check_seeds, register
from sigmapi.experiments.kit.results import Result
from sigmapi.experiments.sweep.figures import METRICS, draw_summary
from sigmapi.experiments.sweep.table import (
    METRIC_COLUMNS,
    RESULTS,
    append_row,
    open_table,
    read_table,
    run_key,
    typed,
)
from sigmapi.metrics import evaluate
from sigmapi.metrics.circular import CIRCULAR_KEYS
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.tasks import get_relation

FIGURE = "sweep.png"
"""The sweep's summary figure in its output folder."""

MAX_RUNS = 10_000
"""Most runs (grid points x seeds) one spec may name; a larger sweep is several specs, each
in its own --out folder (or several machines: engine dask)."""


@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep: the grid point ``params``, the ``seed``, the grid point's resolved
    config (``point``; :attr:`config` adds the seed) and its identity ``run_key``
    (:func:`~sigmapi.experiments.sweep.table.run_key`)."""

    run_id: str
    run_key: str
    params: dict[str, object]
    seed: int
    point: SOMConfig
    n_test: int

    @property
    def config(self) -> SOMConfig:
        """The run's config: the grid point's with the run's seed."""
        return self.point.replace(seed=self.seed)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep spec (module docstring); :meth:`runs` lists the cross product.

    Grid values are stored as the config resolves them, each once (``[0.5, 1, 1.0]`` is
    ``[0.5, 1.0]``), so that one config has one name.
    """

    preset: str
    seeds: tuple[int, ...]
    grid: dict[str, list[object]]
    fixed: dict[str, object] = field(default_factory=dict)
    n_test: int = 2000

    @classmethod
    def from_toml(cls, text: str, source: str = "sweep spec") -> SweepSpec:
        """Parse and check a spec; every grid point must make a valid config."""
        return cls.from_dict(parse_toml(text, source), source)

    @classmethod
    def from_dict(cls, data: object, source: str = "sweep spec") -> SweepSpec:
        """Check a spec given as its TOML file's table (what :meth:`to_dict` writes)."""
        if not isinstance(data, dict):
            raise ConfigError(f"{source} must be a table of keys, got {type(data).__name__}")
        unknown = sorted(set(data) - {"preset", "seeds", "set", "grid", "n_test"})
        if unknown:
            raise ConfigError(
                f"{source}: unknown key {unknown[0][:60]!r}; a spec has preset, "
                "seeds, n_test, [set] and [grid]"
            )
        preset = data.get("preset")
        if not isinstance(preset, str):
            raise ConfigError(
                f"{source}: preset must be a preset name, got {preset!r:.60}; "
                'e.g. preset = "tiny-1d"'
            )
        seeds = check_seeds(data.get("seeds", [0]), f"{source}: seeds")
        grid = data.get("grid", {})
        if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
            raise ConfigError(
                f"{source}: [grid] must map each field to a non-empty list of values, got "
                f"{grid!r:.200}; e.g. code_width = [0.5, 1.0]"
            )
        fixed = data.get("set", {})
        if not isinstance(fixed, dict):
            raise ConfigError(f"{source}: [set] must be a table of fields, got {fixed!r:.200}")
        both = sorted(set(fixed) & set(grid))
        if both:
            raise ConfigError(f"{source}: {both[0]!r} is both in [set] and in [grid]; keep one")
        if "seed" in grid or "seed" in fixed:
            raise ConfigError(f"{source}: give seeds with seeds = [...], not as a field")
        n_test = data.get("n_test", 2000)
        if not isinstance(n_test, int) or isinstance(n_test, bool) or not 2 <= n_test <= 10**7:
            raise ConfigError(
                f"{source}: n_test must be an int in [2, 10000000], got {n_test!r:.60}"
            )
        base = _base(preset, fixed, source)
        resolved = {}
        for key in sorted(grid):  # each value once, as the config resolves it
            values: dict[str, object] = {}
            for value in grid[key]:
                try:
                    got = SOMConfig.from_dict({**base, key: value}).to_dict()[key]
                except (ConfigError, TypeError) as exc:
                    raise ConfigError(f"grid point {key} = {value!r:.60}: {exc}") from None
                values.setdefault(json.dumps(got, sort_keys=True), got)
            resolved[key] = list(values.values())
        spec = cls(preset, seeds, resolved, fixed, n_test)
        spec.count()  # bounded; a point invalid only jointly fails in runs(), before any run
        return spec

    @classmethod
    def read(cls, path: str | Path) -> SweepSpec:
        p = Path(path)
        if not p.is_file():
            raise ConfigError(
                f"sweep spec {str(p)!r} does not exist or is not a file; check the path"
            )
        if p.stat().st_size > 1 << 20:
            raise ConfigError(
                f"sweep spec {str(p)!r} is over 1 MB; a spec is a short TOML "
                "file (module sigmapi.experiments.sweep.run)"
            )
        try:
            text = p.read_bytes().decode("utf-8-sig")  # a byte order mark is no key
        except UnicodeDecodeError as exc:
            raise ConfigError(
                f"sweep spec {str(p)!r} is not UTF-8 text (byte {exc.start}); save it as UTF-8"
            ) from None
        return cls.from_toml(text, f"sweep spec {str(p)!r}")

    def to_dict(self) -> dict[str, object]:
        """The spec as its TOML file holds it (``set`` for :attr:`fixed`)."""
        return {
            "preset": self.preset,
            "seeds": list(self.seeds),
            "n_test": self.n_test,
            "set": self.fixed,
            "grid": self.grid,
        }

    def count(self) -> int:
        """The number of runs (grid points x seeds); over :data:`MAX_RUNS` raises ConfigError."""
        n = math.prod(len(v) for v in self.grid.values()) * len(self.seeds)
        if n > MAX_RUNS:
            sizes = " x ".join(f"{len(v)} {k}" for k, v in sorted(self.grid.items()))
            raise ConfigError(
                f"the sweep names {n:,} runs ({sizes or 'no grid'} x {len(self.seeds)} seeds), "
                f"more than {MAX_RUNS:,}; split it into several specs, each with its own --out"
            )
        return n

    def runs(self) -> list[SweepRun]:
        """Every (grid point, seed), grid-major; configs checked here (ConfigError names the
        grid point)."""
        self.count()
        base = _base(self.preset, self.fixed, "sweep spec")
        keys = sorted(self.grid)
        out = []
        for values in itertools.product(*(self.grid[k] for k in keys)):
            params = dict(zip(keys, values, strict=True))
            try:
                cfg = check_map_fits_task(SOMConfig.from_dict({**base, **params}))  # as train
            except (ConfigError, TypeError) as exc:
                raise ConfigError(f"grid point {params}: {exc}") from None
            resolved = cfg.to_dict()
            for seed in self.seeds:
                rid = json.dumps({**params, "seed": seed}, sort_keys=True)
                key = run_key(resolved, seed, self.n_test)
                out.append(SweepRun(rid, key, params, seed, cfg, self.n_test))
        return out


def _base(preset: str, fixed: Mapping[str, object], source: str) -> dict[str, object]:
    """The preset with the spec's ``[set]``, checked."""
    base = load_preset(preset).to_dict()
    try:
        return SOMConfig.from_dict({**base, **fixed}).to_dict()
    except (ConfigError, TypeError) as exc:
        raise ConfigError(f"{source}: [set]: {exc}") from None


def sweep_job(run: SweepRun) -> dict[str, object]:
    """Train and evaluate one run (a job of the executor); its metrics and seconds."""
    t0 = time.perf_counter()
    model = SigmaPiSOM(run.config).fit()
    train = time.perf_counter() - t0
    metrics = evaluate(model, n_test=run.n_test).to_dict()
    return {**metrics, "train_seconds": train, "total_seconds": time.perf_counter() - t0}


def read_results(path: str | Path) -> list[dict[str, str]]:
    """The rows of a sweep table (strings, as written; the last row of each run, in file
    order); ``[]`` if there is none yet. A damaged table raises ConfigError."""
    table = read_table(path)
    return [] if table is None else list(table.rows.values())


def _row(run: SweepRun, outcome: Outcome) -> dict[str, object]:
    row = {"run_id": run.run_id, "run_key": run.run_key, **run.params, "seed": run.seed}
    if outcome.ok:
        return {**row, **outcome.value, "status": "ok", "error": ""}
    error = " ".join(str(outcome.error).split())[:2000]  # one line, bounded
    return {**row, "status": "failed", "error": error, "total_seconds": round(outcome.seconds, 3)}


def _job_memory(runs: Sequence[SweepRun]) -> int:
    """The largest job's memory (:func:`~sigmapi.executor.job_memory`), estimated once per
    distinct model size."""
    seen: dict[tuple[object, ...], int] = {}
    for r in runs:
        c = r.point
        size = (c.map_shape, c.x_shape, c.y_shape, c.backend, c.kernel_tol, r.n_test)
        if size not in seen:
            seen[size] = job_memory(c, r.n_test)
    return max(seen.values(), default=1)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    *,
    engine: str = "local",
    workers: int | None = None,
    memory_budget: int | None = None,
    address: str | None = None,
    retry_failed: bool = False,
    add: bool = False,
    on_plan: Callable[[int, int, str], None] | None = None,
    on_done: Callable[[bool, str], None] | None = None,
    executor: Executor | None = None,
) -> list[dict[str, object]]:
    """Run the missing runs of ``spec``, appending each to ``out/results.csv``; this spec's rows.

    ``engine``, ``workers``, ``memory_budget`` (bytes) and ``address`` say where the runs go
    (:class:`~sigmapi.executor.Executor`), unless ``executor`` is given. A table there that
    holds runs of another spec is refused unless ``add``
    (:func:`~sigmapi.experiments.sweep.table.open_table`). ``on_plan(n_to_run, n_skipped,
    reason)`` is called once before the first run and ``on_done(ok, line)`` after each.
    """
    if executor is None:
        executor = Executor(engine, workers, address, memory_budget)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"out {str(out)!r} is a file; give a folder for the sweep's table")
    out.mkdir(parents=True, exist_ok=True)
    with output_lock(out, f"--out folder {str(out)!r}"):
        claim_folder(out, "sweep", force=False, owns=(RESULTS,))  # no other run's files lost
        path = out / RESULTS
        runs = spec.runs()
        angles = any(get_relation(r.point.relation).circular for r in runs)
        metrics = (*METRIC_COLUMNS, *(CIRCULAR_KEYS if angles else ()))
        timed = ("train_seconds", "total_seconds", "status", "error")
        columns = ["run_id", "run_key", *sorted(spec.grid), "seed", *metrics, *timed]
        for name in (FIGURE, RESULT_FILE):  # what is written after the runs: checked before them
            if (out / name).exists() and not (out / name).is_file():
                raise ConfigError(
                    f"{str(out / name)!r} is not a file (a folder?); the sweep writes it after its "
                    "runs: move it away or give a new --out"
                )
        executor.check()
        have = open_table(path, columns, {r.run_key for r in runs}, add=add)
        keep = {"ok", "failed"} if not retry_failed else {"ok"}
        done = {k: r for k, r in have.items() if r["status"] in keep}
        todo = [r for r in runs if r.run_key not in done]
        plan = executor.plan(_job_memory(todo), len(todo))
        if on_plan is not None:
            on_plan(len(todo), len(runs) - len(todo), plan.reason)
        by_id = {r.run_key: r for r in todo}
        rows: dict[str, dict[str, Any]] = dict(have)
        for outcome in executor.run(sweep_job, [(r.run_key, r) for r in todo], plan.workers):
            run = by_id[outcome.key]
            row = _row(run, outcome)
            append_row(path, columns, row)
            rows[run.run_key] = {c: row.get(c, "") for c in columns}
            if on_done is not None:
                what = ", ".join(f"{k} {v}" for k, v in run.params.items())
                text = (
                    f"order R^2 {row['order_r2']:.3f}{', FOLDED' if row['folded'] else ''}"
                    if outcome.ok
                    else f"FAILED: {outcome.error}"
                )
                on_done(outcome.ok, f"{what}, seed {run.seed}: {text} ({outcome.seconds:.0f} s)")
        return [rows[r.run_key] for r in runs if r.run_key in rows]


# ------------------------------------------------------------------ the experiment


@dataclass(frozen=True)
class SweepConfig:
    """What ``sigmapi sweep`` runs: a spec file, and how failed runs and the figure are handled."""

    spec: str = field(metadata=INPUT)
    """The sweep spec, a TOML file: preset, seeds, n_test, [set] and [grid] (see
    :mod:`sigmapi.experiments.sweep.run`); its seeds are the sweep's default seeds."""
    retry_failed: bool = False
    """Run failed runs again (otherwise finished runs, failed or not, are kept)."""
    add: bool = False
    """Add this spec's runs to an --out table that holds another spec's runs (its rows are
    kept; otherwise such a table is refused)."""
    metric: str = "order_r2"
    """The metric of the summary figure (a column of the table)."""

    def __post_init__(self) -> None:
        _validate.choice("metric", self.metric, METRICS)
        self.read_spec().runs()  # a missing or bad spec, or grid point, fails here: before any work

    def read_spec(self) -> SweepSpec:
        """The parsed spec (:meth:`SweepSpec.read`)."""
        return SweepSpec.read(self.spec)


@dataclass
class SweepResult(Result):
    """The table of a sweep (every run of its spec, in grid order) and its settings."""

    spec: SweepSpec
    rows: list[dict[str, object]]
    metric: str = "order_r2"

    KEYS = ("spec", "table: table_file", "runs", "failed", "rows: typed_rows")
    """The JSON form: the spec, the table's file, the counts of runs and failed ones, and
    the table's rows, typed."""
    table_file = RESULTS

    @classmethod
    def from_dict(cls, data: object) -> SweepResult:
        """The result a :meth:`to_dict` wrote (``result.json``): its spec and rows."""
        if not isinstance(data, dict) or not isinstance(data["rows"], list):
            raise TypeError("a sweep's result must be a JSON object with a list of rows")
        return cls(SweepSpec.from_dict(data["spec"], "the result's spec"), list(data["rows"]))

    def typed_rows(self) -> list[dict[str, object]]:
        """The table's rows, each value typed (:func:`~sigmapi.experiments.sweep.table.typed`)."""
        return [{k: typed(v) for k, v in r.items()} for r in self.rows]

    def runs(self) -> int:
        return len(self.rows)

    def failed(self) -> int:
        return sum(r.get("status") != "ok" for r in self.typed_rows())

    def table(self) -> str:
        """Per grid point: the runs that finished and the median of :attr:`metric` over them."""
        keys = sorted(self.spec.grid)
        points: dict[str, list[float]] = {}
        for r in self.rows:
            point = ", ".join(f"{k} {r[k]}" for k in keys) or self.spec.preset
            value = typed(r.get(self.metric))
            finished = points.setdefault(point, [])
            if str(r.get("status")) == "ok" and isinstance(value, (int, float)):
                finished.append(float(value))
        lines = [f"{'grid point':40s} {'ok runs':>7s} {self.metric:>12s} (median)"]
        for point, values in points.items():
            median = f"{statistics.median(values):12.3f}" if values else f"{'-':>12s}"
            lines.append(f"{point:40s} {len(values):7d} {median}")
        lines.append(f"{len(self.rows)} runs, {self.failed()} failed; the table: {RESULTS}")
        return "\n".join(lines)

    def figure(self, out_dir: Path) -> list[Path]:
        """The summary figure, ``sweep.png`` (:func:`draw_summary`)."""
        return [draw_summary(self.spec, self.rows, Path(out_dir) / FIGURE, self.metric)]


class Sweep(Experiment[SweepConfig]):
    """Train and evaluate the cross product of a grid of parameters and the seeds of a spec
    file; the table is written after every run, so that a sweep started again in the same
    folder runs only the missing runs."""

    name = "sweep"
    summary = "train and evaluate a grid of parameters x seeds"
    config_type = SweepConfig
    default_out = "sweep"
    resumes = True
    writes = (FIGURE,)
    """The file written into --out besides the table and result.json (checked first)."""
    owns = (RESULTS,)
    """What an unmarked folder may hold: a table (checked strictly by the sweep itself)."""

    def default_seeds(self, config: SweepConfig, *, quick: bool = False) -> tuple[int, ...]:
        """The spec's seeds."""
        return config.read_spec().seeds

    def execute(self, config: SweepConfig, run: Run) -> SweepResult:
        """Run the missing runs of the spec (with ``seeds``) into ``out`` (required)."""
        out = run.out
        if out is None:
            raise ConfigError(
                "out must be a folder for the sweep's table, got None; the table "
                "is written there after every run"
            )
        spec = dataclasses.replace(config.read_spec(), seeds=run.seeds)
        ex = run.executor if run.executor is not None else Executor(workers=1)
        show = Progress.of(run.progress)
        bars: list[tuple[Callable[[bool, str], None], Any]] = []  # the bar, once planned

        def on_plan(n_run: int, n_skip: int, reason: str) -> None:
            show.note(
                f"sweep: {n_run + n_skip} runs, {n_skip} finished already, {n_run} to "
                f"run; engine {ex.engine}, {reason}"
            )
            bars.append(show.jobs(n_run, "sweep"))

        try:
            rows = run_sweep(
                spec,
                out,
                retry_failed=config.retry_failed,
                add=config.add,
                on_plan=on_plan,
                on_done=lambda ok, line: bars[0][0](ok, line),
                executor=ex,
            )
        finally:
            for _, bar in bars:
                bar.close()
        return SweepResult(spec, rows, config.metric)


SWEEP = register(Sweep())
