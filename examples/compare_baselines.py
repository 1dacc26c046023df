"""The Sigma-Pi map beside a first-order SOM, MiniSom, a basis-function network and an RBM.

Needs the extra: ``pip install 'sigmapi[baselines]'``. The same as ``sigmapi compare``, from
Python:

    python examples/compare_baselines.py           # the quick comparison (about a minute)
    python examples/compare_baselines.py --small   # a few seconds
"""

from __future__ import annotations

import argparse
import dataclasses

from sigmapi.baselines import QUICK, run_compare
from sigmapi.baselines.plots import compare_figure


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    parser.add_argument("--out", default="compare.png", help="figure file")
    args = parser.parse_args()
    cfg = QUICK
    if args.small:
        small = {"seeds": (0,), "train_pairs": 500, "som_iterations": 2000, "rbm_epochs": 1,
                 "n_test": 200, "overrides": ("iterations=5000",)}  # fmt: skip
        cfg = dataclasses.replace(cfg, **small)
    result = run_compare(cfg)
    print(result.table())
    compare_figure(result).savefig(args.out, dpi=120)
    print(result.caption())


if __name__ == "__main__":
    main()
