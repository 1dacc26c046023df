"""``sigmapi stream``: learning from a stream of frames against learning from explicit pairs.

A robot does not receive view pairs known to share z: it receives a stream in which the object
stays put for a few saccades (the dwell time ``d``) and then moves at moments nobody marks
(:meth:`sigmapi.tasks.TwoViewSampler.stream`), so the consecutive frames that straddle a move
are wrong pairs. Per seed this experiment trains

- **pairs**: the map on explicit view pairs of one z (:meth:`~sigmapi.SigmaPiSOM.fit` on the
  built-in task), the reference;
- **stream, trace lam**, for each dwell time ``d`` and trace constant ``lam``: the same config
  on ``iterations + 1`` frames of the stream (:meth:`~sigmapi.SigmaPiSOM.fit_stream`, the
  trace rule of :mod:`sigmapi.rules.trace`). All trace constants of one ``(seed, d)`` see the
  same frames.

and scores every map by :func:`sigmapi.evaluate` (view consistency, z error, order R^2, fold
score). ``"methods"`` holds one entry per method and dwell time: medians, worst seed and the
per-seed values; ``"acceptance"`` the comparison with pairs seed by seed at ``d >= 4``.

One module, read top to bottom: the settings (:class:`StreamConfig`, :data:`QUICK`), the
result (:class:`StreamResult`: its JSON form, table and figure, drawn by :mod:`.figures`), the
run (:class:`StreamExperiment`, one job per seed and dwell time).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.executor import job_memory
from sigmapi.experiments.base import KEY_VALUES, register
from sigmapi.experiments.kit.jobs import SeedJob, SeedRuns, Tick, iterations_counted
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.results import (
    VC_MARGIN,
    Column,
    Result,
    as_object,
    columns,
    margin_case,
    margin_line,
    plain,
    render,
    tuples,
)
from sigmapi.experiments.kit.seeds import SeedPlan, check_seeds
from sigmapi.metrics import evaluate
from sigmapi.model.som import SigmaPiSOM

# -- the settings ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class StreamConfig:
    """What ``sigmapi stream`` trains and scores."""

    preset: str = "paper-1d"
    """The task and the map's settings (a preset name; ``sigmapi presets``)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    dwells: tuple[int, ...] = field(
        default=(1, 2, 4, 8, 16),
        metadata=_validate.bounded("ints", 1, 100_000, fix="saccades per position", sep=","),
    )
    """Dwell times: saccades (frames) per object position."""
    traces: tuple[float, ...] = field(
        default=(0.0, 0.5),
        metadata=_validate.bounded(
            "numbers", 0, 1, hi_open=True, fix="trace constants in [0, 1), e.g. --traces 0,0.5"
        ),
    )
    """Trace constants of the trace rule (0: the two-view rule on consecutive frames)."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", 10, 1_000_000, fix="e.g. 10000")
    )
    """Test z's (and calibration z's) of the evaluation."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", tuple(self.overrides))
        _validate.check_fields(self)  # each dwell time and trace constant within its bounds
        for name, what, fix in (
            ("dwells", "dwell time", "e.g. --dwells 1,2,4,8,16"),
            ("traces", "trace constant", "e.g. --traces 0,0.5"),
        ):
            if not getattr(self, name):
                raise _validate.fail(name, f"at least one {what}", [], fix)
            object.__setattr__(self, name, tuple(sorted(set(getattr(self, name)))))
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with the overrides: the task and the map's settings."""
        return MapSpec(self.preset, self.overrides).config()


QUICK = StreamConfig(
    overrides=("iterations=20000", "refine_pairs=20000"), dwells=(1, 4, 16), n_test=2000
)
"""The quick look: a short run of the 1-D map, three dwell times, one seed."""


# -- the result: its JSON form, table and figure ---------------------------------------------------

METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "fold_score")
"""The scores of each map (:func:`sigmapi.evaluate`), besides ``folded``."""

PER_SEED = (*METRICS, "folded", "seconds")
"""The values of each map that ``"methods"`` keeps per seed."""


MIN_DWELL = 4
"""Acceptance: the dwell times it applies to (``d >= MIN_DWELL``)."""

COLUMNS = columns(
    "name:20s dwell:>5 view_consistency:9.3f view_consistency_worst:6.3f z_error:8.3f",
    "order_r2:9.3f order_r2_worst:6.3f",
    Column("folded", lambda m: f"{m['n_seeds'] - m['ordered']:3d}/{m['n_seeds']:<3d}", ">7s"),
)
"""The table's columns: one row per method and dwell time (medians, worst seeds)."""


@dataclass(frozen=True)
class MapRun:
    """One map's scores (:meth:`StreamExperiment.seed_run`; ``dwell`` None: the map on pairs)."""

    seed: int
    dwell: int | None
    trace: float | None
    view_consistency: float
    view_within_one: float
    z_error: float
    order_r2: float
    fold_score: float
    folded: bool
    seconds: float


