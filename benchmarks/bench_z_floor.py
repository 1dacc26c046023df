"""Why the 1-D z error stops at about 0.30: the partition of z that the rule's fixed point makes.

Usage (from the repository root)::

    python benchmarks/bench_z_floor.py                      # paper-1d, seeds 700-702
    python benchmarks/bench_z_floor.py --seeds 700 701 --out floor.json

Per seed: trains the preset (its whole procedure), moves the map to its fixed point of Eq. 7
(:func:`sigmapi.analysis.fixed_point.fixed_point`), and counts which unit wins view 0 of
200,000 pairs.
z is uniform, so a unit's share of the wins is the share of the z range it covers (its bin).
Two quantisation floors follow, in input grid spacings like ``z_error``: that of equal bins
(the range over the number of units, over sqrt(12)), and that of the bins the map has (each
bin decoded at its centre; ``sqrt(sum_k share_k width_k^2 / 12)``). The map's own z error
adds to the second the views whose winner is a neighbour of the bin their z lies in.
Writes ``benchmarks/results/z-floor.json``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

import sigmapi
from _common import machine, write_result
from sigmapi import SigmaPiSOM, evaluate
from sigmapi.analysis.fixed_point import fixed_point
from sigmapi.metrics import grid_spacing

ROOT = Path(__file__).resolve().parent
PAIRS = 200_000


def run_seed(preset: str, seed: int) -> dict[str, Any]:
    """The bins of one seed's fixed-point map and the two floors."""
    model = SigmaPiSOM(sigmapi.load_preset(preset).replace(seed=seed)).fit()
    fp = fixed_point(model).model
    assert fp is not None
    if len(fp.map_shape) != 1:
        raise SystemExit(f"{preset} is not a 1-D map; this measures 1-D bins only")
    batch = fp.sampler.sample(PAIRS, np.random.default_rng(7))
    w = fp.winner(batch.x0, batch.y0, hard=True)
    z = batch.z[:, 0]
    lo, hi = fp.sampler.relation.z_range
    spacing = float(grid_spacing(fp.x_shape, fp.config.periodic)[0])
    share = np.bincount(w, minlength=fp.n_units) / w.size
    along = np.argsort([np.median(z[w == k]) if np.any(w == k) else np.inf
                        for k in range(fp.n_units)])  # fmt: skip
    widths = share[along] * (hi - lo)
    return {
        "seed": seed,
        "z_error_refined": float(evaluate(model).z_error),
        "z_error_fixed_point": float(evaluate(fp).z_error),
        "shares_along_z": np.round(share[along], 4).tolist(),
        "end_over_median_width": float(widths[[0, -1]].mean() / np.median(widths)),
        "floor_equal_bins": float((hi - lo) / fp.n_units / np.sqrt(12.0) * spacing),
        "floor_these_bins": float(np.sqrt(np.sum(share[along] * widths**2 / 12.0)) * spacing),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="paper-1d")
    parser.add_argument("--seeds", nargs="*", type=int, default=[700, 701, 702])
    parser.add_argument("--out", default=str(ROOT / "results" / "z-floor.json"))
    args = parser.parse_args()
    runs = []
    for seed in args.seeds:
        runs.append(run_seed(args.preset, seed))
        print({k: v for k, v in runs[-1].items() if k != "shares_along_z"}, flush=True)
    write_result(Path(args.out), {
        "command": f"python benchmarks/bench_z_floor.py --preset {args.preset} --seeds "
                   + " ".join(map(str, args.seeds)),
        "machine": machine(), "preset": args.preset, "pairs": PAIRS, "runs": runs,
    })  # fmt: skip


if __name__ == "__main__":
    main()
