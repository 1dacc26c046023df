"""A trained map deployed in spiking neurons (docs/guide/neurons.md).

Every input unit of the retinal and the gaze code is a pool of ``pool`` Poisson neurons, each
firing at ``peak_rate`` times the unit's code value (a code of length 1, whose peak is near
1). Two networks read them, each simulated for many trials at once with a fixed time step
``dt`` (exact exponential decay between steps):

**conjunction** (a Sigma-Pi map, :class:`~sigmapi.SigmaPiSOM`): every pair of a retinal and
a gaze neuron has a coincidence detector (two clustered synapses and an NMDA-like AND) that
fires once for every retinal and gaze spike at most ``coincidence_ms`` apart (``m`` whole
steps, ``m = coincidence_ms / dt``; no refractory period: at 100 Hz a neuron's next spike
within 1 ms is rare). The conjunction unit of the input pair ``(i, j)`` is the ``pool^2``
detectors of the pools of ``x_i`` and ``y_j``, and its spikes per step are counted exactly from
the pools' spikes: ``s_x s_y + s_x R_y + R_x s_y``, with ``R`` a pool's spikes in the ``m``
steps before. Its rate is ``r_x r_y (2 m + 1) dt`` (``r`` the pools' rates), the product the
Sigma-Pi unit needs at every rate, with no saturation. The map units are leaky
integrate-and-fire neurons (time constant ``tau_m``, threshold 1, reset 0): unit ``k``
receives conjunction unit ``(i, j)`` with weight ``gain w_kij / max w``, and every map spike
inhibits every other map unit of the trial by ``inhibition`` (a soft winner-take-all by
lateral inhibition).

**dendritic** (a :class:`~sigmapi.neurons.dendritic.DendriticMap`): each map unit is a neuron
with ``D`` dendritic compartments and a spiking soma. Compartment ``d`` filters its synaptic
input with time constant ``tau_s`` (weights ``u_kd``, ``v_kd``); its drive is the filtered
input in units of the rate code (``u . x`` when the pools fire at their mean rates) less the
branch threshold, and it passes ``sigmoid(g (drive - theta))`` to the soma as a current
(a dendritic plateau, scaled by ``plateau``). The somata are the same LIF neurons with the same
lateral inhibition.

The decision after a window of ``T`` ms is the map unit with the most spikes in it (ties: the
higher membrane potential at ``T``). One simulation of the longest window gives every shorter
window. The module needs numpy only.

:func:`protocol_spikes` runs the conjunction network on the trials of the gain-field studies'
protocol (:mod:`sigmapi.analysis.monkey`) and keeps every map spike, for the NWB file
(:mod:`sigmapi.nwb`), where the run fits :data:`PROTOCOL_BUDGET`.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.analysis.monkey import WINDOW
from sigmapi.model.som import SigmaPiSOM
from sigmapi.nwb import TrialSpikes, protocol_trials

__all__ = [
    "PROTOCOL",
    "PROTOCOL_BUDGET",
    "SpikingConfig",
    "SpikingRun",
    "coincidence_steps",
    "protocol_spikes",
    "simulate_conjunction",
    "simulate_dendritic",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SpikingConfig:
    """The spiking deployment's settings (module docstring)."""

    peak_rate: float = 100.0
    """Firing rate (Hz) of an input neuron at code value 1."""
    pool: int = 10
    """Poisson neurons per input unit."""
    windows_ms: tuple[float, ...] = (10.0, 20.0, 50.0, 100.0, 200.0, 500.0)
    """Decision windows (ms)."""
    dt_ms: float = 0.25
    """Time step (ms)."""
    coincidence_ms: float = 0.5
    """Coincidence detectors: the longest interval (ms) between a retinal and a gaze spike
    that still counts as a coincidence (rounded to whole steps)."""
    tau_s_ms: float = 5.0
    """Dendritic compartments: synaptic time constant (ms)."""
    tau_m_ms: float = 10.0
    """Map somata: membrane time constant (ms)."""
    gain: float = 0.6
    """Conjunction network: the largest synaptic weight onto a map soma, in units of its
    threshold."""
    plateau: float = 0.3
    """Dendritic network: the current per ms a branch in full plateau drives into its soma,
    in units of the threshold."""
    inhibition: float = 0.5
    """Lateral inhibition per map spike, in units of the threshold."""

    def __post_init__(self) -> None:
        for name in (
            "peak_rate",
            "dt_ms",
            "coincidence_ms",
            "tau_s_ms",
            "tau_m_ms",
            "gain",
            "plateau",
        ):
            _validate.positive(name, getattr(self, name), fix="a positive number")
        _validate.integer("pool", self.pool, 1, fix="e.g. 10")
        _validate.number("inhibition", self.inhibition, 0.0, fix="e.g. 0.5")
        if not self.windows_ms or min(self.windows_ms) < self.dt_ms:
            raise _validate.fail(
                "windows_ms",
                f"windows of at least dt_ms={self.dt_ms}",
                list(self.windows_ms),
                "e.g. 10,50,200",
            )
        if self.pool * self.peak_rate * self.dt_ms / 1000.0 > 0.5:
            raise _validate.fail(
                "pool * peak_rate * dt",
                "<= 0.5 spikes per step",
                self.pool * self.peak_rate * self.dt_ms / 1000.0,
                "use a smaller dt_ms",
            )


