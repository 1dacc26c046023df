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
- ``winners_equal``: the graph's ``winner`` equals ``model.winner`` on all 10,000 test pairs;
- ``gather_f64_one_us``, ``gather_f32_one_us``: the floor of any graph that reads each pair's
  kept weight rows: onnxruntime gathering just those rows (their indices computed beforehand,
  in Python), from the float64 weights the graph holds and from the model's float32 columns,
  one pair per call, alternating with ``respond`` (``floor_respond_one_us``) like the rest;
  ``gather_matmul_f64_one_us``, ``gather_cast_matmul_f32_one_us``: the same rows gathered and
  summed with the pair's products (float64 ``MatMul``; float32 rows cast to float64 first):
  the graph's core without the selection of the rows;
- ``onnx_profile_one_us``: onnxruntime's profiler on ``--calls`` single-pair calls of the
  exported graph: each operator type's kernel time per call (median over calls), largest first.

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
        session = ort.InferenceSession(
            str(path), _options(threads), providers=["CPUExecutionProvider"]
        )
        size = path.stat().st_size
        profile = _profile(str(path), x, y, calls, threads, tmp)

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
    floors = _gather_floors(model, x, y, calls, threads)
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
        **floors,
        "onnx_profile_one_us": profile,
        "winners_equal": equal,
        "onnx_bytes": size,
        "kernel_tol": float(model.config.kernel_tol),
        "map_shape": list(model.map_shape),
    }
    out["onnx_over_respond_one"] = out["onnx_one_us"] / out["respond_one_us"]
    out["onnx_over_respond_1000"] = out["onnx_1000_ms"] / out["respond_1000_ms"]
    return out


def _options(threads: int, profile_in: str | None = None) -> Any:
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.intra_op_num_threads = threads
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    if profile_in is not None:
        options.enable_profiling = True
        options.profile_file_prefix = str(Path(profile_in) / "profile")
    return options


def _profile(path: str, x: Any, y: Any, calls: int, threads: int, tmp: str) -> dict[str, float]:
    """Each operator type's kernel time per single-pair call (median over calls, us), from
    onnxruntime's profiler; nodes inside the ``Scan`` body count under their own type."""
    import json

    import onnxruntime as ort

    session = ort.InferenceSession(path, _options(threads, tmp), providers=["CPUExecutionProvider"])
    session.run(["winner"], {"x": x[:1], "y": y[:1]})  # warm up
    for i in range(calls):
        b = (i * 7919) % x.shape[0]
        session.run(["winner"], {"x": x[b : b + 1], "y": y[b : b + 1]})
    events = json.loads(Path(session.end_profiling()).read_text(encoding="utf-8"))
    runs = [e for e in events if e.get("cat") == "Session" and e["name"] == "model_run"]
    per_run: dict[str, list[float]] = {}
    for r, run in enumerate(runs[1:]):  # the warm-up run left out
        t0, t1 = run["ts"], run["ts"] + run["dur"]
        for e in events:
            if e.get("cat") == "Node" and e["name"].endswith("_kernel_time") and t0 <= e["ts"] < t1:
                op = e["args"]["op_name"]
                per_run.setdefault(op, [0.0] * (len(runs) - 1))[r] += e["dur"]
    per_run["model_run"] = [float(run["dur"]) for run in runs[1:]]
    medians = {op: statistics.median(v) for op, v in per_run.items()}
    return dict(sorted(medians.items(), key=lambda kv: -kv[1]))


def _gather_floors(model: Any, x: Any, y: Any, calls: int, threads: int) -> dict[str, float]:
    """onnxruntime on each pair's kept weight rows, their indices and products computed
    beforehand in Python: gathering them (float64 and float32 weights) and gathering and
    summing them (float64 ``MatMul``; float32 rows ``Cast`` to float64 first), against
    ``respond`` call by call; medians (us)."""
    import numpy as np
    import onnxruntime as ort
    from onnx import TensorProto, helper, numpy_helper

    from sigmapi.export import _columns, _truncation

    raw, _ = _columns(model)
    tol = _truncation(model)
    f64, f32 = TensorProto.DOUBLE, TensorProto.FLOAT
    gather = helper.make_node("Gather", ["w", "rows"], ["picked"], axis=0)
    total = helper.make_node("MatMul", ["values", "picked64"], ["out"])
    graphs = {
        "gather_f64": (np.float64, f64, [gather], "picked"),
        "gather_f32": (np.float32, f32, [gather], "picked"),
        "gather_matmul_f64": (np.float64, f64, [gather,
            helper.make_node("Identity", ["picked"], ["picked64"]), total], "out"),
        "gather_cast_matmul_f32": (np.float32, f64, [gather,
            helper.make_node("Cast", ["picked"], ["picked64"], to=f64), total], "out"),
    }  # fmt: skip
    sessions = {}
    for name, (dtype, kind, nodes, out) in graphs.items():
        rank = [None, raw.shape[1]] if out == "picked" else [raw.shape[1]]
        graph = helper.make_graph(
            nodes,
            name,
            [helper.make_tensor_value_info("rows", TensorProto.INT64, [None]),
             helper.make_tensor_value_info("values", f64, [None])],
            [helper.make_tensor_value_info(out, kind, rank)],
            [numpy_helper.from_array(raw.astype(dtype), "w")],
        )  # fmt: skip
        proto = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 21)])
        proto.ir_version = 10
        sessions[name] = (out, ort.InferenceSession(
            proto.SerializeToString(), _options(threads), providers=["CPUExecutionProvider"]
        ))  # fmt: skip
    times: dict[str, list[float]] = {name: [] for name in [*graphs, "respond"]}
    for i in range(calls):
        b = (i * 7919) % x.shape[0]
        outer = np.outer(x[b], y[b]).ravel()
        rows = np.flatnonzero(np.abs(outer) > tol * np.abs(x[b]).max() * np.abs(y[b]).max())
        feed = {"rows": rows, "values": outer[rows]}
        for name, (out, session) in sessions.items():
            t0 = time.perf_counter()
            session.run([out], feed)
            times[name].append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        model.respond(x[b : b + 1], y[b : b + 1])
        times["respond"].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) * 1e6 for k, v in times.items()}
    return {f"{k}_one_us": v for k, v in med.items() if k != "respond"} | {
        "floor_respond_one_us": med["respond"]
    }


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
