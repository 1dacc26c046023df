"""A trained Sigma-Pi map as a NIR graph (the Neuromorphic Intermediate Representation, read
by Norse, snnTorch, Rockpool, Sinabs, Spyx, Lava-DL and SpiNNaker2): :func:`nir_graph`,
``sigmapi export MODEL --format nir --out FILE.nir`` (docs/guide/other-tools.md).

The graph uses only primitives that most readers support (``Input``, ``Affine``, ``IF``,
``LIF``, ``Output``; no ``Threshold``, which only Spyx reads), in one chain::

    input (n_x + n_y) -> conjunction Affine -> conjunction IF (n_x n_y + n_x + n_y)
    -> map Affine -> map LIF (n_units) -> output

- **input**: the two codes side by side, ``[x, y]`` (``x_code.encode``, ``y_code.encode``,
  flattened in C order), held as a constant current for the whole trial;
- **conjunction**: one integrate-and-fire neuron per input pair ``(i, j)`` (index
  ``i n_y + j``), driven by ``x_i + y_j - theta`` (weights 1 and 1, bias ``-theta``), reset
  to 0. Its rate is about ``max(0, x_i + y_j - theta)`` over its threshold: an AND of its two
  inputs (with ``theta`` near one code's peak it fires only when both are active), in place of
  the product ``x_i y_j`` a Sigma-Pi weight multiplies. NIR has no product of two signals;
  this is the sum-and-threshold conjunction of the dendritic and basis-function maps
  (:mod:`sigmapi.neurons.basis`) with a linear instead of a sigmoid rise. Then one relay
  neuron per code unit (index ``n_x n_y + i``, then ``n_x n_y + n_x + j``), driven by ``x_i``
  or ``y_j`` alone, firing at about its code value;
- **map**: the learned weights. Unit ``k`` receives conjunction ``(i, j)`` with weight
  ``threshold * S_k . (alpha * W_(ij))`` (``W`` the Sigma-Pi weights, ``alpha`` a scale per
  unit, ``S`` the winner rule's affine map of the responses,
  :func:`sigmapi.export.score_matrix`: the soft rule's smoothing, ``min_distance``'s squared
  norms in the bias), the relays with fitted weights, and a bias: the rule's offset, the fit's
  constant, and a shift that keeps the winner's drive positive (the same for every unit, so
  it changes no ranking). The units are leaky integrate-and-fire neurons with a time constant
  far longer than a trial (near-perfect integrators). The readout (:func:`winners`) counts
  spikes, then latency: the winner is the unit that fires most, and among those the one whose
  last spike came earliest (it reached that count first: the most input); then the lowest
  index. With few spikes (a threshold a few times below the winner's input over the trial)
  this reads the time each unit takes to gather its input, finer than a count of one step's
  worth of spikes, and no input is lost at a reset before the first spike.

The sum-and-threshold conjunction is not the product: its error depends on where the codes'
peaks sit (a normalised 2-D code's peak ranges from about 0.44 to 0.65, by how far the
position lies from a grid unit), and through the learned weights alone a paper-2d map
(seed 0) gets the model's winners on 92 % of the pairs at best. The relays correct the
responses by terms linear in each code: per unit ``k``, ``alpha_k`` and the relays' weights
are the least-squares fit of the model's responses ``h_k`` to ``alpha_k r_k + beta_k . [x,
y, 1]`` (``r_k`` the conjunctions' rates through ``W_k``, every rate the neurons' exact spike
count over the trial). On paper-2d maps this lifts the agreement to about 96 % of held-out
calibration pairs (rates). ``theta`` is chosen from a
small grid: for each, the fit on two thirds of ``calibration`` pairs of random positions
(drawn with ``seed``), the winners on the last third; the best is refitted on all of them.
The map neurons' threshold gives the winner one of :data:`MAP_SPIKES` spikes in a trial: the
one whose simulated winners agree most with the model's on 400 of the held-out pairs.
The graph's metadata holds ``theta``, the agreements, the codes, and how to simulate it:
``dt = 1`` (the graph's time unit is one step) for ``steps = 2000`` steps. Measured on fresh
maps and pairs: docs/guide/other-tools.md (``benchmarks/bench_nir.py``,
``tests/cli/test_export_nir.py``).
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.errors import UsageError, install_hint
from sigmapi.export import code_meta, score_matrix
from sigmapi.io import atomic_write_bytes
from sigmapi.model.som import SigmaPiSOM, load_model

__all__ = [
    "DT_S",
    "STEPS",
    "conjunction_rates",
    "export_nir",
    "if_rates",
    "nir_graph",
    "winners",
]

Array = NDArray[np.float64]

DT_S = 1.0
"""Time step the graph is meant to be simulated with: the graph's time unit is one step (the
IF neurons gain ``R I dt`` per step, as Norse's integrate-and-fire cell adds its input)."""
STEPS = 2000
"""Steps of one trial."""
CONJUNCTION_PERIOD = 10
"""The strongest conjunction neuron of the calibration pairs fires about once in this many
steps (at ``DT_S``), and so does the strongest relay: a rate that ``STEPS`` resolve to about
1 %."""
MAP_SPIKES = (3, 5, 10, 20)
"""Candidate numbers of the winner's spikes in a trial (about; the median winner's). Under
:func:`winners` few spikes read the latency of each unit's input (paper-2d maps, seeds 0-2:
3 spikes gave the winners of the input integrated without spikes); many spikes make a
neuron's threshold small against the bursts of input it gets when conjunctions fire together
(one spike a step at most, the rest of the burst lost at the reset); below 3 a weak winner
may not fire. The graph's calibration picks the one whose simulated winners agree most with
the model's."""
HELD_OUT_SIMULATED = 400
"""Held-out calibration pairs simulated to pick the winner's spikes."""
TAU_S = 1e6
"""The map neurons' time constant (s): leak negligible over a trial."""
THETAS = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)
"""Candidate ``theta``, in units of the larger code's peak value."""