@dataclass
class SpikingRun:
    """One simulation's decisions: ``winners`` ``(W, B)`` per window, spikes per trial in
    each window by layer (``input``, ``hidden``: coincidence units or dendritic plateaus
    counted as none, ``map``), each ``(W, B)``; ``map_spike_steps``, where the simulation
    recorded them: every map spike as a row ``(trial, unit, step)`` ``(n, 3)``, in the order
    they fired (step ``s`` covers ``s dt`` to ``(s + 1) dt`` of the trial)."""

    windows_ms: tuple[float, ...]
    winners: NDArray[np.int64]
    input_spikes: Array
    hidden_spikes: Array
    map_spikes: Array
    map_spike_steps: NDArray[np.int64] | None = None


class _Soma:
    """The map's LIF somata of ``B`` trials with lateral inhibition; counts per window."""

    def __init__(
        self, b: int, k: int, cfg: SpikingConfig, steps: NDArray[np.int64], record: bool = False
    ) -> None:
        self.v = np.zeros((b, k))
        self.count = np.zeros((b, k))
        self.decay = np.exp(-cfg.dt_ms / cfg.tau_m_ms)
        self.inh = cfg.inhibition
        self.at = {int(s): i for i, s in enumerate(steps)}
        self.winners = np.zeros((len(steps), b), dtype=np.int64)
        self.spikes = np.zeros((len(steps), b))
        self.fired: list[NDArray[np.int64]] | None = [] if record else None

    def step(self, t: int, current: Array) -> None:
        v = self.v * self.decay + current
        fire = v >= 1.0
        n = fire.sum(axis=1, keepdims=True)
        v = np.where(fire, 0.0, v - self.inh * (n - fire))
        self.v = np.maximum(v, -1.0)  # inhibition cannot hyperpolarise without bound
        self.count += fire
        if self.fired is not None and fire.any():
            trial, unit = np.nonzero(fire)
            self.fired.append(np.stack([trial, unit, np.full_like(trial, t)], axis=1))
        if t in self.at:
            i = self.at[t]
            self.winners[i] = np.argmax(self.count + np.clip(self.v, 0.0, 0.999), axis=1)
            self.spikes[i] = self.count.sum(axis=1)

    def spike_steps(self) -> NDArray[np.int64] | None:
        """The recorded spikes ``(n, 3)`` (:class:`SpikingRun`), or None unrecorded."""
        if self.fired is None:
            return None
        return np.concatenate([np.zeros((0, 3), np.int64), *self.fired]).astype(np.int64)


def _steps(cfg: SpikingConfig) -> NDArray[np.int64]:
    return np.asarray(np.round(np.asarray(cfg.windows_ms) / cfg.dt_ms), dtype=np.int64) - 1


def coincidence_steps(cfg: SpikingConfig) -> int:
    """``m``: the coincidence window in whole time steps (at least 1)."""
    return max(1, round(cfg.coincidence_ms / cfg.dt_ms))


