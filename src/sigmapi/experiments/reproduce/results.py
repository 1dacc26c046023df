"""What the reproduction run takes and gives: its options (:class:`ReproduceConfig`, the
command-line options; :class:`ReproduceOptions`) and typed results (:class:`ReproduceResult`,
``metrics.json``); the report's sections are :mod:`sigmapi.experiments.kit.report`'s.
"""

from __future__ import annotations

import shutil
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.experiments.base import check_seeds
from sigmapi.experiments.kit.results import Result, as_object
from sigmapi.metrics import ORDERED_R2, Metrics

METRIC_KEYS = ("view_consistency", "view_within_one", "z_error", "order_r2", "usage", "fold_score")
"""The metrics the report tabulates (median, worst seed, mean and sd over seeds)."""

WORSE_IS_LARGER = ("z_error", "fold_score")
"""Metrics whose worst seed has the largest value (the others: the smallest)."""

Stage = Literal["refined", "unrefined"]
"""Which map of a run: at its end (``refined``, after the refinement where the preset has
one) or at the end of the training, before the refinement (``unrefined``)."""


def plural(n: int) -> str:
    """The plural ending of a word counted ``n`` times ("s" unless one)."""
    return "s" if n != 1 else ""


SaveModels = Literal["shown", "all", "none"]
SAVE_MODELS: tuple[str, ...] = get_args(SaveModels)
"""Which trained models the report writes: the one the figures show, all, or none."""

N_CHECKPOINTS = 20
"""Checkpoints of the learning curves per run (log-spaced); ``quick``: :data:`QUICK_SIZES`."""

CURVE_TEST = 1000
"""Test (and calibration) set size at each learning-curve checkpoint."""

N_TEST = 10_000
"""Test set size of the final metrics."""

OTHER_PROCEDURE = {"paper-1d": "paper-1d-authors", "paper-2d": "paper-2d-authors"}
"""Each paper preset (sigmapi's procedure: ordered start, then refinement) beside the
authors' procedure at the same sizes (random start, no refinement), on the same seeds."""

REPORT = "report.html"
"""The report's page in its folder."""

QUICK_SIZES = {"n_checkpoints": 12, "curve_test": 300, "n_test": 2000}
"""Smaller measurements of ``quick`` runs (checkpoints, their test sets, the final test set)."""


@dataclass(frozen=True)
class ReproduceConfig:
    """What one reproduction run measures and writes (the seeds are given apart)."""

    quick: bool = False
    """Fewer iterations per preset, smaller measurements: a first look."""
    save_models: SaveModels = "shown"
    """Which trained models to write beside the report: the one the figures show (the
    worst-ordered seed), all, or none."""
    seeds_2d: int | None = field(
        default=5, metadata=_validate.bounded("int", 1, 1000, none=True, fix="e.g. 5")
    )
    """How many of the seeds the 2-D presets train: the first ones (as many as there are
    seeds for all of them; None in Python). A 2-D run costs about as much as 20 1-D runs;
    the default keeps the whole run within 15 minutes on two cores (measured in
    benchmarks/results/reproduce.json)."""
    n_test: int | None = field(
        default=None, metadata=_validate.bounded("int", 2, 1_000_000, none=True, fix="e.g. 10000")
    )
    """Test set size of the final metrics (default: 10,000, and 2,000 in quick runs)."""
    dpi: int = field(default=100, metadata=_validate.bounded("int", 20, 1200, fix="300 for print"))
    """Resolution of the report's figures (300 for print)."""

    def __post_init__(self) -> None:
        _validate.boolean("quick", self.quick)
        _validate.choice("save_models", self.save_models, SAVE_MODELS)
        _validate.check_fields(self)  # the bounds declared beside the fields

    @property
    def n_checkpoints(self) -> int:
        return QUICK_SIZES["n_checkpoints"] if self.quick else N_CHECKPOINTS

    @property
    def curve_test(self) -> int:
        return QUICK_SIZES["curve_test"] if self.quick else CURVE_TEST

    @property
    def test_size(self) -> int:
        if self.n_test is not None:
            return self.n_test
        return QUICK_SIZES["n_test"] if self.quick else N_TEST


@dataclass(frozen=True)
class ReproduceOptions(ReproduceConfig):
    """A :class:`ReproduceConfig` with the run's seeds, progress and workers (what the report
    and its sections see, :class:`~sigmapi.experiments.kit.report.ReportContext`)."""

    seeds: tuple[int, ...] = (0, 1, 2)
    """Training seeds (2-D presets: the first ``seeds_2d`` of them)."""
    progress: bool = True
    """Show progress bars on stderr."""
    workers: int | None = field(default=None, metadata=_validate.bounded("int", 1, none=True))
    """Training runs at once (default: as many as cores and half the available memory allow,
    :func:`~sigmapi.executor.plan_workers`); the results do not depend on it."""

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "seeds", check_seeds(self.seeds))

    def seeds_of(self, cfg: SOMConfig) -> tuple[int, ...]:
        """The seeds a preset trains: all of :attr:`seeds`, the first ``seeds_2d`` in 2-D."""
        return self.seeds[: self.seeds_2d] if len(cfg.map_shape) >= 2 else self.seeds


