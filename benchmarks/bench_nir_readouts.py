"""Readouts of the NIR graph's map neurons, and their thresholds: how often each gives the
model's winner (the choice behind :func:`sigmapi.neurons.nir_graph.winners` and
``MAP_SPIKES``).

Usage (from the repository root)::

    sigmapi train --preset paper-2d --seed 0 --out /tmp/p2_0.npz
    sigmapi export /tmp/p2_0.npz --format nir --out /tmp/g_0.nir
    python benchmarks/bench_nir_readouts.py --models /tmp/p2_0.npz --graphs /tmp/g_0.nir

Writes ``benchmarks/results/nir-readouts.json``. For each map: ``--pairs`` fresh pairs
(``--pair-seed``); each pair's input to the map neurons at every step, from the graph by NIR's
definitions (each IF neuron under a constant input fires every
``floor(v_threshold / I) + 1`` steps, as in ``bench_nir.py``); then the map neurons (leak
negligible, reset to 0) at several thresholds, each the median winner's input over the trial
(over the first 25 pairs) divided by ``--spikes`` (about the winner's spikes in a trial; the
graph's own threshold is not used). The readouts: ``count`` (the most spikes; ties: the
lowest index), ``count_first`` and ``count_last`` (ties: the earliest first or last spike),
``first_spike`` (the earliest first spike), and ``integrated`` (the input summed over the
trial, without the map neurons' spikes: what a perfect readout of the graph gives).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from _common import commit, machine, write_result

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def currents(graph: Any, inputs: np.ndarray, steps: int) -> np.ndarray:
    """The map neurons' input at each step ``(B, steps, K)``, in the units the LIF adds
    ``dt / tau`` of per step."""
    n = graph.nodes
    conj, fire, mapped = n["conjunction"], n["conjunction_if"], n["map"]
    w_map = mapped.weight.astype(np.float64)
    drive = inputs @ conj.weight.T.astype(np.float64) + conj.bias
    cur = np.broadcast_to(mapped.bias.astype(np.float64), (len(inputs), steps, len(w_map)))
    cur = cur.copy()
    for b, g in enumerate(float(graph.metadata["dt"]) * fire.r * drive):
        on = np.flatnonzero(g > 0)
        period = np.floor(fire.v_threshold[on] / g[on]) + 1
        keep = period <= steps
        on, period = on[keep], period[keep].astype(np.int64)
        by_period = np.zeros((steps + 1, len(w_map)))
        np.add.at(by_period, period, w_map[:, on].T)
        for p in np.unique(period):  # fires at steps p, 2p, ... (step t is index t - 1)
            cur[b, p - 1 :: p] += by_period[p]
    return cur


def spikes(cur: np.ndarray, thresholds: np.ndarray) -> tuple[np.ndarray, ...]:
    """Counts, first and last spikes' steps ``(B, M, K)`` of integrators (reset to 0) fed
    ``cur`` at each of the ``M`` thresholds."""
    b, steps, k = cur.shape
    shape = (b, len(thresholds), k)
    v, count = np.zeros(shape), np.zeros(shape)
    first, last = np.full(shape, np.inf), np.full(shape, np.inf)
    for t in range(steps):
        v = v + cur[:, t, None, :]
        fired = v > thresholds[None, :, None]
        v = np.where(fired, 0.0, v)
        count += fired
        first = np.where(fired & np.isinf(first), t, first)
        last = np.where(fired, t, last)
    return count, first, last


def readouts(count: np.ndarray, first: np.ndarray, last: np.ndarray) -> dict[str, np.ndarray]:
    top = count == count.max(axis=-1, keepdims=True)
    return {
        "count": count.argmax(axis=-1),
        "count_first": np.where(top, -first, -np.inf).argmax(axis=-1),
        "count_last": np.where(top, -last, -np.inf).argmax(axis=-1),
        "first_spike": (-first).argmax(axis=-1),
    }


def measure(model_path: str, graph_path: str, args: argparse.Namespace) -> dict[str, Any]:
    import nir

    import sigmapi

    model, graph = sigmapi.load(model_path), nir.read(graph_path)
    steps = int(graph.metadata["steps"])
    rng = np.random.default_rng(args.pair_seed)
    d = len(model.x_shape)
    x = model.x_code.encode(rng.random((args.pairs, d)))
    y = model.y_code.encode(rng.random((args.pairs, d)))
    want, inputs = model.winner(x, y), np.concatenate([x, y], axis=1)
    t0 = time.perf_counter()
    got: dict[str, list[np.ndarray]] = {}
    thresholds = None
    for s in range(0, args.pairs, 25):
        cur = currents(graph, inputs[s : s + 25], steps)
        total = cur.sum(axis=1)
        if thresholds is None:
            thresholds = float(np.median(total.max(axis=1))) / np.asarray(args.spikes)
        got.setdefault("integrated", []).append(total.argmax(axis=1))
        for name, won in readouts(*spikes(cur, thresholds)).items():
            got.setdefault(name, []).append(won)
    out: dict[str, Any] = {"model": model_path, "graph": graph_path, "pairs": args.pairs}
    out["integrated"] = float(np.mean(np.concatenate(got.pop("integrated")) == want))
    for name, parts in got.items():
        won = np.concatenate(parts)
        out[name] = {f"{k:g}": float(np.mean(won[:, i] == want)) for i, k in enumerate(args.spikes)}
    out["seconds"] = time.perf_counter() - t0
    print(out, flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models", nargs="+", required=True, help="model files (sigmapi train)")
    parser.add_argument("--graphs", nargs="+", required=True, help="their NIR files, in order")
    parser.add_argument("--pairs", type=int, default=500, help="fresh pairs per model")
    parser.add_argument("--pair-seed", type=int, default=11, help="seed of the fresh pairs")
    parser.add_argument(
        "--spikes", type=float, nargs="+", default=[2, 3, 5, 10, 20, 30, 45, 60, 90]
    )
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "nir-readouts.json")
    args = parser.parse_args()
    if len(args.models) != len(args.graphs):
        parser.error(f"--graphs: one per model ({len(args.models)}), got {len(args.graphs)}")
    runs = [measure(m, g, args) for m, g in zip(args.models, args.graphs, strict=True)]
    write_result(
        args.out,
        {"runs": runs, "spikes": args.spikes, "pair_seed": args.pair_seed,
         "commit": commit(SRC), "machine": machine()},
    )  # fmt: skip


if __name__ == "__main__":
    main()