def _poisson(rng: np.random.Generator, rates: Array, dt_s: float) -> Array:
    """Spikes of the pools in one step ``(B, n)`` (a pool's spikes: one Poisson count)."""
    return np.asarray(rng.poisson(rates * dt_s), dtype=np.float64)


def simulate_conjunction(
    weights: Array,
    x: Array,
    y: Array,
    cfg: SpikingConfig,
    rng: np.random.Generator,
    record: bool = False,
) -> SpikingRun:
    """Coincidence detectors into LIF map units (module docstring) for ``B`` trials, codes ``x``
    ``(B, n_x)`` and ``y`` ``(B, n_y)``; ``weights`` the Sigma-Pi map's ``(K, n_x, n_y)``;
    ``record``: keep every map spike (:attr:`SpikingRun.map_spike_steps`)."""
    k, nx, ny = weights.shape
    b = x.shape[0]
    w = np.maximum(weights, 0.0).reshape(k, nx * ny)
    w = (cfg.gain * w / max(float(w.max()), 1e-300)).T  # (n_x n_y, K)
    steps = _steps(cfg)
    dt_s = cfg.dt_ms / 1000.0
    rx, ry = (
        cfg.peak_rate * cfg.pool * np.maximum(x, 0.0),
        cfg.peak_rate * cfg.pool * np.maximum(y, 0.0),
    )
    m = coincidence_steps(cfg)
    hx, hy = np.zeros((m, b, nx)), np.zeros((m, b, ny))  # the pools' spikes, m steps back
    near_x, near_y = np.zeros((b, nx)), np.zeros((b, ny))  # their sums
    soma = _Soma(b, k, cfg, steps, record)
    n_in, n_c = np.zeros(b), np.zeros(b)
    ins, hid = np.zeros((len(steps), b)), np.zeros((len(steps), b))
    for t in range(int(steps[-1]) + 1):
        sx, sy = _poisson(rng, rx, dt_s), _poisson(rng, ry, dt_s)
        c = sx[:, :, None] * (near_y + sy)[:, None, :] + near_x[:, :, None] * sy[:, None, :]
        f = c.reshape(b, -1)
        near_x += sx - hx[t % m]
        near_y += sy - hy[t % m]
        hx[t % m], hy[t % m] = sx, sy
        soma.step(t, f @ w)
        n_in += sx.sum(axis=1) + sy.sum(axis=1)
        n_c += f.sum(axis=1)
        if t in soma.at:
            ins[soma.at[t]], hid[soma.at[t]] = n_in, n_c
    return SpikingRun(
        tuple(cfg.windows_ms), soma.winners, ins, hid, soma.spikes, soma.spike_steps()
    )


def simulate_dendritic(
    u: Array,
    v: Array,
    gain: float,
    threshold: float,
    x: Array,
    y: Array,
    cfg: SpikingConfig,
    rng: np.random.Generator,
) -> SpikingRun:
    """Dendritic compartments into LIF somata (module docstring); ``u`` ``(K, D, n_x)``,
    ``v`` ``(K, D, n_y)``, ``gain`` and ``threshold`` the branch sigmoid's of a trained
    :class:`~sigmapi.neurons.dendritic.DendriticMap`."""
    k, d, _ = u.shape
    b = x.shape[0]
    uf, vf = u.reshape(k * d, -1), v.reshape(k * d, -1)
    bias = 0.5 * ((uf**2).sum(axis=1) + (vf**2).sum(axis=1))
    steps = _steps(cfg)
    dt_s = cfg.dt_ms / 1000.0
    rate = cfg.peak_rate * cfg.pool
    rx, ry = rate * np.maximum(x, 0.0), rate * np.maximum(y, 0.0)
    decay = np.exp(-cfg.dt_ms / cfg.tau_s_ms)
    scale = 1.0 / (rate * cfg.tau_s_ms / 1000.0)  # filtered spikes -> code units
    current = np.zeros((b, k * d))
    soma = _Soma(b, k, cfg, steps)
    n_in = np.zeros(b)
    ins = np.zeros((len(steps), b))
    for t in range(int(steps[-1]) + 1):
        sx, sy = _poisson(rng, rx, dt_s), _poisson(rng, ry, dt_s)
        current = current * decay + sx @ uf.T + sy @ vf.T
        z = np.clip(gain * (current * scale - bias - threshold), -60.0, 60.0)
        plateau = (1.0 / (1.0 + np.exp(-z))).reshape(b, k, d).sum(axis=2)
        soma.step(t, cfg.plateau * cfg.dt_ms * plateau)
        n_in += sx.sum(axis=1) + sy.sum(axis=1)
        if t in soma.at:
            ins[soma.at[t]] = n_in
    return SpikingRun(tuple(cfg.windows_ms), soma.winners, ins, np.zeros_like(ins), soma.spikes)