@dataclass
class StreamResult(Result):
    """Every map's scores (:class:`MapRun`) and the settings they ran with."""

    config: StreamConfig
    seeds: tuple[int, ...]
    runs: list[MapRun]
    seconds: float

    KEYS = ("methods", "acceptance", "settings", "seconds")
    """The JSON form: :meth:`methods`, :meth:`acceptance`, :meth:`settings` and the whole
    run's wall time."""
    FIGURE = "stream.png"
    DRAWN_BY = "sigmapi.experiments.stream.figures:stream_figure"

    @classmethod
    def from_dict(cls, data: object) -> StreamResult:
        """The result a :meth:`to_dict` wrote (e.g. read back from ``result.json``): its runs
        from the values per seed, so that a result read back has its table and figure."""
        obj = as_object(data)
        st, seeds = obj["settings"], tuple(obj["settings"]["seeds"])
        names = (f.name for f in dataclasses.fields(StreamConfig))
        config = StreamConfig(**tuples({k: st[k] for k in names}))
        runs = [
            MapRun(seed, m["dwell"], m["trace"], **{k: m["per_seed"][k][i] for k in PER_SEED})
            for m in obj["methods"]
            for i, seed in enumerate(seeds)
        ]
        return cls(config, seeds, runs, float(obj["seconds"]))

    @classmethod
    def combine(cls, parts: Sequence[StreamResult]) -> StreamResult:
        """The runs of several results of one config on different seeds, as one result (its
        ``seconds`` the sum of theirs)."""
        if not parts or any(p.config != parts[0].config for p in parts):
            raise ConfigError("results to combine must share one config (and be at least one)")
        seeds = check_seeds([s for p in parts for s in p.seeds], "seeds of the results")
        runs = [r for p in parts for r in p.runs]
        return cls(parts[0].config, seeds, runs, sum(p.seconds for p in parts))

    def _rows(self, trace: float | None, dwell: int | None) -> list[MapRun]:
        rows = [r for r in self.runs if r.trace == trace and r.dwell == dwell]
        return sorted(rows, key=lambda r: self.seeds.index(r.seed))

    def methods(self) -> list[dict[str, object]]:
        """One entry per method and dwell time: ``name``, ``dwell`` (None for pairs),
        ``trace``, the median of each metric, its worst seed (``*_worst``: lowest view
        consistency and order, highest z error and fold score), ``fold_rate``, ``ordered``
        (seeds not folded), ``n_seeds`` and ``per_seed`` (the values in seed order)."""
        keys = [(None, None)] + [(t, d) for t in self.config.traces for d in self.config.dwells]
        out = []
        for trace, dwell in keys:
            rows = self._rows(trace, dwell)
            name = "pairs" if trace is None else f"stream trace {trace:g}"
            entry: dict[str, object] = {"name": name, "dwell": dwell, "trace": trace}
            for k in METRICS:
                vals = [getattr(r, k) for r in rows]
                worst = max(vals) if k in ("z_error", "fold_score") else min(vals)
                entry.update({k: float(np.median(vals)), f"{k}_worst": float(worst)})
            folded = [r.folded for r in rows]
            entry.update(
                fold_rate=float(np.mean(folded)),
                ordered=int(len(rows) - sum(folded)),
                n_seeds=len(rows),
                per_seed={k: [getattr(r, k) for r in rows] for k in PER_SEED},
            )
            out.append(entry)
        return out

    def acceptance(self) -> dict[str, object]:
        """Per trace constant and dwell time ``>= MIN_DWELL``: the view consistency of the
        stream minus that of pairs, seed by seed (median, worst), how many seeds are within
        :data:`VC_MARGIN` and ordered, and whether every seed is."""
        return {"margin": VC_MARGIN, "min_dwell": MIN_DWELL, "cases": self.cases()}

    def cases(self) -> list[dict[str, Any]]:
        """The cases of :meth:`acceptance`, trace constant-major: ``trace``, ``dwell`` and
        :func:`~sigmapi.experiments.kit.results.margin_case` of their gaps."""
        pairs = {r.seed: r for r in self._rows(None, None)}
        out = []
        for trace in self.config.traces:
            for dwell in (d for d in self.config.dwells if d >= MIN_DWELL):
                rows = self._rows(trace, dwell)
                gap = [r.view_consistency - pairs[r.seed].view_consistency for r in rows]
                margin = margin_case(gap, [r.folded for r in rows])
                out.append({"trace": trace, "dwell": dwell, **margin})
        return out

    def settings(self) -> dict[str, object]:
        """The config, the seeds and the resolved map config."""
        config = self.config
        return {**plain(config), "seeds": self.seeds, "config": config.som_config.to_dict()}

    def table(self) -> str:
        """Medians per method and dwell time, then the acceptance lines."""
        cases = [(c, margin_line(c, "view consistency of pairs")) for c in self.cases()]
        lines = [f"trace {c['trace']:g}, dwell {c['dwell']}: {text}" for c, text in cases]
        return "\n".join(render(COLUMNS, self.methods()) + lines)

    def caption(self) -> str:
        """The figure's caption, computed from the result."""
        pairs = self.methods()[0]
        n = len(self.seeds)
        best = max(self.cases(), key=lambda c: (c["met"], c["vc_gap_median"]), default=None)
        text = (
            f"{self.config.preset}, {n} seed{'s' * (n > 1)} ({', '.join(map(str, self.seeds))}): "
            f"view consistency and fold rate of maps learned from a stream in which the object "
            f"stays for d saccades, against explicit pairs (median "
            f"{pairs['view_consistency']:.3f}, {pairs['ordered']} of {n} ordered). Lines: "
            f"medians over seeds; bands: best to worst seed."
        )
        if best is not None:
            text += (
                f" At d >= {MIN_DWELL} the closest is trace {best['trace']:g} at d = "
                f"{best['dwell']}: {best['met']} of {best['n_seeds']} seeds within "
                f"{VC_MARGIN} of pairs and ordered (median gap {best['vc_gap_median']:+.3f})."
            )
        return text