def _nir() -> Any:
    try:
        import nir
    except ImportError:
        raise UsageError(
            f"exporting to NIR needs the nir package (not installed here); {install_hint('nir')}"
        ) from None
    return nir


def if_rates(drive: Array, v_threshold: float) -> Array:
    """What integrate-and-fire neurons with constant input ``drive`` pass on in a trial: their
    spikes over :data:`STEPS` steps (``dt = 1``: the membrane gains ``drive`` per step, fires
    above ``v_threshold`` and resets to 0, so it fires every ``floor(v_threshold / drive) + 1``
    steps), times ``v_threshold``, per step: ``max(0, drive)`` less what the reset discards."""
    period = np.floor(v_threshold / np.maximum(drive, 1e-300)) + 1.0
    spikes = np.where(drive > 0, np.floor(STEPS / np.minimum(period, 2.0 * STEPS)), 0.0)
    return np.asarray(spikes * v_threshold / STEPS)


def conjunction_rates(x: Array, y: Array, theta: float, v_conj: float) -> Array:
    """The conjunction neurons' :func:`if_rates` ``(B, n_x n_y)``, driven by
    ``x_i + y_j - theta``."""
    drive = (x[:, :, None] + y[:, None, :] - theta).reshape(x.shape[0], -1)
    return if_rates(drive, v_conj)


def _responses(columns: Array, x: Array, y: Array, theta: float, v_conj: float) -> Array:
    """The conjunctions' rates (:func:`conjunction_rates`) through the Sigma-Pi weights,
    ``columns`` ``(n_x n_y, K)``: ``(B, K)``. Only the conjunctions that fire are read (a few
    in a hundred of a 2-D map's 50,625: those whose two inputs together pass ``theta``)."""
    out = np.empty((x.shape[0], columns.shape[1]))
    for s in range(0, x.shape[0], 64):  # (B, n_x n_y) in pieces: 2-D maps have 50,625 pairs
        drive = (x[s : s + 64, :, None] + y[s : s + 64, None, :] - theta).reshape(
            len(x[s : s + 64]), -1
        )
        rows, fire = np.nonzero(drive > 0)
        rates = if_rates(drive[rows, fire], v_conj)
        ends = np.searchsorted(rows, np.arange(len(drive) + 1))
        for row in range(len(drive)):
            part = slice(ends[row], ends[row + 1])
            out[s + row] = rates[part] @ columns[fire[part]]
    return out


