"""The Sigma-Pi map beside the baselines
=====================================

The Sigma-Pi map beside a first-order SOM, MiniSom, a basis-function network and an RBM.

Needs the extra: ``pip install 'sigmapi[baselines]'``. The same as ``sigmapi compare``, from
Python::

    python examples/compare_baselines.py           # the quick comparison
    python examples/compare_baselines.py --small   # a tiny one
"""

from __future__ import annotations

import argparse
import dataclasses

from sigmapi.experiments.compare.figures import compare_figure
from sigmapi.experiments.compare.run import QUICK, QUICK_SEEDS, run_compare


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    parser.add_argument("--out", default="compare.png", help="figure file")
    args = parser.parse_args()
    cfg, seeds = QUICK, QUICK_SEEDS
    if args.small:
        small = {"train_pairs": 500, "baseline_iterations": 2000, "rbm_epochs": 1, "n_test": 200,
                 "overrides": ("iterations=5000",)}  # fmt: skip
        cfg, seeds = dataclasses.replace(cfg, **small), (0,)
    result = run_compare(cfg, seeds=seeds)
    print(result.table())
    compare_figure(result.to_dict()).savefig(args.out, dpi=120)
    print(result.caption())


if __name__ == "__main__":
    main()
