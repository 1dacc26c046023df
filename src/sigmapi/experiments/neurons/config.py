"""The settings of ``sigmapi neurons`` (:class:`NeuronsConfig`) and its quick look."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TypeVar

from sigmapi import _memory, _validate
from sigmapi.config import SOMConfig, apply_overrides, load_preset
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.neurons.spiking import SpikingConfig
from sigmapi.neurons.training import TrainingConfig

METRICS = ("view_consistency", "view_within_one", "z_error", "order_r2", "usage", "fold_score")
"""The scores of each rate map (:func:`sigmapi.evaluate`), besides ``folded``."""

PHYSIOLOGY = ("reference_frame_index", "gain_r2", "peak_modulation")
"""What a 1-D map's row holds of its physiology (:func:`~sigmapi.analysis.physiology.record`:
the median over its units)."""

REFERENCE_RATE = 100
"""The peak rate (Hz) the dendritic spiking network runs at (the conjunction network: every
rate of the config)."""

DT_MS = 0.25
"""The spiking networks' time step (ms), unless the pool's rate needs a shorter one."""

DENDRITIC_INHIBITION = 0.5
"""Lateral inhibition per map spike of the dendritic spiking network (threshold units)."""

LONGEST_WINDOW_MS = 5000
"""Longest decision window (ms) of the spiking networks."""

HIGHEST_RATE = 2000
"""Highest input peak rate (Hz) of the spiking networks (cortical neurons fire below 500)."""

MAX_SPIKING_STEPS = 10**10
"""Most trial-steps of spiking simulation per seed (:meth:`NeuronsConfig.spiking_cost`; the
defaults run about 10^7)."""


T = TypeVar("T")


def _bounded(
    default: T,
    kind: str,
    lo: float,
    hi: float,
    fix: str = "",
    *,
    count: int = _validate.MAX_ITEMS,
    lo_open: bool = False,
) -> T:
    """A field of ``default`` within ``[lo, hi]`` (:func:`~sigmapi._validate.bounded`); a
    tuple of ints (kind ``"ints"``) is given comma-separated, its fix by default
    ``"positive ints, e.g. 2,4,7"``."""
    if kind == "ints":
        fix = fix or "positive ints, e.g. 2,4,7"
        return field(
            default=default, metadata=_validate.bounded(kind, lo, hi, fix=fix, count=count, sep=",")
        )
    return field(
        default=default, metadata=_validate.bounded(kind, lo, hi, fix=fix, lo_open=lo_open)
    )


@dataclass(frozen=True)
class NeuronsConfig:
    """What ``sigmapi neurons`` trains, deploys and scores."""

    preset: str = "paper-1d"
    """The 1-D task and the Sigma-Pi map's settings (a preset name)."""
    preset_2d: str = "paper-2d"
    """The 2-D task ("" for none)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to both presets' Sigma-Pi maps, e.g. ``iterations=50000``."""
    branches: tuple[int, ...] = _bounded((2, 4, 7, 10, 15), "ints", 1, 1000)
    """Dendritic branches per unit, 1-D (one map per value)."""
    branches_2d: tuple[int, ...] = _bounded((7,), "ints", 1, 1000)
    """Dendritic branches per unit, 2-D."""
    sparse_branches: tuple[int, ...] = _bounded((15, 30, 45), "ints", 1, 10_000)
    """Branches per unit (mean over the map) of the sparse dendritic maps, two clustered
    synapses each (:class:`~sigmapi.neurons.sparse.SparseDendriticMap`), 1-D."""
    sparse_branches_2d: tuple[int, ...] = _bounded((200,), "ints", 1, 10_000)
    """The same, 2-D (candidate conjunctions at ``basis_stride_2d``)."""
    seeds_2d: int = _bounded(2, "int", 0, 1000, "0 runs no 2-D task")
    """How many of the seeds also run the 2-D task (the first ones)."""
    pairs: int = _bounded(100_000, "int", 0, 10_000_000, "e.g. 100000")
    """View pairs of the dendritic and basis-function maps' online phase."""
    pairs_2d: int = _bounded(30_000, "int", 0, 10_000_000, "e.g. 50000")
    """The same, 2-D."""
    windows_ms: tuple[int, ...] = _bounded(
        (10, 20, 50, 100, 200, 500), "ints", 1, LONGEST_WINDOW_MS, "e.g. 20,100,200", count=20
    )
    """Decision windows of the spiking networks (ms)."""
    peak_rates: tuple[int, ...] = _bounded(
        (50, 100, 200), "ints", 1, HIGHEST_RATE, "e.g. 50,100,200", count=20
    )
    """Input peak rates of the spiking networks (Hz); 100 is the acceptance's."""
    spike_test: int = _bounded(300, "int", 10, 100_000, "e.g. 300")
    """Test z's of the spiking networks (each shown as two views)."""
    pool: int = _bounded(20, "int", 1, 1000, "e.g. 20")
    """Poisson neurons per input unit of the spiking networks (chosen on seeds 0-2, with the
    gain and the inhibition: docs/guide/neurons.md)."""
    spike_gain: float = _bounded(0.3, "number", 0, 100, "e.g. 0.3", lo_open=True)
    """The conjunction networks' largest synaptic weight onto a map soma (threshold units)."""
    spike_inhibition: float = _bounded(0.25, "number", 0, 100, "e.g. 0.25")
    """Lateral inhibition per map spike of the conjunction networks (threshold units; the
    dendritic network keeps :data:`DENDRITIC_INHIBITION`)."""
    pools_compared: tuple[int, ...] = _bounded((5, 10), "ints", 1, 1000, "e.g. 5,10", count=20)
    """Other pool sizes the conjunction network runs at the reference rate (what a smaller
    pool costs in accuracy and saves in spikes)."""
    basis_stride_2d: int = _bounded(2, "int", 1, 100, "e.g. 2")
    """The 2-D basis-function layer's stride (every 2nd retinal and gaze unit per axis: 8^4
    hidden units instead of 15^4)."""
    spiking_branches: int = _bounded(10, "int", 0, 1000, "0: none")
    """The dendritic map (1-D, branches per unit) deployed in spiking neurons (0: none)."""
    spiking_sparse_branches: int = _bounded(30, "int", 0, 10_000, "0: none")
    """The sparse dendritic map (1-D, branches per unit) deployed in spiking neurons (0: none):
    each branch a coincidence detector of its retinal and its gaze pool, coupled to a LIF soma
    by its coupling."""
    n_test: int = _bounded(5000, "int", 100, 1_000_000, "e.g. 5000")
    """Test z's (and calibration z's) of the rate maps' evaluation."""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "overrides", tuple(self.overrides))
        _validate.check_fields(self)  # the bounds declared beside the fields
        for f in dataclasses.fields(self):  # the sets of ints: sorted, each value once
            if f.type == "tuple[int, ...]":
                set_(self, f.name, tuple(sorted(set(getattr(self, f.name)))))
        if not self.branches or not self.windows_ms or not self.peak_rates:
            raise _validate.fail(
                "branches, windows_ms and peak_rates",
                "non-empty",
                (self.branches, self.windows_ms, self.peak_rates),
                "give at least one value each",
            )
        steps, need = self.spiking_cost()  # the spiking simulations' time and memory, bounded
        fix = "use fewer or shorter windows_ms, lower peak_rates, a smaller pool or spike_test"
        if steps > MAX_SPIKING_STEPS:
            raise _validate.fail(
                "windows_ms x peak_rates x pool x spike_test",
                f"at most {MAX_SPIKING_STEPS:.0e} trial-steps of spiking simulation per seed "
                "(the defaults run about 7e+06)",
                float(f"{steps:.3g}"),
                fix,
            )
        _memory.check(need, f"a spiking simulation of peak_rates={self.peak_rates}", fix)
        self.som_config  # noqa: B018 (a bad preset or override fails here)
        if self.preset_2d:
            self.som_config_2d  # noqa: B018

    def spiking_cost(self) -> tuple[int, int]:
        """``(steps, bytes)``: the time steps of every spiking simulation of one seed's 1-D
        task (each window's longest, at each rate and pool, each of :attr:`spike_test` trials
        a step of the whole network) and the largest simulation's spike history (the
        coincidence detectors' ``m`` steps of both pools of every trial), an upper estimate."""
        runs = [(r, self.pool) for r in self.peak_rates]
        runs += [(REFERENCE_RATE, p) for p in self.pools_compared]
        n = 64  # the 1-D inputs' units (grid 15 or so) and their margins, generously
        steps, peak = 0, 0
        for rate, pool in runs:
            dt = min(DT_MS, 500.0 / (pool * rate))
            steps += int(max(self.windows_ms) / dt) * self.spike_test * 2
            peak = max(peak, max(1, round(0.5 / dt)) * self.spike_test * 2 * n * 8 * 2)
        return steps, peak

    @property
    def som_config(self) -> SOMConfig:
        """The 1-D task with the overrides."""
        return apply_overrides(load_preset(self.preset), list(self.overrides))

    @property
    def som_config_2d(self) -> SOMConfig:
        """The 2-D task with the overrides. Its refinement draws random pairs (``refine_draw =
        "random"``, unless an override says otherwise), as the neurons' own refinement does
        and as the results in docs/guide/neurons.md were measured; ``paper-2d`` itself now
        draws quasi-random pairs (docs/guide/ceiling.md)."""
        base = load_preset(self.preset_2d).replace(refine_draw="random")
        return apply_overrides(base, list(self.overrides))

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