def _fit(r: Array, f: Array, h: Array) -> tuple[Array, Array]:
    """Per unit ``k`` the least-squares ``h[:, k] ~ alpha_k r[:, k] + f @ beta[:, k]``:
    ``alpha`` ``(K,)`` and ``beta`` ``(F, K)`` (a tiny ridge keeps ``f``'s solve defined)."""
    gram = f.T @ f
    gram[np.diag_indices_from(gram)] += 1e-9 * float(np.trace(gram)) / len(gram) + 1e-300
    pinv = np.linalg.solve(gram, f.T)  # (F, B)
    r_res, h_res = r - f @ (pinv @ r), h - f @ (pinv @ h)
    alpha = (r_res * h_res).sum(axis=0) / np.maximum((r_res * r_res).sum(axis=0), 1e-300)
    return alpha, pinv @ (h - r * alpha)


def _calibrate(
    model: SigmaPiSOM, columns: Array, a: Array, b: Array, n: int, seed: int
) -> dict[str, Any]:
    """``theta``, the thresholds, the per-unit scale ``alpha`` of the conjunctions and the
    relays' weights ``beta`` (fitted on two thirds of ``n`` pairs for each candidate
    ``theta``, the one with the most winners equal to the model's on the last third kept,
    then refitted on all ``n``), the bias shift and the agreements."""
    rng = np.random.default_rng(seed)
    x = model.x_code.encode(rng.random((n, len(model.x_shape))))
    y = model.y_code.encode(rng.random((n, len(model.y_shape))))
    want, h = model.winner(x, y), model.respond(x, y)
    peak = float(max(x.max(), y.max()))
    v_relay = peak * CONJUNCTION_PERIOD  # the strongest relay fires once in the period
    f = np.concatenate([if_rates(x, v_relay), if_rates(y, v_relay), np.ones((n, 1))], axis=1)
    fit = np.arange(n) < (2 * n) // 3
    best: dict[str, Any] = {"held_out_agreement": -1.0}
    for t in THETAS:
        top = float(np.max(x.max(axis=1) + y.max(axis=1))) - t * peak
        v_conj = top * CONJUNCTION_PERIOD  # the strongest fires once in the period
        r = _responses(columns, x, y, t * peak, v_conj)
        alpha, beta = _fit(r[fit], f[fit], h[fit])
        s = (r[~fit] * alpha + f[~fit] @ beta) @ a + b
        agree = float(np.mean(np.argmax(s, axis=1) == want[~fit]))
        if agree > best["held_out_agreement"]:
            best = {"theta": t * peak, "v_conj": v_conj, "r": r, "held_out_agreement": agree}
    alpha, beta = _fit(best["r"], f, h)
    s = (best.pop("r") * alpha + f @ beta) @ a + b
    win = s.max(axis=1)
    shift = max(0.0, -float(win.min())) + 0.1 * float(np.ptp(win) + 1e-12)
    held = np.flatnonzero(~fit)[:HELD_OUT_SIMULATED]
    return {**best, "v_relay": v_relay, "alpha": alpha, "beta": beta, "shift": shift,
            "held_x": x[held], "held_y": y[held], "held_winners": want[held],
            "agreement": float(np.mean(np.argmax(s, axis=1) == want)),
            "top_score": float(np.median(win)) + shift}  # fmt: skip


def winners(counts: Array, last_spike: Array) -> NDArray[np.intp]:
    """The graph's readout, per pair: the map neuron with the most spikes in the trial; among
    those, the one whose last spike came earliest (it reached that count first: the most
    input); then the lowest index. ``counts`` and ``last_spike`` (the step, from 0, of each
    neuron's last spike; anything for a neuron that did not fire) are ``(B, K)``."""
    counts = np.asarray(counts, dtype=np.float64)
    last = np.where(counts > 0, np.asarray(last_spike, dtype=np.float64), 0.0)
    span = max(float(last.max(initial=0.0)), 0.0) + 2.0  # a spike more outweighs any step
    return np.asarray(np.argmax(counts * span - last, axis=1))


