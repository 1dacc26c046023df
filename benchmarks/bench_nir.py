"""The NIR graph of a map (``sigmapi export --format nir``), simulated: how often its winner
is the model's, on pairs the graph's calibration did not see.

Usage (from the repository root)::

    sigmapi train --preset paper-2d --seed 1 --out /tmp/p2_1.npz      # once per map, ~2 min
    python benchmarks/bench_nir.py --models /tmp/p2_1.npz /tmp/p2_2.npz [--norse-pairs 100]
        [--graph-dir /tmp/graphs]   # keep the graphs; a later run reads them, e.g. for Norse

Writes ``benchmarks/results/nir.json``. For each model: the graph as
:func:`sigmapi.neurons.nir_graph.nir_graph` makes it (its calibration: pairs of seed 0) and
the time that takes; ``--pairs`` fresh pairs (random positions, ``--pair-seed``) run through
the graph's primitives by NIR's definitions (Affine ``W x + b``; IF ``v += dt R I``; LIF
``v += dt / tau ((v_leak - v) + R I)``; a spike when ``v > v_threshold``, then ``v = v_reset``;
every layer in the same step, as ``tests/cli/test_export_nir.py`` simulates them) for the
graph's ``steps``; the winner is the graph's readout (:func:`sigmapi.neurons.nir_graph.winners`:
the map neuron with the most spikes; ties: the earliest last spike, then the lowest index).
Also reported: the winners of the spike count alone (ties: the lowest index, the readout before
issue 45's item 4 was closed), and of the map's input integrated over the trial without the
map neurons' spikes (what a perfect readout of this graph would give).
An IF neuron under a constant input ``I > 0`` fires every ``floor(v_threshold / (R I dt)) + 1``
steps and never under ``I <= 0``, so the simulation adds each conjunction's weights at those
steps instead of stepping 51,075 membranes (the map's LIF neurons are stepped). With
``--norse-pairs N`` Norse (``norse.torch.from_nir``, an independent reader; needs torch)
simulates the file on the first N of the pairs too.
"""

from __future__ import annotations

