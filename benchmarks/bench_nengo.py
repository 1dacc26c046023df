"""The Sigma-Pi map as a spiking Nengo network (``sigmapi.neurons.nengo_net``): its view
consistency against the rate map's, on trained maps of fresh seeds.

Per seed, two maps: ``1d``, paper-1d as the preset trains it (15 units, 15 x 15 codes); ``2d``,
a small map of paper-2d's procedure (a 6 x 6 map, 7 x 7 codes, 3,000 iterations: the paper's
15 x 15 map of 15 x 15 codes takes the Nengo reference simulator about 2 s of CPU per 220 ms
trial, so 1,000 trials about half an hour; ``--model-files`` runs it). For each,
``--pairs`` test z's of ``sigmapi.metrics.evaluation_sets`` shown as their two views (so twice
as many trials), each for the settling time plus the decision window, in one simulation:

- ``view_consistency``: the share of test z's whose two views win the same map neuron in
  Nengo; ``rate_view_consistency``: the same for the rate map (``model.winner``);
  ``vc_gap``: their difference (the target: within 0.02);
- ``agreement``: the share of trials whose Nengo winner is the rate map's;
- ``seconds``: the wall-clock time of building and simulating the trials; ``peak_rss_mb``:
  the process's peak resident memory after it (``ru_maxrss``, so the largest map so far);
  ``neurons``: the network's spiking neurons (input pools and map units) and ``products``:
  the conjunction node's outputs (``n_x n_y``), the size of the learned transform's input.

``--model-files`` runs trained model files instead (``map`` ``paper-2d``, the full 15 x 15
map of 15 x 15 codes; its seed the file's): train them with
``sigmapi train --preset paper-2d --seed N --out FILE``. ``--products active`` sums only the
active inputs' products in the conjunction node (``NengoConfig.products``): the same winners up
to float rounding, about 0.04 s of CPU a trial of the full map instead of 1-2 s.

Usage::

    python benchmarks/bench_nengo.py --seeds 0 1 --out benchmarks/results/nengo-tuning.json
    python benchmarks/bench_nengo.py --seeds 100 101 102 103 104     # fresh: nengo.json
    python benchmarks/bench_nengo.py --model-files paper-2d-seed123.npz paper-2d-seed124.npz \
        --pairs 50 --out benchmarks/results/nengo-paper-2d-123-124.json
    python benchmarks/bench_nengo.py --model-files p2_140.npz p2_141.npz p2_142.npz \
        p2_143.npz p2_144.npz --products active --out benchmarks/results/nengo-paper-2d.json
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import time
from pathlib import Path
from typing import Any

import numpy as np

from _common import machine, write_result

OUT = Path(__file__).resolve().parent / "results" / "nengo.json"


def maps(seed: int) -> dict[str, Any]:
    """The two trained maps of ``seed``."""
    import sigmapi

    one = sigmapi.SigmaPiSOM(sigmapi.load_preset("paper-1d"), seed=seed).fit()
    two = sigmapi.SigmaPiSOM(
        sigmapi.load_preset("paper-2d"),
        map_shape=(6, 6),
        x_shape=(7, 7),
        y_shape=(7, 7),
        iterations=3000,
        refine_pairs=3000,
        seed=seed,
    ).fit()
    return {"1d": one, "2d": two}


def measure(model: Any, pairs: int, cfg: Any, seed: int) -> dict[str, Any]:
    from sigmapi.metrics import evaluation_sets
    from sigmapi.neurons.nengo_net import nengo_winners

    _, test = evaluation_sets(model, max(pairs, 100))
    x = np.vstack([test.x0[:pairs], test.x1[:pairs]])
    y = np.vstack([test.y0[:pairs], test.y1[:pairs]])
    rate = model.winner(x, y)
    start = time.perf_counter()
    w = nengo_winners(model, x, y, cfg, seed=seed)
    secs = time.perf_counter() - start
    vc, rvc = float(np.mean(w[:pairs] == w[pairs:])), float(np.mean(rate[:pairs] == rate[pairs:]))
    nx, ny = x.shape[1], y.shape[1]
    return {
        "view_consistency": vc,
        "rate_view_consistency": rvc,
        "vc_gap": vc - rvc,
        "agreement": float(np.mean(w == rate)),
        "trials": int(x.shape[0]),
        "seconds": secs,
        "seconds_per_trial": secs / x.shape[0],
        "simulated_s": x.shape[0] * (cfg.settle_ms + cfg.window_ms) / 1e3,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "neurons": (nx + ny) * cfg.pool + model.n_units,
        "products": nx * ny,
    }


def _models(args: argparse.Namespace) -> Any:
    """``(seed, map name, model)`` of each map the arguments ask for."""
    if args.model_files:
        from sigmapi.model.som import load_model

        for path in args.model_files:
            model = load_model(path)
            yield int(model.config.seed), "paper-2d", model
        return
    for seed in args.seeds:
        for name, model in maps(seed).items():
            if name in args.maps:
                yield seed, name, model


def main() -> None:
    from sigmapi.neurons.nengo_net import NengoConfig

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102, 103, 104])
    p.add_argument("--pairs", type=int, default=500, help="test z's per map (two views each)")
    p.add_argument("--window-ms", type=float, default=NengoConfig.window_ms)
    p.add_argument("--maps", nargs="+", choices=("1d", "2d"), default=["1d", "2d"])
    p.add_argument(
        "--products",
        choices=("all", "active"),
        default=NengoConfig.products,
        help="the conjunction node's products (NengoConfig.products; active: paper-2d in minutes)",
    )
    p.add_argument(
        "--model-files",
        type=Path,
        nargs="+",
        default=[],
        help="trained model files to run instead of --seeds (map paper-2d)",
    )
    p.add_argument("--out", type=Path, default=OUT)
    args = p.parse_args()
    cfg = NengoConfig(window_ms=args.window_ms, products=args.products)
    start = time.perf_counter()
    rows = []
    for seed, name, model in _models(args):
        row = {"seed": seed, "map": name, **measure(model, args.pairs, cfg, seed)}
        print(row, flush=True)
        rows.append(row)
    names = ["paper-2d"] if args.model_files else args.maps
    summary = {}
    for name in names:
        gaps = [r["vc_gap"] for r in rows if r["map"] == name]
        summary[name] = {
            "vc_gap_median": float(np.median(gaps)),
            "vc_gap_worst": float(max(gaps, key=abs)),
            "met": sum(abs(g) <= 0.02 for g in gaps),
            "n_seeds": len(gaps),
            "agreement_median": float(
                np.median([r["agreement"] for r in rows if r["map"] == name])
            ),
            "seconds_median": float(np.median([r["seconds"] for r in rows if r["map"] == name])),
        }
    which = (
        f"--model-files {' '.join(map(str, args.model_files))}"
        if args.model_files
        else f"--seeds {' '.join(map(str, args.seeds))} --maps {' '.join(args.maps)}"
    )
    write_result(
        args.out,
        {
            "command": f"python benchmarks/bench_nengo.py {which} "
            f"--pairs {args.pairs} --window-ms {args.window_ms:g} --products {args.products}",
            "config": dataclasses.asdict(cfg),
            "rows": rows,
            "summary": summary,
            "wall_s": time.perf_counter() - start,
            "machine": machine(),
        },
    )


if __name__ == "__main__":
    main()