def _spike_counts(c: dict[str, Any], map_w: Any, map_b: Any, v_map: Any) -> tuple[Array, Array]:
    """The map neurons' spike counts and last spikes' steps ``(B, K)`` on the held-out pairs
    of calibration ``c``: the graph run by NIR's definitions at ``dt = 1`` for :data:`STEPS`
    steps, the conjunctions and relays by their firing periods (under a constant input
    ``I > 0`` an IF neuron fires every ``floor(v_threshold / I) + 1`` steps), the map's LIF
    neurons stepped."""
    x, y = c["held_x"], c["held_y"]
    k = map_w.shape[0]
    w = map_w.astype(np.float64)
    counts, last = np.zeros((len(x), k)), np.full((len(x), k), -1.0)
    for s in range(0, len(x), 50):
        xs, ys = x[s : s + 50], y[s : s + 50]
        conj = (xs[:, :, None] + ys[:, None, :] - np.float32(c["theta"])).reshape(len(xs), -1)
        drive = np.concatenate([conj, xs, ys], axis=1)
        threshold = np.where(np.arange(drive.shape[1]) < conj.shape[1],
                             np.float32(c["v_conj"]), np.float32(c["v_relay"]))  # fmt: skip
        current = np.broadcast_to(map_b.astype(np.float64), (len(xs), STEPS, k)).copy()
        for b, g in enumerate(drive):
            on = np.flatnonzero(g > 0)
            period = np.floor(threshold[on] / g[on]) + 1
            on, period = on[period <= STEPS], period[period <= STEPS].astype(np.int64)
            by_period = np.zeros((STEPS + 1, k))
            np.add.at(by_period, period, w[:, on].T)
            for p in np.unique(period):  # fires at steps p, 2p, ... (step t is index t - 1)
                current[b, p - 1 :: p] += by_period[p]
        v = np.zeros((len(xs), k))
        for t in range(STEPS):
            v = v + DT_S / TAU_S * (-v + current[:, t])
            fired = v > v_map
            v = np.where(fired, 0.0, v)
            counts[s : s + 50] += fired
            last[s : s + 50][fired] = t
    return counts, last


