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
  code base that computes the same winners);
- floors, measured in the same process on the fast kernel (:func:`floors`): a loop that only
  reads a pair's weight rows, the triad bandwidth (one thread) and the bytes a call needs over
  it; ``fast_over_floors`` holds each call's median ratio to them, beside the triad's GB/s.
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
    if backend == "fast":
        out.update(floors(model, x, y, calls, pair))
    if with_eval:
        sigmapi.evaluate(model, test=test, calibration=cal)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            sigmapi.evaluate(model, test=test, calibration=cal)
            times.append(time.perf_counter() - t0)
        out["evaluate_s"] = statistics.median(times)
    return out


def floors(model: Any, x: Any, y: Any, calls: int, pair: Callable[[int], Any]) -> dict:
    """The floors of the fast kernel's calls on this machine, in this process.

    ``read_one_random_us``: a compiled loop that only reads (sums) the weight rows of a pair's
    kept input pairs, all units, prefetching 8 rows ahead as the kernel does, for the same pairs
    as ``respond_one_random_us`` (the bytes a one-pair call must read, in its order, with
    nothing else); ``bytes_one_mean``: those bytes;
    ``triad_one_thread_gb_s``: a STREAM-like triad over 3 x 256 MiB (one thread);
    ``bandwidth_one_us``: the bytes over the triad; ``bandwidth_1000_ms``: a batch's floor if
    every weight row its pairs need were read once (the union of their kept rows) at the
    triad's rate.
    """
    import numpy as np
    from numba import njit

    from sigmapi.kernels._rows import _pairs, prefetch_row

    st = model._run.state if hasattr(model, "_run") else model._state  # older --baseline-src
    raw, tol = st.raw, st.tol

    @njit(cache=False)
    def read_rows(raw, xv, yv, tol, jb, pi, pv, acc):  # type: ignore[no-untyped-def]
        n = _pairs(xv, yv, tol, jb, pi, pv)
        for k in range(acc.shape[0]):
            acc[k] = 0.0
        for q in range(min(n, 8)):
            prefetch_row(raw, pi[q])
        for q in range(n):
            if q + 8 < n:
                prefetch_row(raw, pi[q + 8])  # as the kernel's calls prefetch
            row = raw[pi[q]]
            for k in range(acc.shape[0]):
                acc[k] += row[k]
        return n

    @njit(cache=False)
    def triad(a, b, c, s):  # type: ignore[no-untyped-def]
        for i in range(a.shape[0]):
            a[i] = b[i] + s * c[i]

    jb, pi, pv = st.scratch()[:3]
    acc = np.empty(raw.shape[1], dtype=raw.dtype)
    row_bytes = raw.shape[1] * raw.itemsize
    kept = [read_rows(raw, *(a[0] for a in pair(0)), tol, jb, pi, pv, acc)]
    out: dict[str, Any] = {}
    out["read_one_random_us"] = _median_us(
        lambda i: kept.append(read_rows(raw, *(a[0] for a in pair(i)), tol, jb, pi, pv, acc)),
        calls, 1,
    )  # fmt: skip
    out["bytes_one_mean"] = float(np.mean(kept[1:])) * row_bytes
    n = 256 * 2**20 // 8
    a, b, c = np.zeros(n), np.ones(n), np.full(n, 2.0)
    triad(a, b, c, 3.0)
    best = min(_median_us(lambda i: triad(a, b, c, 3.0), 1, 0) for _ in range(5))
    gb_s = 24 * n / best / 1e3
    out["triad_one_thread_gb_s"] = gb_s
    out["bandwidth_one_us"] = out["bytes_one_mean"] / gb_s / 1e3
    rows = set()
    for i in range(1000):
        m = _pairs(x[i], y[i], tol, jb, pi, pv)
        rows.update(pi[:m].tolist())
    out["bandwidth_1000_ms"] = len(rows) * row_bytes / gb_s / 1e6
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

    keys = [k for k in rounds["fast"][0] if k.endswith(("_us", "_ms", "_s", "_mean"))]
    medians = {
        name: {k: statistics.median(r[k] for r in runs if k in r) for k in keys if k in runs[0]}
        for name, runs in rounds.items()
    }
    floor_pairs = {
        "respond_one_random_us": ("read_one_random_us", "bandwidth_one_us"),
        "winner_one_random_us": ("read_one_random_us", "bandwidth_one_us"),
        "respond_1000_ms": (None, "bandwidth_1000_ms"),
        "winner_1000_ms": (None, "bandwidth_1000_ms"),
    }
    over_floor = {
        f"{call}_over_{floor}": statistics.median(r[call] / r[floor] for r in rounds["fast"])
        for call, pair_floors in floor_pairs.items()
        for floor in pair_floors
        if floor is not None
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
        "fast_over_floors": over_floor,
        "triad_one_thread_gb_s": medians["fast"]["triad_one_thread_gb_s"],
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