# -- the run: one job per seed and dwell time ------------------------------------------------------

PLAN = SeedPlan({"frames": 7})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the frames of
dwell time d, ``SeedSequence(seed, spawn_key=(7, d))``, apart from the model's own streams."""


@dataclass(frozen=True)
class StreamJob(SeedJob):
    """One job of the experiment (``shared``: the map's config): the map on pairs when
    ``dwell`` is None, else one map per trace constant on the stream of ``(seed, dwell)``."""

    dwell: int | None = None


class StreamExperiment(SeedRuns[StreamConfig]):
    """Maps learned from a stream of frames (the trace rule) over dwell times and trace
    constants, against the map learned from explicit pairs, on the same seeds."""

    name = "stream"
    summary = "learning from a stream of frames (trace rule) against explicit view pairs"
    config_type = StreamConfig
    quick = QUICK
    seeds = tuple(range(800, 810))
    quick_seeds = (0,)
    quick_time = "about 45 s on two busy cores"
    default_out = "stream"
    writes = StreamResult.figure_names()
    unit = "it"

    def check(self, config: StreamConfig) -> int:
        """One job's memory: the map's and its stream's frames (two codes, float64)."""
        cfg = config.som_config
        frames = 16 * (cfg.iterations + 1) * (int(np.prod(cfg.x_shape)) + int(np.prod(cfg.y_shape)))
        return job_memory(cfg, config.n_test) + frames

    def prepare(self, config: StreamConfig, progress: object) -> SOMConfig:
        return config.som_config  # every job's map

    def jobs(
        self, config: StreamConfig, seeds: tuple[int, ...], shared: object
    ) -> list[tuple[str, Any]]:
        """One job per seed on pairs, then one per seed and dwell time."""
        jobs = [(f"seed {s} pairs", StreamJob(config, s, shared=shared)) for s in seeds]
        return jobs + [
            (f"seed {s} dwell {d}", StreamJob(config, s, shared=shared, dwell=d))
            for s in seeds
            for d in config.dwells
        ]

    def steps(self, job: StreamJob) -> int:
        maps = 1 if job.dwell is None else len(job.config.traces)
        return maps * job.shared.iterations

    def desc(self, job: StreamJob) -> str:
        return f"stream seed {job.seed} " + ("pairs" if job.dwell is None else f"dwell {job.dwell}")

    def describe(self, key: str, value: list[MapRun]) -> str:
        return f"{key}: same unit " + ", ".join(f"{r.view_consistency:.3f}" for r in value)

    def seed_run(self, job: StreamJob, tick: Tick | None) -> list[MapRun]:
        """Train and score the maps of one job (:class:`StreamJob`), one :class:`MapRun` each."""
        cfg, its = job.shared, job.shared.iterations

        def scored(model: SigmaPiSOM, trace: float | None, start: float) -> MapRun:
            m = evaluate(model, n_test=job.config.n_test)
            scores = {k: float(getattr(m, k)) for k in METRICS}
            seconds = time.perf_counter() - start
            return MapRun(
                job.seed, job.dwell, trace, **scores, folded=bool(m.folded), seconds=seconds
            )

        if job.dwell is None:
            start = time.perf_counter()
            model = SigmaPiSOM(cfg, seed=job.seed)
            return [scored(model.fit(callback=iterations_counted(tick, "pairs", its)), None, start)]
        model = SigmaPiSOM(cfg, seed=job.seed)
        frames = model.sampler.stream(its + 1, job.dwell, PLAN.rng(job.seed, "frames", job.dwell))
        xy = (frames.x, frames.y)  # every trace constant learns from the same frames
        out = []
        for lam in job.config.traces:
            start = time.perf_counter()
            counter = iterations_counted(tick, f"trace {lam:g}", its)
            model = SigmaPiSOM(cfg, seed=job.seed).fit_stream(xy, trace=lam, callback=counter)
            out.append(scored(model, lam, start))
        return out

    def collect(
        self, config: StreamConfig, seeds: tuple[int, ...], values: list[Any]
    ) -> StreamResult:
        return StreamResult(config, seeds, [r for rows in values for r in rows], 0.0)


STREAM = register(StreamExperiment())
