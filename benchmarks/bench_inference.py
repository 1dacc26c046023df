"""Speed of a trained map in use: ``respond``, ``winner``, ``transform`` and ``evaluate``.

Usage (from the repository root)::

    sigmapi train --preset paper-2d --seed 0 --out /tmp/p2.npz      # once, ~40-90 s
    python benchmarks/bench_inference.py --model /tmp/p2.npz
    python benchmarks/bench_inference.py --model /tmp/p2.npz --baseline-src ../main/src

Writes ``benchmarks/results/inference.json``. Each code base is measured in its own process,
the processes alternating (``--repeats`` rounds), so all see the same machine load; every
number is a median. Measured on the model as loaded (the fast kernel) and, for the ratio, on
the same weights on the dense reference kernel (``backend="reference"``, the definition);
``--baseline-src`` adds another checkout's ``src`` (e.g. the code before this benchmark's
changes) measured the same way.

- ``*_one_random_us``: one pair per call, a different pair of the 10,000 test pairs each time
  (its weight rows mostly not in cache), the median over ``--calls`` calls;
- ``respond_one_same_us``: the same pair again and again (weight rows in cache);
- ``*_1000_ms``: batches of 1,000 distinct test pairs;
- ``evaluate_s``: ``sigmapi.evaluate(model)`` (10,000 test pairs and as many calibration pairs,
  their sets precomputed);
- ``winners_checksum``: the sum of the winners of the first 1,000 test pairs (equal for every
  code base that computes the same winners).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from _common import commit, machine, run_child, write_result

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def _median_us(f: Callable[[int], object], calls: int, start: int) -> float:
    times = []
    for i in range(calls):
        t0 = time.perf_counter()
        f(start + i)
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e6


def child(model_path: str, backend: str, calls: int, batches: int, with_eval: bool) -> dict:
    """One round of measurements of one code base (the ``sigmapi`` on ``sys.path``)."""
    import numpy as np

    import sigmapi
    from sigmapi.metrics import evaluation_sets

    model = sigmapi.load(model_path, backend=None if backend == "fast" else backend)
    cal, test = evaluation_sets(model, 10_000)
    x, y = test.x0, test.y0
    n = x.shape[0]

    def pair(i: int) -> tuple[Any, Any]:
        b = (i * 7919) % n  # a stride through the test set: a new pair every call
        return x[b : b + 1], y[b : b + 1]

    model.respond(*pair(0)), model.winner(*pair(0)), model.transform(*pair(0))  # warm up
    model.winner(x[:1000], y[:1000]), model.respond(x[:1000], y[:1000])
    out: dict[str, Any] = {"backend": model.backend}
    out["respond_one_random_us"] = _median_us(lambda i: model.respond(*pair(i)), calls, 1)
    out["respond_one_same_us"] = _median_us(lambda i: model.respond(*pair(0)), calls, 1)
    out["winner_one_random_us"] = _median_us(lambda i: model.winner(*pair(i)), calls, calls)
    out["transform_one_random_us"] = _median_us(
        lambda i: model.transform(*pair(i)), calls, 2 * calls
    )

    def batch(i: int) -> slice:
        s = (i % 10) * 1000
        return slice(s, s + 1000)

    out["respond_1000_ms"] = (
        _median_us(lambda i: model.respond(x[batch(i)], y[batch(i)]), batches, 0) / 1e3
    )
    out["winner_1000_ms"] = (
        _median_us(lambda i: model.winner(x[batch(i)], y[batch(i)]), batches, 1) / 1e3
    )
    out["winners_checksum"] = int(np.sum(model.winner(x[:1000], y[:1000])))
    if with_eval:
        sigmapi.evaluate(model, test=test, calibration=cal)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            sigmapi.evaluate(model, test=test, calibration=cal)
            times.append(time.perf_counter() - t0)
        out["evaluate_s"] = statistics.median(times)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", required=True, help="a paper-2d model file (sigmapi train)")
    parser.add_argument("--baseline-src", type=Path, help="another checkout's src to compare")
    parser.add_argument("--baseline-label", help="what the baseline is (default: its git commit)")
    parser.add_argument("--repeats", type=int, default=3, help="rounds per code base (median)")
    parser.add_argument("--calls", type=int, default=300, help="single-pair calls per round")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "inference.json")
    args = parser.parse_args()

    cases: dict[str, tuple[Path, str, int, bool]] = {
        "fast": (SRC, "fast", 10, True),
        "reference": (SRC, "reference", 3, False),  # ~1-2 s per batch of 1,000: fewer
    }
    if args.baseline_src is not None:
        cases["baseline"] = (args.baseline_src.resolve(), "fast", 10, True)
    rounds: dict[str, list[dict]] = {name: [] for name in cases}
    for r in range(args.repeats):
        for name, (src, backend, batches, ev) in cases.items():
            res = run_child(
                __file__, [args.model, backend, str(args.calls), str(batches), str(int(ev))], src
            )
            rounds[name].append(res)
            print(f"round {r} {name}: {json.dumps(res)}", flush=True)

    keys = [k for k in rounds["fast"][0] if k.endswith(("_us", "_ms", "_s"))]
    medians = {
        name: {k: statistics.median(r[k] for r in runs if k in r) for k in keys if k in runs[0]}
        for name, runs in rounds.items()
    }
    ratios = {
        f"{other}_over_fast": {
            k: medians[other][k] / medians["fast"][k]
            for k in medians[other]
            if k in medians["fast"]
        }
        for other in medians
        if other != "fast"
    }
    result = {
        "command": " ".join(["python benchmarks/bench_inference.py", *sys.argv[1:]]),
        "model": {"path": args.model, "note": "paper-2d preset (15x15 inputs and map)"},
        "machine": machine(),
        "medians": medians,
        "ratios": ratios,
        "winners_checksums": {
            name: sorted({r["winners_checksum"] for r in runs}) for name, runs in rounds.items()
        },
        "baseline": args.baseline_label or commit(args.baseline_src),
        "rounds": rounds,
    }
    write_result(args.out, result)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        a = sys.argv[2:]
        print(json.dumps(child(a[0], a[1], int(a[2]), int(a[3]), a[4] == "1")))
    else:
        main()