def windows_of(values: Sequence[float]) -> tuple[float, ...]:
    """Sorted distinct windows (ms)."""
    return tuple(sorted({float(v) for v in values}))


PROTOCOL = SpikingConfig(pool=20, gain=0.3, inhibition=0.25, windows_ms=(1000.0 * WINDOW,))
"""The conjunction network :func:`protocol_spikes` runs: the settings ``sigmapi neurons``
deploys a map with (100 Hz, pools of 20, 0.25 ms steps, its ``spike_gain`` and
``spike_inhibition``; docs/guide/neurons.md), for the protocol's counting window."""

PROTOCOL_BUDGET = 2.0e9
"""The most ``trials x conjunction units x time steps`` :func:`protocol_spikes` simulates
(a paper-1d map's protocol, 105 trials of 225 conjunction units for 2,000 steps, is 4.7e7;
a paper-2d map's, 11,025 trials of 50,625 for 2,000 steps, is 1.1e12: too long for the
NumPy network by about four orders of magnitude)."""

_BATCH = 4_000_000
"""Trials times conjunction units simulated at once (the coincidence counts of a step take
8 bytes each)."""


def protocol_spikes(
    model: SigmaPiSOM,
    fixation: dict[str, NDArray[np.float64]],
    cfg: SpikingConfig = PROTOCOL,
    seed: int = 0,
    budget: float = PROTOCOL_BUDGET,
) -> TrialSpikes | None:
    """Every map spike of the conjunction network deployed from ``model``'s weights in the
    trials of a :func:`~sigmapi.analysis.monkey.fixation_protocol` recording ``fixation``
    (the NWB file's order, :func:`sigmapi.nwb.protocol_trials`), each trial a fresh network
    run for ``cfg``'s longest window; None where ``trials x n_x n_y x steps`` exceeds
    ``budget``. A spike's time is the start of the step it fired in."""
    cond_e, cond_p = protocol_trials(fixation)
    weights = np.asarray(model.weights_, dtype=np.float64)
    _, nx, ny = weights.shape
    n_steps = int(_steps(cfg)[-1]) + 1
    if len(cond_e) * nx * ny * n_steps > budget:
        return None
    x = model.x_code.encode(fixation["stimuli"][cond_p])
    y = model.y_code.encode(fixation["eyes"][cond_e])
    rng = np.random.default_rng(seed)
    per = max(1, _BATCH // (nx * ny))
    found = []
    for lo in range(0, len(cond_e), per):
        run = simulate_conjunction(weights, x[lo : lo + per], y[lo : lo + per], cfg, rng, True)
        assert run.map_spike_steps is not None
        found.append(run.map_spike_steps + np.array([lo, 0, 0]))
    spikes = np.concatenate(found)
    settings = {
        "network": "conjunction (sigmapi.neurons.spiking.simulate_conjunction)",
        **{name: getattr(cfg, name) for name in cfg.__dataclass_fields__},
        "seed": seed,
    }
    return TrialSpikes(
        trial=spikes[:, 0],
        unit=spikes[:, 1],
        time=spikes[:, 2] * cfg.dt_ms / 1000.0,
        source=(
            "sigmapi's spiking deployment (the conjunction network of sigmapi.neurons.spiking: "
            f"Poisson input pools at {cfg.peak_rate:g} Hz, coincidence detectors, LIF map "
            f"units with lateral inhibition, {cfg.dt_ms:g} ms steps, seed {seed})"
        ),
        settings=json.loads(json.dumps(settings, default=list)),
    )
