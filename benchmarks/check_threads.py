"""Does a whole training run give the same map on any number of numba threads? A check, not a
timing: one preset and seed trained with ``threads=True`` on the fast kernel once per thread
count, in one process (numba's threads set between runs), the weights compared bit for bit.

    python benchmarks/check_threads.py --preset paper-2d --seed 0 --threads 1 2
    python benchmarks/check_threads.py --threads 1 2 4 8 16 --out threads-16-cores.json

The tests check the same on a small map at the machine's thread count (two here); this runs a
whole preset and takes thread counts up to the machine's cores (a 16-core machine's run is in
``benchmarks/results/threads-16-cores.json``). Writes each run's weight checksum (sha256 of the
float64 weights), its wall time (the first run of each code path includes numba's compilation:
the times are a by-product, not a benchmark) and ``same`` (every checksum equal). Exits 1 when
they differ.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
from pathlib import Path

import numba
import numpy as np

from _common import machine, write_result
from sigmapi import SigmaPiSOM, load_preset


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="paper-2d")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, numba.config.NUMBA_NUM_THREADS])
    ap.add_argument("--out", type=Path, default=None, help="write the JSON here (default: print)")
    args = ap.parse_args(argv)
    top = numba.config.NUMBA_NUM_THREADS
    bad = [n for n in args.threads if not 1 <= n <= top]
    if bad:
        ap.error(f"--threads must be in [1, {top}] (NUMBA_NUM_THREADS), got {bad}")
    cfg = load_preset(args.preset).replace(seed=args.seed, backend="fast", threads=True)
    runs = {}
    for n in args.threads:
        numba.set_num_threads(n)
        t0 = time.perf_counter()
        w = np.ascontiguousarray(SigmaPiSOM(cfg).fit().weights_, dtype=np.float64)
        runs[str(n)] = {
            "sha256": hashlib.sha256(w.tobytes()).hexdigest(),
            "seconds": round(time.perf_counter() - t0, 2),
        }
        print(f"{n:3d} threads: {runs[str(n)]['sha256'][:16]}  {runs[str(n)]['seconds']} s")
    same = len({r["sha256"] for r in runs.values()}) == 1
    result = {
        "preset": args.preset,
        "seed": args.seed,
        "runs": runs,
        "same": same,
        "machine": machine(numba=numba.__version__, numpy=np.__version__, numba_threads=top),
    }
    print("the same map on every thread count" if same else "the maps DIFFER")
    if args.out is not None:
        write_result(args.out, result)
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
