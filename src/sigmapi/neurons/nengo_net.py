"""A trained Sigma-Pi map as a spiking Nengo network (Nengo 4.1, the reference simulator;
docs/guide/other-tools.md). Needs the nengo extra (``pip install 'sigmapi[nengo]'``; Nengo
4.1 is licensed under the GPL, version 2); imported only when a network is built.

The network computes what the spiking conjunction network of :mod:`sigmapi.neurons.spiking`
computes, in Nengo's objects:

- **input**: every retinal and gaze code unit is a pool of ``pool`` spiking rectified-linear
  neurons (``nengo.SpikingRectifiedLinear``, random initial phases), each firing at
  ``peak_rate`` times the unit's code value; a ``nengo.Node`` presents the trials one after
  another, each for ``settle_ms + window_ms``;
- **conjunction**: a ``nengo.Node`` receives the pools' spikes through a synapse of
  ``tau_s_ms`` (read as rates, in code units) and gives the products ``x_i y_j`` of every input
  pair: the multiplication of a Sigma-Pi unit's clustered synapses, as the coincidence
  detectors of the NumPy network compute it;
- **map**: ``n_units`` LIF neurons (``nengo.LIF``, Nengo's default time constants). The learned
  weights are the connection's transform from the conjunctions to the map neurons' currents
  (with ``products="active"``, the conjunction node's own weighted sum: below):
  unit ``k`` receives ``gain (S_k . W)`` (``W`` the Sigma-Pi weights, ``S`` the winner rule's
  affine map of the responses, :func:`sigmapi.export.score_matrix`) plus a bias, the rule's
  offset and a shift that puts the median winner's current at ``drive`` times the threshold
  (set on calibration pairs, the same for every unit);
- **decision**: the map neuron with the most spikes in the window after ``settle_ms`` (ties:
  the higher filtered rate at the window's end), as the NumPy network decides.

``products="all"`` (the default) passes all ``n_x n_y`` products to the map through a
connection whose transform holds the learned weights: Nengo's reference simulator multiplies
the dense ``(n_units, n_x n_y)`` matrix every step (paper-2d: 11.4 M multiply-adds, about 2 s of
CPU per 220 ms trial). ``products="active"`` computes the same currents inside the conjunction
node from the input units whose filtered spikes exceed ``active_cut`` of the largest in their
code (the rest are spike trains' decaying tails and units that did not fire; the fast
kernel drops products below 1e-4 of the peak the same way), ``sum_ij T_kij x_i y_j`` over
those units only, and drives the map neurons through an identity connection: the same
network up to that cut and float rounding (``tests/experiments/test_nengo_net.py``),
many times cheaper on the 2-D map (docs/guide/other-tools.md).

:func:`nengo_winners` simulates trials and returns the winners; :func:`build_network` gives
the ``nengo.Network`` itself.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import UsageError, install_hint
from sigmapi.export import score_matrix
from sigmapi.model.som import SigmaPiSOM

__all__ = ["NengoConfig", "build_network", "nengo_winners"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class NengoConfig:
    """The Nengo network's settings (module docstring)."""

    peak_rate: float = 100.0
    """Firing rate (Hz) of an input neuron at code value 1."""
    pool: int = 10
    """Input neurons per code unit."""
    window_ms: float = 200.0
    """Decision window (ms)."""
    settle_ms: float = 20.0
    """Time (ms) each trial runs before its window (the previous trial's activity decays)."""
    tau_s_ms: float = 5.0
    """Synaptic time constant (ms) of the input pools' spikes into the conjunctions."""
    drive: float = 8.0
    """The median winner's current, in units of the map neurons' threshold. ``(drive,
    spread)`` was chosen on seeds 0-1 (``benchmarks/bench_nengo.py``'s maps, 100 test z's)
    among (3, 2), (8, 8) and (16, 16): (3, 2) gave the map neurons about 20 spikes in a window,
    too few to rank close units (2-D agreement 0.86-0.92); the other two did equally well
    (0.93-0.96)."""
    spread: float = 8.0
    """The range (5th to 95th percentile) of the winners' scores on the calibration pairs, in
    threshold units."""
    dt_ms: float = 1.0
    """Simulator time step (ms)."""
    products: str = "all"
    """``"all"``: the learned weights are a connection's transform from every product;
    ``"active"``: the conjunction node sums the active units' products with them (module
    docstring)."""
    active_cut: float = 1e-4
    """With ``products="active"``: input units below this share of their code's largest
    filtered value are left out."""

    def __post_init__(self) -> None:
        for name in ("peak_rate", "window_ms", "tau_s_ms", "drive", "spread", "dt_ms"):
            _validate.positive(name, getattr(self, name), fix="a positive number")
        _validate.integer("pool", self.pool, 1, fix="e.g. 10")
        _validate.number("settle_ms", self.settle_ms, 0.0, fix="e.g. 20")
        _validate.choice("products", self.products, ("all", "active"))
        _validate.number("active_cut", self.active_cut, 0.0, 1.0, fix="e.g. 1e-4")


def _nengo() -> Any:
    try:
        with warnings.catch_warnings():  # nengo 4.1 reads np.core.umath.clip at import
            warnings.filterwarnings("ignore", "numpy.core is deprecated", DeprecationWarning)
            import nengo
    except ImportError:
        raise UsageError(
            "the Nengo network needs the nengo package (not installed here); "
            f"{install_hint('nengo')}"
        ) from None
    return nengo


