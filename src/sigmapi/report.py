"""The reproduction report: ``sigmapi reproduce --out DIR``, the project's main job.

Trains the paper presets, evaluates them and writes ``DIR/metrics.json``, the trained model
files and ``DIR/report.html`` with the measured metrics beside the reference figures of
ALGORITHM.md.
"""

from __future__ import annotations

import argparse
import html
import json
import sys
import time
from pathlib import Path
from typing import Any

from sigmapi.config import SOMConfig, list_presets, load_preset
from sigmapi.io import atomic_write_bytes
from sigmapi.metrics import evaluate

__all__ = ["REFERENCE", "register", "reproduce"]

REFERENCE: dict[str, dict[str, float]] = {
    "paper-1d": {"view_consistency": 0.87, "view_within_one": 0.988, "z_error": 0.32},
}
"""Reference figures of ALGORITHM.md (the authors' 1-D script re-stated in NumPy, 4 seeds)."""


def _presets(quick: bool) -> list[tuple[str, SOMConfig]]:
    names = [n for n in ("paper-1d", "paper-2d") if n in list_presets()]
    out = []
    for name in names:
        cfg = load_preset(name)
        if quick:
            cfg = cfg.replace(iterations=max(1000, cfg.iterations // 10))
        out.append((name, cfg))
    return out


def reproduce(out: Path, seeds: list[int], quick: bool = False, progress: bool = True) -> dict[str, Any]:
    """Train and evaluate each paper preset for ``seeds``; write the report into ``out``."""
    from sigmapi.cli import progress_callback
    from sigmapi.som import SigmaPiSOM

    out.mkdir(parents=True, exist_ok=True)
    results: dict[str, Any] = {"quick": quick, "seeds": seeds, "presets": {}}
    for name, cfg in _presets(quick):
        runs = []
        for seed in seeds:
            model = SigmaPiSOM(cfg, seed=seed)
            callback, bar = progress_callback(cfg.iterations, f"{name} seed {seed}", disable=not progress or None)
            t0 = time.perf_counter()
            with bar:
                model.fit(callback=callback)
            seconds = time.perf_counter() - t0
            model.save(out / f"{name}-seed{seed}.npz")
            metrics = evaluate(model).to_dict()
            runs.append({"seed": seed, "train_seconds": seconds, "backend": model.backend, **metrics})
        keys = ("view_consistency", "view_within_one", "z_error", "order_r2", "usage")
        mean = {k: sum(float(r[k]) for r in runs) / len(runs) for k in keys}
        results["presets"][name] = {
            "config": cfg.to_dict(), "runs": runs, "mean": mean, "reference": REFERENCE.get(name, {}),
        }  # fmt: skip
    atomic_write_bytes(out / "metrics.json", json.dumps(results, indent=2).encode())
    atomic_write_bytes(out / "report.html", _html(results).encode())
    return results


def _html(results: dict[str, Any]) -> str:
    rows = []
    for name, res in results["presets"].items():
        for key, value in res["mean"].items():
            ref = res["reference"].get(key)
            rows.append(
                f"<tr><td>{html.escape(name)}</td><td>{key}</td><td>{value:.3f}</td>"
                f"<td>{'' if ref is None else f'{ref:.3f}'}</td></tr>"
            )
    title = "sigmapi reproduction of Weber &amp; Wermter (2007)"
    return (
        f"<!doctype html><html><head><meta charset='utf-8'><title>{title}</title></head><body>"
        f"<h1>{title}</h1><p>Seeds: {results['seeds']}; quick run: {results['quick']}.</p>"
        "<table border='1'><tr><th>preset</th><th>metric</th><th>measured (mean over seeds)</th>"
        f"<th>reference</th></tr>{''.join(rows)}</table></body></html>"
    )


def cmd_reproduce(args: argparse.Namespace) -> int:
    from sigmapi.cli import UsageError

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is a file; give a folder for the report")
    if out.exists() and any(out.iterdir()) and not args.force:
        raise UsageError(f"--out folder {str(out)!r} is not empty; pass --force to write into it")
    results = reproduce(out, seeds=args.seeds, quick=args.quick, progress=not args.quiet)
    for name, res in results["presets"].items():
        print(f"{name}: " + ", ".join(f"{k} {v:.3f}" for k, v in res["mean"].items()), file=sys.stderr)
    print(f"wrote {out / 'report.html'}", file=sys.stderr)
    return 0


def register(sub: Any) -> None:
    """Add ``sigmapi reproduce`` to the CLI."""
    p = sub.add_parser("reproduce", help="train the paper presets and write the reproduction report")
    p.add_argument("--out", default="report", help="folder for the report (default: ./report)")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="seeds (default: 0 1 2)")
    p.add_argument("--quick", action="store_true", help="a 10x shorter run for a first look")
    p.add_argument("--force", action="store_true", help="write into a non-empty --out folder")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=cmd_reproduce)
