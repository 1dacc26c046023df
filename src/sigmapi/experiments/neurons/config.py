"""The settings of ``sigmapi neurons`` (:class:`NeuronsConfig`) and its quick look."""

from __future__ import annotations

from dataclasses import dataclass, field

from sigmapi import _validate
from sigmapi.config import SOMConfig, apply_overrides, load_preset
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.neurons.spiking import SpikingConfig
from sigmapi.neurons.training import TrainingConfig

METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "usage", "fold_score")
"""The scores of each rate map (:func:`sigmapi.evaluate`), besides ``folded``."""

REFERENCE_RATE = 100
"""The peak rate (Hz) the dendritic spiking network runs at (the conjunction network: every
rate of the config)."""

DT_MS = 0.25
"""The spiking networks' time step (ms), unless the pool's rate needs a shorter one."""

DENDRITIC_INHIBITION = 0.5
"""Lateral inhibition per map spike of the dendritic spiking network (threshold units)."""

__all__ = ["DENDRITIC_INHIBITION", "METRICS", "QUICK", "REFERENCE_RATE", "NeuronsConfig"]


@dataclass(frozen=True)
class NeuronsConfig:
    """What ``sigmapi neurons`` trains, deploys and scores."""

    preset: str = "paper-1d"
    """The 1-D task and the Sigma-Pi map's settings (a preset name)."""
    preset_2d: str = "paper-2d"
    """The 2-D task ("" for none)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to both presets' Sigma-Pi maps, e.g. ``iterations=50000``."""
    branches: tuple[int, ...] = field(default=(2, 4, 7, 10, 15), metadata={"sep": ","})
    """Dendritic branches per unit, 1-D (one map per value)."""
    branches_2d: tuple[int, ...] = field(default=(7,), metadata={"sep": ","})
    """Dendritic branches per unit, 2-D."""
    sparse_branches: tuple[int, ...] = field(default=(15, 30, 45), metadata={"sep": ","})
    """Branches per unit (mean over the map) of the sparse dendritic maps, two clustered
    synapses each (:class:`~sigmapi.neurons.sparse.SparseDendriticMap`), 1-D."""
    sparse_branches_2d: tuple[int, ...] = field(default=(200,), metadata={"sep": ","})
    """The same, 2-D (candidate conjunctions at ``basis_stride_2d``)."""
    seeds_2d: int = 2
    """How many of the seeds also run the 2-D task (the first ones)."""
    pairs: int = 100_000
    """View pairs of the dendritic and basis-function maps' online phase."""
    pairs_2d: int = 30_000
    """The same, 2-D."""
    windows_ms: tuple[int, ...] = field(default=(10, 20, 50, 100, 200, 500), metadata={"sep": ","})
    """Decision windows of the spiking networks (ms)."""
    peak_rates: tuple[int, ...] = field(default=(50, 100, 200), metadata={"sep": ","})
    """Input peak rates of the spiking networks (Hz); 100 is the acceptance's."""
    spike_test: int = 300
    """Test z's of the spiking networks (each shown as two views)."""
    pool: int = 20
    """Poisson neurons per input unit of the spiking networks (chosen on seeds 0-2 among 20
    and 40 with the coincidence detectors of :mod:`sigmapi.neurons.spiking`: 40 raised the
    agreement with the rate map at 200 ms from about 0.98 to 0.99 for three times the spikes,
    and did not bring the view consistency closer)."""
    spike_gain: float = 0.3
    """The conjunction networks' largest synaptic weight onto a map soma (threshold units;
    chosen on seeds 0-2 among 0.15, 0.3 and 0.6 with the pool)."""
    spike_inhibition: float = 0.25
    """Lateral inhibition per map spike of the conjunction networks (threshold units; chosen
    on seeds 0-2 between 0.25 and 0.5: at 200 ms the worst seed's view consistency was
    0.003 from the rate map's at 0.25, 0.010 at 0.5). The dendritic network keeps
    :data:`DENDRITIC_INHIBITION`."""
    pools_compared: tuple[int, ...] = field(default=(5, 10), metadata={"sep": ","})
    """Other pool sizes the conjunction network runs at the reference rate (what a smaller
    pool costs in accuracy and saves in spikes)."""
    basis_stride_2d: int = 2
    """The 2-D basis-function layer's stride (every 2nd retinal and gaze unit per axis: 8^4
    hidden units instead of 15^4)."""
    spiking_branches: int = 10
    """The dendritic map (1-D, branches per unit) deployed in spiking neurons (0: none)."""
    spiking_sparse_branches: int = 30
    """The sparse dendritic map (1-D, branches per unit) deployed in spiking neurons (0: none):
    each branch a coincidence detector of its retinal and its gaze pool, coupled to a LIF soma
    by its coupling."""
    n_test: int = 5000
    """Test z's (and calibration z's) of the rate maps' evaluation."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "overrides", tuple(self.overrides))
        for name in (
            "branches",
            "branches_2d",
            "sparse_branches",
            "sparse_branches_2d",
            "windows_ms",
            "peak_rates",
            "pools_compared",
        ):
            vals = [
                _validate.integer(name, v, 1, fix="positive ints, e.g. 2,4,7")
                for v in getattr(self, name)
            ]
            set_(self, name, tuple(sorted(set(vals))))
        if not self.branches or not self.windows_ms or not self.peak_rates:
            raise _validate.fail(
                "branches, windows_ms and peak_rates",
                "non-empty",
                (self.branches, self.windows_ms, self.peak_rates),
                "give at least one value each",
            )
        _validate.integer("seeds_2d", self.seeds_2d, 0, fix="0 runs no 2-D task")
        _validate.integer("pairs", self.pairs, 0, fix="e.g. 100000")
        _validate.integer("pairs_2d", self.pairs_2d, 0, fix="e.g. 50000")
        _validate.integer("spike_test", self.spike_test, 10, fix="e.g. 300")
        _validate.integer("pool", self.pool, 1, 1000, fix="e.g. 20")
        _validate.positive("spike_gain", self.spike_gain, fix="e.g. 0.3")
        _validate.number("spike_inhibition", self.spike_inhibition, 0.0, fix="e.g. 0.25")
        _validate.integer("basis_stride_2d", self.basis_stride_2d, 1, fix="e.g. 2")
        _validate.integer("spiking_branches", self.spiking_branches, 0, fix="0: none")
        _validate.integer("spiking_sparse_branches", self.spiking_sparse_branches, 0, fix="0: none")
        _validate.integer("n_test", self.n_test, 100, fix="e.g. 5000")
        self.som_config  # noqa: B018 (a bad preset or override fails here)
        if self.preset_2d:
            self.som_config_2d  # noqa: B018

    @property
    def som_config(self) -> SOMConfig:
        """The 1-D task with the overrides."""
        return apply_overrides(load_preset(self.preset), list(self.overrides))

    @property
    def som_config_2d(self) -> SOMConfig:
        """The 2-D task with the overrides."""
        return apply_overrides(load_preset(self.preset_2d), list(self.overrides))

    def training(self, two_d: bool) -> TrainingConfig:
        """The schedule of the first-order maps."""
        if two_d:
            return TrainingConfig(pairs=self.pairs_2d, refine_pairs=20_000, refine_rounds=1)
        return TrainingConfig(pairs=self.pairs)

    def spiking(
        self, peak_rate: float, pool: int | None = None, *, dendritic: bool = False
    ) -> SpikingConfig:
        """The spiking deployment at ``peak_rate`` with ``pool`` (default :attr:`pool`)
        Poisson neurons per input unit; the time step 0.25 ms, or shorter where a pool's
        peak rate would give more than 0.5 spikes per step. The lateral inhibition is
        :attr:`spike_inhibition`, or :data:`DENDRITIC_INHIBITION` for the ``dendritic``
        network."""
        pool = self.pool if pool is None else pool
        return SpikingConfig(
            peak_rate=float(peak_rate),
            pool=pool,
            dt_ms=min(DT_MS, 500.0 / (pool * peak_rate)),  # <= 0.5 input spikes per step
            gain=self.spike_gain,
            inhibition=DENDRITIC_INHIBITION if dendritic else self.spike_inhibition,
            windows_ms=tuple(float(w) for w in self.windows_ms),
        )


QUICK = NeuronsConfig(
    preset_2d="",
    overrides=("iterations=60000", "refine_pairs=30000"),
    branches=(4, 10),
    sparse_branches=(30,),
    pairs=40_000,
    windows_ms=(20, 100, 200),
    peak_rates=(100,),
    spike_test=150,
    pools_compared=(),
    spiking_branches=10,
    n_test=2000,
)
"""The quick look: a short 1-D run, two branch counts, one peak rate."""
