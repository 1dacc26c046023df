"""Model file sizes and save/load times: format version 1 against version 2, side by side.

    python benchmarks/bench_files.py --model m.npz     # a trained model (e.g. paper-2d)
    python benchmarks/bench_files.py                    # trains paper-2d for --iterations

Writes ``benchmarks/results/files.json``: the file size of the model in format version 1
(written by a frozen copy of the version-1 writer: float64 weights plus the backend state), in
version 2 (weights once, in the backend's precision) and version 2 deflated
(``save(compress=True)``), their ratios, and the median save and load times of each over
``--repeats`` rounds (alternating, same process, files in one temporary folder). A model
trained for fewer iterations than the preset's has other values and so deflates differently;
uncompressed sizes do not depend on them.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

import sigmapi
from sigmapi.io import digest, header_digest


def write_version_1(model: sigmapi.SigmaPiSOM, path: Path) -> None:
    """What sigmapi wrote before format version 2 (frozen copy, for the comparison)."""
    header, arrays = model.to_arrays()
    w = np.ascontiguousarray(model.weights_)
    state = {k: v for k, v in arrays.items() if k.startswith("state_")}
    full = {"format": "sigmapi-model", "version": 1, **header, "dtype": str(w.dtype),
            "shape": list(w.shape), "sha256": digest(w),
            "state_sha256": {k[6:]: digest(v) for k, v in state.items()}}  # fmt: skip
    full["header_sha256"] = header_digest(full)
    head = np.frombuffer(json.dumps(full, sort_keys=True).encode(), dtype=np.uint8)
    with open(path, "wb") as fh:
        np.savez(fh, header=head, weights=w, **state)  # type: ignore[arg-type]


def _time(fn: Any) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", help="a trained model file (default: train --preset)")
    p.add_argument("--preset", default="paper-2d")
    p.add_argument("--iterations", type=int, default=5000, help="when training (default 5000)")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--out", default=str(Path(__file__).parent / "results" / "files.json"))
    args = p.parse_args(argv)
    if args.model:
        model, source = sigmapi.load(args.model), Path(args.model).name
    else:
        cfg = sigmapi.load_preset(args.preset).replace(seed=0)
        model = sigmapi.SigmaPiSOM(cfg).fit(iterations=args.iterations)
        source = f"{args.preset}, seed 0, {args.iterations} iterations"
    times: dict[str, dict[str, list[float]]] = {k: {"save": [], "load": []} for k in
                                                ("v1", "v2", "v2_compressed")}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        paths = {k: Path(tmp) / f"{k}.npz" for k in times}
        writers = {
            "v1": lambda: write_version_1(model, paths["v1"]),
            "v2": lambda: model.save(paths["v2"]),
            "v2_compressed": lambda: model.save(paths["v2_compressed"], compress=True),
        }
        for _ in range(args.repeats):
            for k, write in writers.items():
                times[k]["save"].append(_time(write))
                times[k]["load"].append(_time(lambda k=k: sigmapi.load(paths[k])))
        back = sigmapi.load(paths["v2"])
        exact = bool(np.array_equal(back.weights_, model.weights_))
        sizes = {k: paths[k].stat().st_size for k in paths}
    med = {k: {op: statistics.median(v) for op, v in t.items()} for k, t in times.items()}
    result = {
        "model": source,
        "backend": model.backend,
        "weights": int(model.weights_.size),
        "bytes": sizes,
        "ratio_v2_to_v1": sizes["v2"] / sizes["v1"],
        "ratio_v2_compressed_to_v2": sizes["v2_compressed"] / sizes["v2"],
        "median_seconds": med,
        "save_plus_load_v2_seconds": med["v2"]["save"] + med["v2"]["load"],
        "v2_round_trip_exact": exact,
        "repeats": args.repeats,
        "machine": platform.platform(),
        "python": sys.version.split()[0],
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