import argparse
import io
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from _common import commit, machine, write_result

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def simulate(
    graph: Any, inputs: np.ndarray, chunk: int = 25
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The map neurons' spike counts, their last spikes' steps (from 0; -1: none) and their
    input summed over the trial, each ``(B, K)``, of ``graph`` under the constant ``inputs``
    ``(B, n_x + n_y)`` (module docstring)."""
    n = graph.nodes
    dt, steps = float(graph.metadata["dt"]), int(graph.metadata["steps"])
    conj, fire, mapped, lif = n["conjunction"], n["conjunction_if"], n["map"], n["map_lif"]
    assert np.all(fire.v_reset == 0) and np.all(fire.v_threshold > 0)
    w_map = mapped.weight.astype(np.float64)
    divisors = [[p for p in range(1, t + 1) if t % p == 0] for t in range(steps + 1)]
    counts = np.zeros((len(inputs), w_map.shape[0]))
    last, total = np.full_like(counts, -1.0), np.zeros_like(counts)
    for s in range(0, len(inputs), chunk):
        drive = inputs[s : s + chunk] @ conj.weight.T.astype(np.float64) + conj.bias
        gain = dt * fire.r * drive  # what an IF membrane gains per step
        by_period = np.zeros((len(drive), steps + 1, w_map.shape[0]))
        for b, g in enumerate(gain):
            on = np.flatnonzero(g > 0)
            period = np.floor(fire.v_threshold[on] / g[on]) + 1
            keep = period <= steps
            np.add.at(by_period[b], period[keep].astype(np.int64), w_map[:, on[keep]].T)
        fires = np.floor(steps / np.maximum(np.arange(steps + 1), 1))  # times period p fires
        total[s : s + chunk] = np.einsum("p,bpk->bk", fires[1:], by_period[:, 1:])
        total[s : s + chunk] += steps * mapped.bias
        v = np.zeros((len(drive), w_map.shape[0]))
        for t in range(1, steps + 1):
            current = by_period[:, divisors[t], :].sum(axis=1) + mapped.bias
            v = v + dt / lif.tau * ((lif.v_leak - v) + lif.r * current)
            spikes = v > lif.v_threshold
            v = np.where(spikes, lif.v_reset, v)
            counts[s : s + chunk] += spikes
            last[s : s + chunk][spikes] = t - 1
    return counts, last, total


def norse_spikes(graph: Any, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The map neurons' spike counts and last spikes' steps ``(B, K)`` in Norse."""
    import torch
    from norse.torch import from_nir

    net = from_nir(graph, dt=float(graph.metadata["dt"]))
    x = torch.tensor(inputs, dtype=torch.float32)
    counts, state = torch.zeros(len(inputs), graph.nodes["map_lif"].tau.shape[0]), None
    last = torch.full_like(counts, -1.0)
    with torch.no_grad():
        for t in range(int(graph.metadata["steps"])):
            spikes, state = net(x, state)
            counts += spikes
            last[spikes > 0] = t
    return np.asarray(counts.numpy()), np.asarray(last.numpy())


def measure(
    path: str, pairs: int, pair_seed: int, norse_pairs: int, graph_dir: Path | None
) -> dict[str, Any]:
    import nir

    import sigmapi
    from sigmapi.io import atomic_write_bytes
    from sigmapi.neurons.nir_graph import nir_graph, winners

    model = sigmapi.load(path)
    kept = graph_dir / (Path(path).stem + ".nir") if graph_dir else None
    made: float | None = None
    if kept is not None and kept.exists():  # written by an earlier run: not timed again
        data = kept.read_bytes()
    else:
        t0 = time.perf_counter()
        graph = nir_graph(model)
        made = time.perf_counter() - t0
        buffer = io.BytesIO()
        nir.write(buffer, graph)
        data = buffer.getvalue()
        if kept is not None:
            atomic_write_bytes(kept, data)
    graph = nir.read(io.BytesIO(data))  # what a reader of the file gets
    rng = np.random.default_rng(pair_seed)
    d = len(model.x_shape)
    x, y = model.x_code.encode(rng.random((pairs, d))), model.y_code.encode(rng.random((pairs, d)))
    inputs = np.concatenate([x, y], axis=1)
    want = model.winner(x, y)
    t0 = time.perf_counter()
    counts, last, total = simulate(graph, inputs)
    got = winners(counts, last)
    out: dict[str, Any] = {
        "model": path,
        "map_shape": list(model.map_shape),
        "graph_seconds": made,
        "graph_bytes": len(data),
        "calibration_agreement": float(graph.metadata["calibration_agreement"]),
        "held_out_agreement": float(graph.metadata["held_out_agreement"]),
        "held_out_simulated_agreement": float(graph.metadata["simulated_agreement"]),
        "map_spikes": int(graph.metadata["map_spikes"]),
        "theta": float(graph.metadata["theta"]),
        "pairs": pairs,
        "agreement": float(np.mean(got == want)),
        "count_only_agreement": float(np.mean(counts.argmax(axis=1) == want)),
        "integrated_agreement": float(np.mean(total.argmax(axis=1) == want)),
        "winner_spikes_median": float(np.median(counts.max(axis=1))),
        "simulation_seconds": time.perf_counter() - t0,
    }
    if norse_pairs:
        t0 = time.perf_counter()
        n_counts, n_last = norse_spikes(graph, inputs[:norse_pairs])
        norse = winners(n_counts, n_last)
        out["norse_pairs"] = norse_pairs
        out["norse_agreement"] = float(np.mean(norse == want[:norse_pairs]))
        out["norse_equal_to_simulation"] = float(np.mean(norse == got[:norse_pairs]))
        out["norse_spike_trains_equal_to_simulation"] = float(  # counts and last spikes
            np.mean(
                np.all(n_counts == counts[:norse_pairs], axis=1)
                & np.all(n_last == last[:norse_pairs], axis=1)
            )
        )
        out["norse_seconds"] = time.perf_counter() - t0
    print(out, flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", nargs="+", required=True, help="model files (sigmapi train)")
    parser.add_argument("--pairs", type=int, default=500, help="fresh pairs per model")
    parser.add_argument("--pair-seed", type=int, default=2026, help="seed of the fresh pairs")
    parser.add_argument("--norse-pairs", type=int, default=0, help="of those, run in Norse")
    parser.add_argument(
        "--graph-dir", type=Path, default=None,
        help="keep each model's graph here (MODEL_STEM.nir) and read it from there next time",
    )  # fmt: skip
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "nir.json")
    args = parser.parse_args()
    import nir

    runs = [
        measure(m, args.pairs, args.pair_seed, args.norse_pairs, args.graph_dir)
        for m in args.models
    ]
    agree = [r["agreement"] for r in runs]
    write_result(
        args.out,
        {
            "runs": runs,
            "agreement_median": statistics.median(agree),
            "agreement_worst": min(agree),
            "at_least_95_percent": sum(a >= 0.95 for a in agree),
            "nir": nir.__version__,
            "commit": commit(SRC),
            "machine": machine(),
        },
    )


if __name__ == "__main__":
    main()