SECONDS = tuple(
    f"{t}_seconds" for t in ("train", "refine", "compile", "measure", "cpu", "compile_cpu")
)
"""The times of a :class:`SeedRun`, whose medians over seeds :meth:`PresetResult.to_dict`
stores (``seconds``)."""


@dataclass
class SeedRun(Result):
    """One trained seed: its metrics after and before the refinement (``unrefined``: the map
    at the end of the training, None where the preset does not refine), learning curve and
    times: the wall seconds of the training iterations and of the refinement rounds
    (``train_seconds``, ``refine_seconds``: without the checkpoints, the evaluations and the
    compile), numba's one-time compile in the worker process that ran it (``compile_seconds``,
    ``compile_cpu_seconds``: wall and CPU seconds of a small run of the same rules; 0 once the
    process has compiled, or for a kernel that compiles nothing), the checkpoints and
    evaluations (``measure_seconds``) and the job's CPU seconds (``cpu_seconds``: the
    measurements in, the compile out)."""

    seed: int
    train_seconds: float
    backend: str
    metrics: Metrics
    curve: dict[str, list[float]]
    unrefined: Metrics | None = None
    refine_seconds: float = 0.0
    compile_seconds: float = 0.0
    measure_seconds: float = 0.0
    cpu_seconds: float = 0.0
    compile_cpu_seconds: float = 0.0

    KEYS = ("seed", *SECONDS, "backend", "*metrics", "unrefined", "curve")
    """The JSON form: the seed, its times, the kernel, the metrics (the final map's at the top),
    the learning curve."""

    def at(self, stage: Stage = "refined") -> Metrics:
        """The metrics of the map at ``stage`` (the final map's where there is no other)."""
        return (
            self.unrefined if stage == "unrefined" and self.unrefined is not None else self.metrics
        )

    def metric(self, key: str, stage: Stage = "refined") -> float:
        return float(getattr(self.at(stage), key))

    @classmethod
    def from_dict(cls, data: object) -> SeedRun:
        """The run a :meth:`to_dict` wrote (the keys that name no field are its metrics)."""
        obj = as_object(data)
        values = cls.read_fields(obj)
        metrics = Metrics.from_dict({k: v for k, v in obj.items() if k not in values})
        unrefined = values.pop("unrefined")
        if unrefined is not None:
            values["unrefined"] = Metrics.from_dict(unrefined)
        return cls(**values, metrics=metrics)


@dataclass
class PresetResult(Result):
    """The runs of one preset over its seeds, the reference figures, the seed the figures
    show (and why), the rule's ceiling, and the figures drawn."""

    config: SOMConfig
    runs: list[SeedRun]
    reference: dict[str, float]
    z_error_floor: float | None
    shown_seed: int
    shown_reason: str = ""
    """Why the figures show ``shown_seed`` (computed from the data)."""
    ceiling: dict[str, Any] | None = None
    """The fixed point of Eq. 7 reached from one map of the task
    (:func:`sigmapi.analysis.fixed_point.fixed_point`; its metrics, the seed and preset of the map
    it started from, rounds); None when not computed."""
    figures: dict[str, dict[str, object]] = field(default_factory=dict)
    """Per figure: its file and the facts its caption states."""

    KEYS = (
        "config",
        "seeds: seed_list",
        "runs",
        "*stats",
        "unrefined",
        "ceiling",
        "reference",
        "z_error_floor",
        "figures",
        "shown_seed",
        "shown_reason",
        "seconds: median_seconds",
    )
    """The JSON form: the statistics after the refinement at the top, those before it in
    ``unrefined`` (docs/guide/reproduce.md names each key)."""

    @property
    def refines(self) -> bool:
        """Whether the runs have an unrefined map to compare (the preset refines)."""
        return all(r.unrefined is not None for r in self.runs) and bool(self.runs)

    def stages(self) -> list[Stage]:
        """The maps of its runs: the final (``refined``) and, where the preset refines, the
        ``unrefined``."""
        return ["refined", "unrefined"] if self.refines else ["refined"]

    def _values(self, key: str, stage: Stage) -> list[float]:
        return [r.metric(key, stage) for r in self.runs]

    def mean(self, stage: Stage = "refined") -> dict[str, float]:
        return {k: statistics.fmean(self._values(k, stage)) for k in METRIC_KEYS}

    def sd(self, stage: Stage = "refined") -> dict[str, float]:
        return {k: statistics.pstdev(self._values(k, stage)) for k in METRIC_KEYS}

    def median(self, stage: Stage = "refined") -> dict[str, float]:
        return {k: statistics.median(self._values(k, stage)) for k in METRIC_KEYS}

    def worst(self, stage: Stage = "refined") -> dict[str, float]:
        """Per metric, the worst seed's value (largest z error and fold score, else smallest)."""
        pick = {k: (max if k in WORSE_IS_LARGER else min) for k in METRIC_KEYS}
        return {k: pick[k](self._values(k, stage)) for k in METRIC_KEYS}

    def ordered_count(self, stage: Stage = "refined") -> int:
        """Seeds whose map is ordered: order R^2 >= ORDERED_R2."""
        return sum(v >= ORDERED_R2 for v in self._values("order_r2", stage))

    def folded_seeds(self, stage: Stage = "refined") -> list[int]:
        """Seeds the z-free fold detector flags."""
        return [r.seed for r in self.runs if r.at(stage).folded]

    def stats(self, stage: Stage = "refined") -> dict[str, object]:
        """The statistics over the seeds of the maps at ``stage``, as the JSON form holds them."""
        return {
            "median": self.median(stage),
            "worst": self.worst(stage),
            "mean": self.mean(stage),
            "sd": self.sd(stage),
            "ordered": self.ordered_count(stage),
            "folded_seeds": self.folded_seeds(stage),
        }

    def unrefined(self) -> dict[str, object] | None:
        return self.stats("unrefined") if self.refines else None

    def seed_list(self) -> list[int]:
        return [r.seed for r in self.runs]

    def median_seconds(self) -> dict[str, float]:
        """Per time of :class:`SeedRun` (:data:`SECONDS`), its median over the seeds."""
        return {k: statistics.median(float(getattr(r, k)) for r in self.runs) for k in SECONDS}


