"""Angles on a ring
================

Angles on a ring: periodic codes, z = (x + y) mod 1, and a periodic (ring) map.

x and y are angles, fractions of a turn where 0 and 1 are the same place (a body direction and
a head-on-body angle, say); z = (x + y) mod 1 (the head direction). The preset ``angles-1d``
puts them on periodic codes and learns them on a ring of 15 units (``map_periodic = true``).
A bounded map (the paper's) learns the same angles as well, view for view, but with a seam:
its two ends decode neighbouring angles, so two nearby z win units at opposite ends of the map
(``seam_gap``: the largest map distance between units that decode neighbouring angles). The
ring has no seam: the units on both sides of the wrap win, one unit apart.

Run it::

    python examples/angles.py            # 15-unit ring, 3 seeds (a few seconds each)
    python examples/angles.py --small    # a 10-unit ring, one seed
"""

from __future__ import annotations

import argparse

import sigmapi


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    args = parser.parse_args()
    cfg = sigmapi.load_preset("angles-1d")  # periodic codes, relation "sum_mod", a ring
    seeds, n_test = range(3), 10_000
    if args.small:
        cfg = cfg.replace(map_shape=(10,), x_shape=(10,), y_shape=(10,), iterations=40_000)
        seeds, n_test = range(1), 2000

    for map_periodic in (True, False):
        name = "ring   " if map_periodic else "bounded"
        for seed in seeds:
            som = sigmapi.SigmaPiSOM(cfg, map_periodic=map_periodic, seed=seed).fit()
            m = sigmapi.evaluate(som, n_test=n_test).to_dict()
            print(f"{name} seed {seed}: same winner {m['view_consistency']:.3f}, "
                  f"z error {m['z_error']:.3f} (circular), circular order R^2 "
                  f"{m['order_circular']:.3f}; seam: largest jump {m['seam_jump']:.2f} grid "
                  f"spacings, units of neighbouring angles up to {m['seam_gap']:.0f} apart, "
                  f"both sides of the wrap win: {m['seam_units_win']}, "
                  f"seamless: {m['seamless']}")  # fmt: skip


if __name__ == "__main__":
    main()
