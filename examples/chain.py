"""A chain of frames
=================

A chain of frames: retina + eye -> head-centred map, its response + head -> body-centred map.

Both maps learn without a teacher, each from two views of its own invariant (the head-centred
position a = (x + e) / 2, then the body-centred z = (a + u) / 2). Beside them, one map learns
the whole transformation at once from the retina and the joint code of (eye, head): third-order
Sigma-Pi units on the same triples (``sigmapi.experiments.chain.run``, docs/algorithm.md).

Run it::

    python examples/chain.py            # paper-1d sizes, 300,000 iterations per map, 5 seeds
    python examples/chain.py --small    # a second or two
"""

from __future__ import annotations

import argparse

import sigmapi
from sigmapi.experiments.chain.run import run_chain


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    parser.add_argument("--code", choices=("response", "winner"), default="response",
                        help="what map A hands to map B (default: its response)")  # fmt: skip
    args = parser.parse_args()
    cfg = sigmapi.load_preset("paper-1d").replace(refine_rounds=0)  # as the README measured
    pairs, seeds, n_test = 20_000, range(5), 10_000
    if args.small:
        cfg = cfg.replace(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=15_000,
                          winner_rule="argmax")  # fmt: skip
        pairs, seeds, n_test = 3000, range(2), 2000

    result = run_chain(seeds, config=cfg, train_pairs=pairs, n_test=n_test, code=args.code)
    for r in result["seeds"]:
        a, c, s = r["map_a"], r["chain"], r["single"]
        print(f"seed {r['seed']}: map A (head-centred) order R^2 {a['order_r2']:.3f}, "
              f"z error {a['z_error']:.3f}")  # fmt: skip
        for name, m in (("chain", c), ("single map", s)):
            print(f"  {name:10s} z error {m['z_error']:.3f}, same winner "
                  f"{m['view_consistency']:.3f}, order R^2 {m['order_r2']:.3f}, "
                  f"{m['weights']:,} weights, {m['train_seconds']:.1f} s")  # fmt: skip
        print(f"  chain / single z error {r['ratio']:.2f}")
    summary = result["summary"]
    print(f"{summary['met']} of {summary['n_seeds']} seeds: chain z error <= "
          f"{summary['target_ratio']:g} x the single map's (median ratio "
          f"{summary['ratio_median']:.2f}, worst {summary['ratio_worst']:.2f})")  # fmt: skip


if __name__ == "__main__":
    main()
