"""Noisy population codes
======================

Noisy population codes: z error and view consistency against the noise level, as a figure.

Every code the map sees, in training and in testing, is made noisy with
:func:`sigmapi.codes.noisy`: Poisson spike counts at a chosen expected count of the most
active unit, or additive Gaussian noise (standard deviation a fraction of the peak). The
Sigma-Pi map (paper-1d sizes, sigmapi's ordering procedure) trains on 20,000 noisy view pairs
with ``fit(views)`` and is scored by ``evaluate`` on noisy test and calibration views.

Run it::

    python examples/noise.py --out noise.png            # 3 seeds, about 3 minutes
    python examples/noise.py --small --out noise.png    # seconds
"""

from __future__ import annotations

import argparse

import numpy as np
from matplotlib.figure import Figure

import sigmapi
from sigmapi.codes import noisy
from sigmapi.metrics import evaluation_sets

LEVELS = {
    "poisson": (100.0, 30.0, 10.0, 5.0, 3.0, 2.0, 1.0),
    "gaussian": (0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 1.0),
}
"""Noise levels: expected spike count at the peak (fewer is noisier); sd / peak."""


def add_noise(batch: sigmapi.Batch, kind: str, level: float, seed: int) -> sigmapi.Batch:
    """The batch with all four codes made noisy (independent noise per code)."""
    rngs = [np.random.default_rng([seed, i]) for i in range(4)]
    x0, y0, x1, y1 = (
        noisy(c, kind, level, r)
        for c, r in zip((batch.x0, batch.y0, batch.x1, batch.y1), rngs, strict=True)
    )
    return batch._replace(x0=x0, y0=y0, x1=x1, y1=y1)


def sweep(cfg: sigmapi.SOMConfig, kind: str, levels, seeds, pairs: int, n_test: int):
    """Median (over seeds) z error and view consistency at each level."""
    out = []
    for level in levels:
        scores = []
        for seed in seeds:
            som = sigmapi.SigmaPiSOM(cfg, seed=seed)
            b = add_noise(som.sampler.sample(pairs, np.random.default_rng(seed)), kind, level, seed)
            som.fit((b.x0, b.y0, b.x1, b.y1))
            cal, test = (add_noise(s, kind, level, 99 + i)
                         for i, s in enumerate(evaluation_sets(som, n_test)))  # fmt: skip
            m = sigmapi.evaluate(som, test=test, calibration=cal)
            scores.append((m.z_error, m.view_consistency))
        z, vc = np.median(scores, axis=0)
        out.append((level, float(z), float(vc)))
        print(f"{kind} {level:g}: z error {z:.3f}, same winner {vc:.3f}")
    return out


def draw(results: dict, floor: float, seeds) -> Figure:
    fig = Figure(figsize=(10, 4), layout="constrained")
    for ax, (kind, rows) in zip(fig.subplots(1, 2), results.items(), strict=True):
        lv, z, vc = (np.array(c) for c in zip(*rows, strict=True))
        ax.plot(lv, z, "o-", color="C0", label="z error")
        ax.axhline(floor, color="0.5", linewidth=0.8, label="winner-only floor")
        ax.set_ylabel("z error (grid spacings)", color="C0")
        ax.set_ylim(0, None)
        twin = ax.twinx()
        twin.plot(lv, vc, "s--", color="C3", label="same winner")
        twin.set_ylim(0, 1)
        twin.set_ylabel("same winner for both views", color="C3")
        if kind == "poisson":
            ax.set_xscale("log")
            ax.invert_xaxis()  # noisier to the right
            ax.set_xlabel("expected spike count of the peak unit (fewer: noisier)")
        else:
            ax.set_xlabel("Gaussian noise sd / peak")
        ax.set_title(f"{kind} noise, median of {len(seeds)} seed{'s' * (len(seeds) > 1)}")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=8)
        twin.legend(loc="upper center", fontsize=8)
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    parser.add_argument("--out", default="noise.png", help="figure file")
    args = parser.parse_args()
    cfg = sigmapi.load_preset("paper-1d").replace(refine_rounds=0)  # as the README measured
    levels, seeds, pairs, n_test = LEVELS, range(3), 20_000, 10_000
    if args.small:
        cfg = cfg.replace(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=10_000,
                          winner_rule="argmax")  # fmt: skip
        levels = {k: (v[0], v[-1]) for k, v in LEVELS.items()}
        seeds, pairs, n_test = range(1), 2000, 1000
    results = {kind: sweep(cfg, kind, lv, seeds, pairs, n_test) for kind, lv in levels.items()}
    n = cfg.map_shape[0]
    floor = (cfg.x_shape[0] - 1) / n / np.sqrt(12.0)
    fig = draw(results, floor, seeds)
    fig.savefig(args.out, dpi=120)
    clean, worst = results["gaussian"][0], results["gaussian"][-1]
    print(
        f"caption: noise in every code, training and test; Gaussian sd {clean[0]:g} -> "
        f"{worst[0]:g} of the peak: z error {clean[1]:.2f} -> {worst[1]:.2f}, same winner "
        f"{clean[2]:.2f} -> {worst[2]:.2f}; Poisson, {results['poisson'][0][0]:g} -> "
        f"{results['poisson'][-1][0]:g} spikes at the peak: z error "
        f"{results['poisson'][0][1]:.2f} -> {results['poisson'][-1][1]:.2f}"
    )


if __name__ == "__main__":
    main()
