"""The spiking conjunction network against its rate map, on more test z's than the experiment.

``sigmapi neurons`` scores the spiking networks on ``spike_test`` test z's per seed, and 300
z's put one seed's view consistency within about 0.02, as large as the target. This runs the
same network (``sigmapi neurons``' settings: 100 Hz peak rate and its pool, coincidence
window, gain and inhibition; the experiment's own ``_spiking_rows``) on ``--test`` z's of the
same evaluation set:

    python benchmarks/bench_neurons_spiking.py --seeds 115 116 117 118 119 120 121 122 123 124 \
        --test 1000 --out neurons-spiking-115-124.json

writes ``benchmarks/results/<--out>`` (default ``neurons-spiking.json``): per window, the
median and worst seed of the gap to the rate map's view consistency and of the agreement
with its winners, and how many seeds are within 0.02.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from _common import machine, write_result
from sigmapi import SigmaPiSOM
from sigmapi.experiments.neurons.config import REFERENCE_RATE, NeuronsConfig
from sigmapi.experiments.neurons.result import within_margin
from sigmapi.experiments.neurons.run import NeuronsJob, _spiking_rows
from sigmapi.neurons.spiking import SpikingRun, simulate_conjunction

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[100, 101, 102, 103, 104])
    p.add_argument("--test", type=int, default=1000)
    p.add_argument("--out", default="neurons-spiking.json", help="file name in results/")
    args = p.parse_args()
    config = NeuronsConfig(preset_2d="", spike_test=args.test, peak_rates=(REFERENCE_RATE,))
    start, cpu = time.perf_counter(), time.process_time()
    rows: list[dict[str, Any]] = []
    for seed in args.seeds:
        sp = SigmaPiSOM(config.som_config, seed=seed).fit()
        weights = sp.weights_

        def conj(x: Any, y: Any, cfg: Any, rng: Any, w: Any = weights) -> SpikingRun:
            return simulate_conjunction(w, x, y, cfg, rng)

        job = NeuronsJob(seed, "1d", config)
        rows += [
            {**r, "seed": seed}
            for r in _spiking_rows(
                job, "spiking-conjunction", sp, conj, sp.winner, [(REFERENCE_RATE, config.pool)]
            )
        ]
        print(seed, [(r["window_ms"], round(r["view_consistency"] - r["rate_view_consistency"], 4))
                     for r in rows[-len(config.windows_ms):]], flush=True)  # fmt: skip
    summary = []
    for w in config.windows_ms:
        sel = [r for r in rows if r["window_ms"] == w]
        gap = [r["view_consistency"] - r["rate_view_consistency"] for r in sel]
        agree = [r["agreement"] for r in sel]
        summary.append({"window_ms": w, "vc_gap_median": float(np.median(gap)),
                        "vc_gap_worst": float(min(gap)),
                        "within_002": int(sum(map(within_margin, gap))),
                        "agreement_median": float(np.median(agree)),
                        "agreement_worst": float(min(agree)),
                        "spikes_per_decision": float(np.median([r["spikes_per_decision"]
                                                                for r in sel])),
                        "n_seeds": len(sel)})  # fmt: skip
    seeds = " ".join(map(str, args.seeds))
    command = f"python benchmarks/bench_neurons_spiking.py --seeds {seeds} --test {args.test}"
    if args.out != "neurons-spiking.json":
        command += f" --out {args.out}"
    spiking = config.spiking(REFERENCE_RATE)
    result = {
        "command": command,
        "seeds": args.seeds,
        "test_z": args.test,
        "pool": config.pool,
        "spike_gain": config.spike_gain,
        "spike_inhibition": config.spike_inhibition,
        "coincidence_ms": spiking.coincidence_ms,
        "dt_ms": spiking.dt_ms,
        "peak_rate": REFERENCE_RATE,
        "summary": summary,
        "rows": rows,
        "wall_s": time.perf_counter() - start,
        "cpu_s": time.process_time() - cpu,
        "machine": machine(),
    }
    write_result(RESULTS / args.out, result)


if __name__ == "__main__":
    main()
