"""A trained Sigma-Pi map as a NIR graph (the Neuromorphic Intermediate Representation, read
by Norse, snnTorch, Rockpool, Sinabs, Spyx, Lava-DL and SpiNNaker2): :func:`nir_graph`,
``sigmapi export MODEL --format nir --out FILE.nir`` (docs/guide/other-tools.md).

The graph uses only primitives that most readers support (``Input``, ``Affine``, ``IF``,
``LIF``, ``Output``; no ``Threshold``, which only Spyx reads), in one chain::

    input (n_x + n_y) -> conjunction Affine -> conjunction IF (n_x n_y) -> map Affine -> map LIF
    (n_units) -> output

- **input**: the two codes side by side, ``[x, y]`` (``x_code.encode``, ``y_code.encode``,
  flattened in C order), held as a constant current for the whole trial;
- **conjunction**: one integrate-and-fire neuron per input pair ``(i, j)`` (index
  ``i n_y + j``), driven by ``x_i + y_j - theta`` (weights 1 and 1, bias ``-theta``), threshold
  ``conjunction_threshold``, reset to 0. Its rate is ``max(0, x_i + y_j - theta)`` over the
  threshold: an AND of its two inputs (with ``theta`` near one code's peak it fires only when
  both are active), in place of the product ``x_i y_j`` a Sigma-Pi weight multiplies. NIR has
  no product of two signals; this is the sum-and-threshold conjunction of the dendritic and
  basis-function maps (:mod:`sigmapi.neurons.basis`) with a linear instead of a sigmoid rise;
- **map**: the learned weights. Unit ``k`` receives conjunction ``(i, j)`` with weight
  ``alpha * threshold * S_k . W_(ij)`` (``W`` the Sigma-Pi weights, ``S`` the winner rule's
  affine map of the responses, :func:`sigmapi.export.score_matrix`: the soft rule's smoothing,
  ``min_distance``'s squared norms in the bias) and a bias, the rule's offset plus a constant
  shift that keeps the winner's drive positive (the same for every unit, so it changes no
  ranking). The units are leaky integrate-and-fire neurons with a time constant far longer
  than a trial (near-perfect integrators); the winner is the unit that fires most (ties: the
  lowest index).

``theta``, ``alpha`` (the scale of the conjunctions' rates against the products) and the shift
are chosen when the graph is made, on ``calibration`` pairs of random positions drawn with
``seed``: those of a small grid that give the most rate-level winners equal to the model's
(:func:`conjunction_scores`). The graph's metadata holds them, the codes, and how to simulate
it: ``dt = 1`` (the graph's time unit is one step) for ``steps = 2000`` steps. The
sum-and-threshold conjunction is not the product: on paper-1d maps about 97 % of the
rate-level winners are the model's, on a paper-2d map (seed 0) 92 %, so the 2-D graph misses
the 95 % target. Simulated, the file of a paper-1d map (seed 7) gave the model's winners on
96.6 % of 500 fresh pairs in Norse and on 97.0 % of 400 in a forward-Euler simulation of the
primitives (``tests/cli/test_export_nir.py``).
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

__all__ = ["DT_S", "STEPS", "conjunction_scores", "export_nir", "nir_graph"]

Array = NDArray[np.float64]

DT_S = 1.0
"""Time step the graph is meant to be simulated with: the graph's time unit is one step (the
IF neurons gain ``R I dt`` per step, as Norse's integrate-and-fire cell adds its input)."""
STEPS = 2000
"""Steps of one trial."""
CONJUNCTION_PERIOD = 10
"""The strongest conjunction neuron of a calibration pair fires about once in this many
steps (at ``DT_S``): a rate that ``STEPS`` resolve to about 1 %."""
MAP_SPIKES = 30
"""The winner's spikes in a trial, about (its rate resolves the ranking to about 0.5 %)."""
TAU_S = 1e6
"""The map neurons' time constant (s): leak negligible over a trial."""
THETAS = (0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)
"""Candidate ``theta``, in units of the larger code's peak value."""
ALPHAS = (0.5, 1.0, 2.0, 4.0)
"""Candidate multipliers of the least-squares scale of the conjunctions' rates."""


def _nir() -> Any:
    try:
        import nir
    except ImportError:
        raise UsageError(
            f"exporting to NIR needs the nir package (not installed here); {install_hint('nir')}"
        ) from None
    return nir


def conjunction_rates(x: Array, y: Array, theta: float, v_conj: float) -> Array:
    """What the conjunction neurons pass on in a trial ``(B, n_x n_y)``: their spikes over
    :data:`STEPS` steps (``dt = 1``: the membrane gains ``I = x_i + y_j - theta`` per step, fires
    above ``v_conj`` and resets to 0, so it fires every ``floor(v_conj / I) + 1`` steps), times
    ``v_conj``, per step: ``max(0, I)`` less what the reset discards."""
    drive = (x[:, :, None] + y[:, None, :] - theta).reshape(x.shape[0], -1)
    period = np.floor(v_conj / np.maximum(drive, 1e-300)) + 1.0
    spikes = np.where(drive > 0, np.floor(STEPS / np.minimum(period, 2.0 * STEPS)), 0.0)
    return np.asarray(spikes * v_conj / STEPS)


