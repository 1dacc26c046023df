"""What the reproduction run takes and gives: its options, its typed results, report sections.

:class:`ReproduceConfig` holds its settings (the command-line options), :class:`ReproduceOptions`
those with the run's seeds, progress and workers; :class:`ReproduceResult` (one
:class:`PresetResult` per preset, one :class:`SeedRun` per seed) is what ``metrics.json``
holds, through ``to_dict()``. A :class:`Section` is a part of the report that an experiment
adds (e.g. the reach experiment); it receives a :class:`ReportContext`.
"""

from __future__ import annotations

import shutil
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, get_args

from sigmapi import _validate
from sigmapi.experiments.base import check_seeds
from sigmapi.metrics import ORDERED_R2

if TYPE_CHECKING:
    from sigmapi.config import SOMConfig
    from sigmapi.metrics import Metrics
    from sigmapi.som import SigmaPiSOM

__all__ = [
    "METRIC_KEYS",
    "SAVE_MODELS",
    "PresetResult",
    "ReportContext",
    "ReproduceConfig",
    "ReproduceOptions",
    "ReproduceResult",
    "Section",
    "SeedRun",
]

METRIC_KEYS = (
    "view_consistency", "view_within_one", "z_error", "order_r2", "usage", "fold_score",
)  # fmt: skip

"""The metrics the report tabulates (mean and sd over seeds)."""

SaveModels = Literal["shown", "all", "none"]
SAVE_MODELS: tuple[str, ...] = get_args(SaveModels)
"""Which trained models the report writes: the one the figures show, all, or none."""

N_CHECKPOINTS = 20
"""Checkpoints of the learning curves per run (log-spaced); ``quick``: :data:`QUICK_SIZES`."""

CURVE_TEST = 1000
"""Test (and calibration) set size at each learning-curve checkpoint."""

N_TEST = 10_000
"""Test set size of the final metrics."""

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
    best-ordered seed), all, or none."""
    n_test: int | None = None
    """Test set size of the final metrics (default: 10,000, and 2,000 in quick runs)."""
    dpi: int = 100
    """Resolution of the report's figures (300 for print)."""

    def __post_init__(self) -> None:
        _validate.boolean("quick", self.quick)
        _validate.choice("save_models", self.save_models, SAVE_MODELS)
        if self.n_test is not None:
            _validate.integer("n_test", self.n_test, 2, fix="e.g. 10000")
        _validate.integer("dpi", self.dpi, 20, 1200, fix="300 for print")

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
    and its sections see, :class:`ReportContext`).

    Attributes
    ----------
    seeds : tuple of int
        Training seeds; figures other than the learning curves show the model of the seed
        with the highest order R^2 (the first on ties), and say which.
    progress : bool
        Show progress bars on stderr.
    workers : int, optional
        Training runs at once (default: one per core, as many as fit in half the available
        memory; :func:`~sigmapi.executor.plan_workers`). The results do not
        depend on it.
    """

    seeds: tuple[int, ...] = (0, 1, 2)
    progress: bool = True
    workers: int | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "seeds", check_seeds(self.seeds))
        if self.workers is not None:
            _validate.integer("workers", self.workers, 1)

    @property
    def config(self) -> ReproduceConfig:
        """The settings without the run's."""
        return ReproduceConfig(self.quick, self.save_models, self.n_test, self.dpi)


@dataclass
class SeedRun:
    """One trained seed: its metrics, learning curve and training time."""

    seed: int
    train_seconds: float
    backend: str
    metrics: Metrics
    curve: dict[str, list[float]]

    def metric(self, key: str) -> float:
        return float(getattr(self.metrics, key))

    def to_dict(self) -> dict[str, Any]:
        return {"seed": self.seed, "train_seconds": self.train_seconds, "backend": self.backend,
                **self.metrics.to_dict(), "curve": self.curve}  # fmt: skip


@dataclass
class PresetResult:
    """The runs of one preset over the seeds, the reference figures, and the figures drawn."""

    config: SOMConfig
    runs: list[SeedRun]
    reference: dict[str, float]
    z_error_floor: float | None
    shown_seed: int
    figures: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Per figure: its file and the facts its caption states."""

    def mean(self) -> dict[str, float]:
        return {k: statistics.fmean(r.metric(k) for r in self.runs) for k in METRIC_KEYS}

    def sd(self) -> dict[str, float]:
        return {k: statistics.pstdev(r.metric(k) for r in self.runs) for k in METRIC_KEYS}

    def median(self) -> dict[str, float]:
        return {k: statistics.median(r.metric(k) for r in self.runs) for k in METRIC_KEYS}

    def worst(self) -> dict[str, float]:
        """Per metric, the worst seed's value (largest z error and fold score, else smallest)."""
        pick = {k: (max if k in ("z_error", "fold_score") else min) for k in METRIC_KEYS}
        return {k: pick[k](r.metric(k) for r in self.runs) for k in METRIC_KEYS}

    def ordered_count(self) -> int:
        """Seeds whose map is ordered: order R^2 >= ORDERED_R2."""
        return sum(r.metrics.order_r2 >= ORDERED_R2 for r in self.runs)

    def folded_seeds(self) -> list[int]:
        """Seeds the z-free fold detector flags."""
        return [r.seed for r in self.runs if r.metrics.folded]

    def to_dict(self) -> dict[str, Any]:
        return {
            "config": self.config.to_dict(), "runs": [r.to_dict() for r in self.runs],
            "mean": self.mean(), "sd": self.sd(), "median": self.median(),
            "worst": self.worst(), "ordered": self.ordered_count(),
            "folded_seeds": self.folded_seeds(), "reference": self.reference,
            "z_error_floor": self.z_error_floor, "figures": self.figures,
            "shown_seed": self.shown_seed,
        }  # fmt: skip


@dataclass
class ReproduceResult:
    """Everything the report states; :meth:`to_dict` is ``metrics.json``."""

    options: ReproduceOptions
    presets: dict[str, PresetResult] = field(default_factory=dict)
    sections: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Per added section (by title): the numbers it stores."""
    total_seconds: float = 0.0
    out: Path | None = None
    """The report folder."""
    figure_files: list[Path] = field(default_factory=list)
    """The figures of the report, in its folder."""

    def to_dict(self) -> dict[str, Any]:
        o = self.options
        return {
            "quick": o.quick, "seeds": list(o.seeds), "n_test": o.test_size,
            "curve_test": o.curve_test,
            "presets": {name: p.to_dict() for name, p in self.presets.items()},
            "sections": self.sections, "total_seconds": self.total_seconds,
        }  # fmt: skip

    def table(self) -> str:
        """The mean metrics of each preset over the seeds, and the report's file."""
        lines = [f"{name}: " + ", ".join(f"{k} {v:.3f}" for k, v in res.mean().items())
                 for name, res in self.presets.items()]  # fmt: skip
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
    """What a section gets: the report folder, the run settings and the trained models.

    ``models`` maps each preset name to its trained models, one per seed (in ``seeds`` order).
    """

    out: Path
    options: ReproduceOptions
    models: dict[str, list[SigmaPiSOM]]

    @property
    def quick(self) -> bool:
        return self.options.quick

    @property
    def progress(self) -> bool:
        return self.options.progress
