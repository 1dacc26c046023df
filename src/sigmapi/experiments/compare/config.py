"""The settings of ``sigmapi compare``: the task, the data and the methods."""

from __future__ import annotations

from dataclasses import dataclass, field

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.experiments.kit.maps import MapSpec

__all__ = ["LABELS", "METHODS", "QUICK", "QUICK_SEEDS", "SEEDS", "CompareConfig"]


LABELS = (10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10_000)
"""Numbers of labelled samples the read-outs are scored with (those <= ``n_test``)."""


METHODS: dict[str, str] = {
    "sigma-pi": "Sigma-Pi map (sigmapi's ordering procedure, crossview)",
    "sigma-pi same view": "Sigma-Pi map, learns the view it saw (ablation)",
    "sigma-pi ordering none": "Sigma-Pi map, the paper's random start (ordering none)",
    "kohonen": "first-order SOM on [x; y] (sigmapi's)",
    "kohonen two-view": "first-order SOM, the two-view rule",
    "minisom": "MiniSom on [x; y] (reference)",
    "basis functions": "gain-field products + linear read-out",
    "rbm": "RBM on [x; y] + linear read-out",
}
"""Method names (the JSON's ``name``) and what each is."""


@dataclass(frozen=True)
class CompareConfig:
    """What ``sigmapi compare`` trains and scores."""

    preset: str = "paper-1d"
    """The task and the Sigma-Pi map's settings (a preset name; ``sigmapi presets``)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    train_pairs: int = field(
        default=20_000, metadata=_validate.bounded("int", 100, 10_000_000, fix="e.g. 20000")
    )
    """View pairs recorded per seed (every method trains on these rows)."""
    baseline_iterations: int = field(
        default=100_000, metadata=_validate.bounded("int", 1, 100_000_000, fix="e.g. 100000")
    )
    """Online updates of the first-order maps (sigmapi's and MiniSom)."""
    rbm_epochs: int = field(default=10, metadata=_validate.bounded("int", 1, 10_000, fix="e.g. 10"))
    """Training passes of the RBM over the data."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", LABELS[0], 1_000_000, fix="e.g. 10000")
    )
    """Test z's (and calibration z's, the pool the labels are drawn from)."""
    methods: tuple[str, ...] = tuple(METHODS)
    """Methods to run (default: all of them); "sigma-pi" always runs."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        for m in self.methods:
            _validate.choice("methods", m, tuple(METHODS))
        object.__setattr__(
            self, "methods", tuple(m for m in METHODS if m in self.methods or m == "sigma-pi")
        )
        object.__setattr__(self, "overrides", tuple(self.overrides))
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def labels(self) -> tuple[int, ...]:
        return tuple(n for n in LABELS if n <= self.n_test)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with the overrides: the task and the Sigma-Pi map's settings."""
        return MapSpec(self.preset, self.overrides).config()


QUICK = CompareConfig(train_pairs=10_000, baseline_iterations=20_000, rbm_epochs=5, n_test=5000)
"""The quick comparison: less data, shorter baselines (with :data:`QUICK_SEEDS`)."""


SEEDS = (0, 1, 2, 3, 4)
"""The default seeds: each draws its own training data and trains every method on it."""


QUICK_SEEDS = (0, 1)
"""The seeds of the quick comparison."""