def conjunction_scores(
    weights: Array,
    a: Array,
    b: Array,
    x: Array,
    y: Array,
    theta: float,
    v_conj: float,
    alpha: float,
) -> Array:
    """Rate-level scores ``(B, K)`` of the graph: ``alpha`` times the conjunctions' rates
    (:func:`conjunction_rates`) in place of ``x_i y_j``, through the weights ``(K, n_x n_y)``
    and the rule's affine map ``(a, b)``."""
    return alpha * _responses(weights, x, y, theta, v_conj) @ a + b


def _responses(weights: Array, x: Array, y: Array, theta: float, v_conj: float) -> Array:
    out = np.empty((x.shape[0], weights.shape[0]))
    for s in range(0, x.shape[0], 128):  # (B, n_x n_y) in pieces: 2-D maps have 50,625 pairs
        out[s : s + 128] = conjunction_rates(x[s : s + 128], y[s : s + 128], theta, v_conj) @ (
            weights.T
        )
    return out


def _calibrate(
    model: SigmaPiSOM, weights: Array, a: Array, b: Array, n: int, seed: int
) -> dict[str, float]:
    """``theta``, the conjunctions' threshold, ``alpha``, the bias shift and the rate-level
    agreement on ``n`` pairs."""
    rng = np.random.default_rng(seed)
    x = model.x_code.encode(rng.random((n, len(model.x_shape))))
    y = model.y_code.encode(rng.random((n, len(model.y_shape))))
    want = model.winner(x, y)
    peak = float(max(x.max(), y.max()))
    best: dict[str, float] = {"agreement": -1.0}
    for t in THETAS:
        top = float(np.max(x[:, :, None] + y[:, None, :])) - t * peak
        v_conj = top * CONJUNCTION_PERIOD  # the strongest fires once in the period
        h = _responses(weights, x, y, t * peak, v_conj)
        # alpha's least-squares value: the rates' scale against the products x_i y_j, from
        # the responses (h against the model's responses)
        hm = model.respond(x, y)
        ls = float((h * hm).sum() / max(float((h * h).sum()), 1e-300))
        for m in ALPHAS if np.any(b != 0) else (1.0,):  # without an offset the scale is free
            s = m * ls * h @ a + b
            agree = float(np.mean(np.argmax(s, axis=1) == want))
            if agree > best["agreement"]:
                win = s.max(axis=1)
                shift = max(0.0, -float(win.min())) + 0.1 * float(np.ptp(win) + 1e-12)
                best = {"theta": t * peak, "v_conj": v_conj, "alpha": m * ls,
                        "agreement": agree, "shift": shift,
                        "top_score": float(np.median(win)) + shift}  # fmt: skip
    return best


def nir_graph(model: SigmaPiSOM, calibration: int = 1000, seed: int = 0) -> Any:
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
    c = _calibrate(model, weights, a, b, calibration, seed)
    v_conj = c["v_conj"]
    conj_in = np.zeros((nx * ny, nx + ny))
    conj_in[np.arange(nx * ny), np.repeat(np.arange(nx), ny)] = 1.0
    conj_in[np.arange(nx * ny), nx + np.tile(np.arange(ny), nx)] = 1.0
    # the map's drive per step: alpha times the conjunctions' rates (a spike counts v_conj)
    # through the rule's scores; the LIF integrates dt / tau of it, so its threshold is the
    # median winner's drive over a trial, dt / tau times, shared among MAP_SPIKES spikes
    map_w = c["alpha"] * v_conj * (weights.T @ a).T  # (K, n_x n_y)
    map_b = b + c["shift"]
    v_map = c["top_score"] * STEPS * DT_S / TAU_S / MAP_SPIKES
    f32 = np.float32
    nodes = {
        "input": nir.Input(input_type={"input": np.array([nx + ny])}),
        "conjunction": nir.Affine(weight=conj_in.astype(f32),
                                  bias=np.full(nx * ny, -c["theta"], dtype=f32)),
        "conjunction_if": nir.IF(r=np.ones(nx * ny, f32),
                                 v_threshold=np.full(nx * ny, v_conj, dtype=f32),
                                 v_reset=np.zeros(nx * ny, f32)),
        "map": nir.Affine(weight=map_w.astype(f32), bias=map_b.astype(f32)),
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
        "alpha": c["alpha"],
        "shift": c["shift"],
        "calibration_agreement": c["agreement"],
        "dt": DT_S,
        "steps": STEPS,
        "readout": "winner = the map_lif unit with the most spikes over the steps "
        "(ties: the lowest index); input: [x, y] held constant",
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