def _currents(model: SigmaPiSOM, cfg: NengoConfig, seed: int) -> tuple[Array, Array]:
    """The map neurons' input transform ``(K, n_x n_y)`` and bias ``(K,)``: ``gain`` times the
    rule's scores plus a shift, from 500 calibration pairs of random positions."""
    k = model.n_units
    w = np.asarray(model.weights_, dtype=np.float64).reshape(k, -1)
    a, b = score_matrix(model)
    rng = np.random.default_rng(seed)
    x = model.x_code.encode(rng.random((500, len(model.x_shape))))
    y = model.y_code.encode(rng.random((500, len(model.y_shape))))
    win = (model.respond(x, y) @ a + b).max(axis=1)
    lo, mid, hi = np.percentile(win, [5, 50, 95])
    gain = cfg.spread / max(float(hi - lo), 1e-300)
    transform = gain * (w.T @ a).T
    bias = gain * b + cfg.drive - gain * float(mid)
    return transform, bias


def build_network(
    model: SigmaPiSOM, x: Array, y: Array, cfg: NengoConfig | None = None, seed: int = 0
) -> tuple[Any, dict[str, object]]:
    """The ``nengo.Network`` that presents the trials ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``
    one after another, and its probes (``"map"``: the map neurons' spikes; ``"rate"``: them
    through a 20 ms synapse)."""
    nengo = _nengo()
    cfg = cfg or NengoConfig()
    nx, ny = x.shape[1], y.shape[1]
    trial_s = (cfg.settle_ms + cfg.window_ms) / 1000.0
    codes = np.concatenate([np.maximum(x, 0.0), np.maximum(y, 0.0)], axis=1)
    transform, bias = _currents(model, cfg, seed)
    n_in = (nx + ny) * cfg.pool

    def present(t: float) -> Array:
        return np.asarray(codes[min(int(t / trial_s), codes.shape[0] - 1)])

    def products(t: float, v: Array) -> Array:
        return np.asarray(np.outer(v[:nx], v[nx:]).ravel())

    if cfg.products == "active":  # (n_x, n_y, K): a pair's weights side by side
        by_pair = np.ascontiguousarray(transform.T.reshape(nx, ny, -1))

    def active(v: Array) -> NDArray[np.intp]:
        return np.flatnonzero(v > cfg.active_cut * max(float(v.max()), 1e-300))

    def currents(t: float, v: Array) -> Array:
        xs, ys = v[:nx], v[nx:]
        i, j = active(xs), active(ys)
        rows = by_pair[i[:, None], j[None, :]]  # (|i|, |j|, K): the active pairs' weights
        return np.asarray(np.tensordot(np.outer(xs[i], ys[j]), rows, axes=2))

    with nengo.Network(seed=seed) as net:
        stimulus = nengo.Node(present, size_out=nx + ny)
        neuron = nengo.SpikingRectifiedLinear(
            initial_state={"voltage": nengo.dists.Uniform(0.0, 1.0)}
        )
        pools = nengo.Ensemble(
            n_in, 1, neuron_type=neuron, gain=np.full(n_in, cfg.peak_rate), bias=np.zeros(n_in)
        )
        # unit u's pool: neurons u * pool ... (u + 1) * pool - 1, driven by its code value
        # (sparse transforms: a dense one multiplies the (n_in, n_x + n_y) zeros every step)
        member = np.stack([np.arange(n_in), np.arange(n_in) // cfg.pool], axis=1)
        spread = nengo.transforms.Sparse((n_in, nx + ny), indices=member, init=1.0)
        nengo.Connection(stimulus, pools.neurons, transform=spread, synapse=None)
        k = model.n_units
        dense = cfg.products == "all"
        conj = nengo.Node(
            products if dense else currents, size_in=nx + ny, size_out=nx * ny if dense else k
        )
        nengo.Connection(
            pools.neurons,
            conj,
            transform=nengo.transforms.Sparse(
                (nx + ny, n_in), indices=member[:, ::-1], init=1.0 / (cfg.pool * cfg.peak_rate)
            ),
            synapse=nengo.Lowpass(cfg.tau_s_ms / 1000.0),
        )
        units = nengo.Ensemble(k, 1, neuron_type=nengo.LIF(), gain=np.ones(k), bias=bias)
        nengo.Connection(conj, units.neurons, transform=transform if dense else 1.0, synapse=None)
        probes = {
            "map": nengo.Probe(units.neurons, "output"),
            "rate": nengo.Probe(units.neurons, "output", synapse=nengo.Lowpass(0.02)),
        }
    return net, probes


def nengo_winners(
    model: SigmaPiSOM, x: Array, y: Array, cfg: NengoConfig | None = None, seed: int = 0
) -> NDArray[np.int64]:
    """Winners ``(B,)`` of the trials ``x``, ``y`` in the Nengo network (module docstring),
    simulated by Nengo's reference simulator."""
    nengo = _nengo()
    cfg = cfg or NengoConfig()
    net, probes = build_network(model, x, y, cfg, seed)
    dt = cfg.dt_ms / 1000.0
    per_trial = round((cfg.settle_ms + cfg.window_ms) / cfg.dt_ms)
    settle = round(cfg.settle_ms / cfg.dt_ms)
    with nengo.Simulator(net, dt=dt, progress_bar=False, seed=seed) as sim:
        sim.run_steps(per_trial * x.shape[0])
    spikes = sim.data[probes["map"]].reshape(x.shape[0], per_trial, -1)
    rate = sim.data[probes["rate"]].reshape(x.shape[0], per_trial, -1)
    counts = (spikes[:, settle:] > 0).sum(axis=1)
    last = rate[:, -1]
    score = counts + 0.5 * last / max(float(last.max()), 1e-300)  # ties: the higher rate
    return np.asarray(np.argmax(score, axis=1), dtype=np.int64)