def nir_graph(model: SigmaPiSOM, calibration: int = 3000, seed: int = 0) -> Any:
    """The NIR graph (a ``nir.NIRGraph``) of a fitted Sigma-Pi map (module docstring).

    Raises :class:`~sigmapi.errors.UsageError` without the nir package,
    :class:`~sigmapi.errors.NotFittedError` for a model that has not been trained.
    """
    nir = _nir()
    w = model.weights_  # raises NotFittedError before training
    k = model.n_units
    weights = np.asarray(w, dtype=np.float64).reshape(k, -1)
    nx, ny = weights.shape[1] // int(np.prod(model.y_shape)), int(np.prod(model.y_shape))
    a, b = score_matrix(model)
    c = _calibrate(model, np.ascontiguousarray(weights.T), a, b, calibration, seed)
    v_conj, v_relay = c["v_conj"], c["v_relay"]
    pairs, relays = nx * ny, nx + ny
    conj_in = np.zeros((pairs + relays, nx + ny))
    conj_in[np.arange(pairs), np.repeat(np.arange(nx), ny)] = 1.0
    conj_in[np.arange(pairs), nx + np.tile(np.arange(ny), nx)] = 1.0
    conj_in[pairs + np.arange(relays), np.arange(relays)] = 1.0  # the relays: one input each
    beta = c["beta"]
    # the map's drive per step: the fitted responses (alpha times the conjunctions' rates,
    # beta the relays' rates and a constant; a spike counts v_conj or v_relay) through the
    # rule's scores; the LIF integrates dt / tau of it, so its threshold is the median
    # winner's drive over a trial, dt / tau times, shared among MAP_SPIKES spikes
    map_w = np.concatenate(
        [v_conj * ((weights.T * c["alpha"]) @ a).T, v_relay * (beta[:relays] @ a).T], axis=1
    )  # (K, n_x n_y + n_x + n_y)
    map_b = beta[relays] @ a + b + c["shift"]
    map_w, map_b = map_w.astype(np.float32), map_b.astype(np.float32)
    v_map, c["simulated_agreement"] = -1.0, -1.0
    for spikes in MAP_SPIKES:  # the one whose simulated winners agree most, on held-out pairs
        v = np.float32(c["top_score"] * STEPS * DT_S / TAU_S / spikes)
        agree = float(np.mean(winners(*_spike_counts(c, map_w, map_b, v)) == c["held_winners"]))
        if agree > c["simulated_agreement"]:
            v_map, c["simulated_agreement"], c["map_spikes"] = float(v), agree, spikes
    f32 = np.float32
    thresholds = np.concatenate([np.full(pairs, v_conj), np.full(relays, v_relay)])
    bias = np.concatenate([np.full(pairs, -c["theta"]), np.zeros(relays)])
    n_conj = pairs + relays
    nodes = {
        "input": nir.Input(input_type={"input": np.array([nx + ny])}),
        "conjunction": nir.Affine(weight=conj_in.astype(f32), bias=bias.astype(f32)),
        "conjunction_if": nir.IF(r=np.ones(n_conj, f32), v_threshold=thresholds.astype(f32),
                                 v_reset=np.zeros(n_conj, f32)),
        "map": nir.Affine(weight=map_w, bias=map_b),
        "map_lif": nir.LIF(tau=np.full(k, TAU_S, dtype=f32), r=np.ones(k, f32),
                           v_leak=np.zeros(k, f32), v_threshold=np.full(k, v_map, dtype=f32),
                           v_reset=np.zeros(k, f32)),
        "output": nir.Output(output_type={"output": np.array([k])}),
    }  # fmt: skip
    edges = [
        ("input", "conjunction"),
        ("conjunction", "conjunction_if"),
        ("conjunction_if", "map"),
        ("map", "map_lif"),
        ("map_lif", "output"),
    ]
    meta = {
        "producer": "sigmapi",
        "map_shape": json.dumps(list(model.map_shape)),
        "x_code": code_meta(model.x_code),
        "y_code": code_meta(model.y_code),
        "winner_rule": model.winner_rule_.name,
        "theta": c["theta"],
        "shift": c["shift"],
        "conjunctions": pairs,
        "relays": relays,
        "calibration_agreement": c["agreement"],
        "held_out_agreement": c["held_out_agreement"],
        "map_spikes": c["map_spikes"],
        "simulated_agreement": c["simulated_agreement"],
        "dt": DT_S,
        "steps": STEPS,
        "readout": "winner = the map_lif unit with the most spikes over the steps; ties: "
        "the one whose last spike came earliest, then the lowest index; input: [x, y] "
        "held constant",
    }
    return nir.NIRGraph(nodes=nodes, edges=edges, metadata=meta)


def export_nir(
    model: SigmaPiSOM | str | Path, out: str | Path, *, force: bool = False, seed: int = 0
) -> Path:
    """Write the NIR graph of ``model`` (a fitted model or a model file) to ``out`` (HDF5,
    ``nir.write``), atomically; returns the path. Refuses an existing ``out`` unless
    ``force`` (:class:`~sigmapi.errors.UsageError`)."""
    target = Path(out)
    if target.exists() and not force:
        raise UsageError(f"out {str(target)!r} exists; pass force=True (--force) to overwrite it")
    nir = _nir()
    som = model if isinstance(model, SigmaPiSOM) else load_model(model)
    graph = nir_graph(som, seed=seed)
    buffer = io.BytesIO()  # h5py reads back what it writes: not through a write-only handle
    nir.write(buffer, graph)
    return atomic_write_bytes(target, buffer.getvalue())