@dataclass
class ReproduceResult(Result):
    """Everything the report states; :meth:`to_dict` is ``metrics.json``."""

    options: ReproduceOptions
    presets: dict[str, PresetResult] = field(default_factory=dict)
    sections: dict[str, dict[str, object]] = field(default_factory=dict)
    """Per added section (by title): the numbers it stores."""
    total_seconds: float = 0.0
    out: Path | None = None
    """The report folder."""
    figure_files: list[Path] = field(default_factory=list)
    """The figures of the report, in its folder."""

    KEYS = (
        "quick: options.quick",
        "seeds: options.seeds",
        "seeds_2d: options.seeds_2d",
        "n_test: options.test_size",
        "curve_test: options.curve_test",
        "presets",
        "sections",
        "total_seconds",
    )
    """The JSON form (``metrics.json``; docs/guide/reproduce.md names each key)."""

    @classmethod
    def from_dict(cls, data: object) -> ReproduceResult:
        """The result a :meth:`to_dict` wrote (``metrics.json``): its options (those it
        states), presets and sections; no report folder."""
        data = as_object(data)
        stated = {k: data[k] for k in ("quick", "seeds", "seeds_2d", "n_test")}
        options = ReproduceOptions(**stated, progress=False)
        presets = {name: PresetResult.from_dict(p) for name, p in data["presets"].items()}
        return cls(options, presets, dict(data["sections"]), float(data["total_seconds"]))

    def table(self) -> str:
        """Per preset the median metrics over its seeds, labelled (after and before the
        refinement, and the rule's ceiling, where there are), and the report's file: the
        statistics of the report's table."""
        lines = []
        for name, res in self.presets.items():
            n = len(res.runs)
            for stage in res.stages():
                label = "median" if stage == "refined" else "median before refinement"
                text = ", ".join(f"{k} {v:.3f}" for k, v in res.median(stage).items())
                lines.append(f"{name}: {label} of {n} seed{plural(n)}: {text}")
            flagged, worst = res.folded_seeds(), res.worst()
            flags = (
                f"; the fold detector flags seed{plural(len(flagged))} "
                f"{', '.join(map(str, flagged))} (its signs, views of one z won by distant "
                "units, also mark a coarse map)"
                if flagged
                else ""
            )
            lines.append(
                f"{name}: {res.ordered_count()} of {n} ordered (order R^2 >= {ORDERED_R2}){flags}; "
                f"worst seed: view_consistency {worst['view_consistency']:.3f}, "
                f"order_r2 {worst['order_r2']:.3f}"
            )
            if res.ceiling is not None:
                lines.append(
                    f"{name}: the rule's ceiling (fixed point of Eq. 7 from seed "
                    f"{res.ceiling['seed']} of {res.ceiling['preset']}): "
                    f"view_consistency {res.ceiling['view_consistency']:.3f}"
                )
        if self.out is not None:
            lines.append(f"report: {self.out / REPORT}")
        return "\n".join(lines)

    def figure(self, out_dir: Path) -> list[Path]:
        """The report's figures, drawn with it into its folder (copied into ``out_dir`` when
        that is another folder)."""
        folder = Path(out_dir)
        if self.out is not None and folder.resolve() == Path(self.out).resolve():
            return list(self.figure_files)
        folder.mkdir(parents=True, exist_ok=True)
        return [Path(shutil.copy2(f, folder / f.name)) for f in self.figure_files]
