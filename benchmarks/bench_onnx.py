"""The exported ONNX graph in onnxruntime against the model's own ``respond`` in Python.

Usage (from the repository root)::

    sigmapi train --preset paper-2d --seed 0 --out /tmp/p2.npz      # once, ~1-2 min
    python benchmarks/bench_onnx.py --model /tmp/p2.npz

Writes ``benchmarks/results/onnx.json``. One process, the two paths alternating call by call
(both see the same machine load); every number is a median:

- ``*_one_us``: one pair per call, a different pair of the 10,000 test pairs each time
  (:func:`sigmapi.metrics.evaluation_sets`), ``--calls`` calls;
- ``*_1000_ms``: batches of 1,000 distinct test pairs, ``--batches`` batches;
- ``onnx_over_respond_*``: the medians' ratio (the target: at most 2);
- ``winners_equal``: the graph's ``winner`` equals ``model.winner`` on all 10,000 test pairs.

onnxruntime runs on one thread (``intra_op_num_threads=1``) unless ``--threads`` says more;
``respond`` uses the fast kernel as loaded (numba's threads for a batch).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from _common import commit, machine, write_result

ROOT = Path(__file__).resolve().parent
SRC = ROOT.parent / "src"


def measure(model_path: str, calls: int, batches: int, threads: int) -> dict[str, Any]:
    """Both paths on the test pairs of ``model_path``; medians and their ratios."""
    import numpy as np
    import onnxruntime as ort

    import sigmapi
    from sigmapi.export import export_onnx
    from sigmapi.metrics import evaluation_sets

    model = sigmapi.load(model_path)
    _, test = evaluation_sets(model, 10_000)
    x, y = test.x0, test.y0
    n = x.shape[0]
    with tempfile.TemporaryDirectory() as tmp:
        path = export_onnx(model, Path(tmp) / "map.onnx")
        options = ort.SessionOptions()
        options.intra_op_num_threads = threads
        session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        size = path.stat().st_size

    def graph(a: Any, b: Any) -> Any:
        return session.run(["winner"], {"x": a, "y": b})[0]

    winners = np.concatenate([graph(x[s : s + 1000], y[s : s + 1000]) for s in range(0, n, 1000)])
    equal = bool(np.array_equal(winners, model.winner(x, y)))
    model.respond(x[:1], y[:1]), model.respond(x[:1000], y[:1000])  # warm up (numba, caches)
    times: dict[str, list[float]] = {k: [] for k in ("onnx_one", "respond_one")}
    for i in range(calls):
        b = (i * 7919) % n  # a stride through the test set: a new pair every call
        a, c = x[b : b + 1], y[b : b + 1]
        t0 = time.perf_counter()
        graph(a, c)
        t1 = time.perf_counter()
        model.respond(a, c)
        t2 = time.perf_counter()
        times["onnx_one"].append(t1 - t0)
        times["respond_one"].append(t2 - t1)
    times.update(onnx_1000=[], respond_1000=[])
    for i in range(batches):
        s = slice((i % 10) * 1000, (i % 10) * 1000 + 1000)
        t0 = time.perf_counter()
        graph(x[s], y[s])
        t1 = time.perf_counter()
        model.respond(x[s], y[s])
        t2 = time.perf_counter()
        times["onnx_1000"].append(t1 - t0)
        times["respond_1000"].append(t2 - t1)
    out: dict[str, Any] = {
        "onnx_one_us": statistics.median(times["onnx_one"]) * 1e6,
        "respond_one_us": statistics.median(times["respond_one"]) * 1e6,
        "onnx_1000_ms": statistics.median(times["onnx_1000"]) * 1e3,
        "respond_1000_ms": statistics.median(times["respond_1000"]) * 1e3,
        "winners_equal": equal,
        "onnx_bytes": size,
        "kernel_tol": float(model.config.kernel_tol),
        "map_shape": list(model.map_shape),
    }
    out["onnx_over_respond_one"] = out["onnx_one_us"] / out["respond_one_us"]
    out["onnx_over_respond_1000"] = out["onnx_1000_ms"] / out["respond_1000_ms"]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", required=True, help="a model file (sigmapi train)")
    parser.add_argument("--calls", type=int, default=500, help="single-pair calls per path")
    parser.add_argument("--batches", type=int, default=20, help="batches of 1,000 per path")
    parser.add_argument("--threads", type=int, default=1, help="onnxruntime's intra-op threads")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "onnx.json")
    args = parser.parse_args()
    import onnxruntime

    result = measure(args.model, args.calls, args.batches, args.threads)
    print(result, flush=True)
    write_result(
        args.out,
        {
            "model": args.model,
            "calls": args.calls,
            "batches": args.batches,
            "onnxruntime_threads": args.threads,
            "onnxruntime": onnxruntime.__version__,
            "commit": commit(SRC),
            "machine": machine(),
            **result,
        },
    )


if __name__ == "__main__":
    main()
