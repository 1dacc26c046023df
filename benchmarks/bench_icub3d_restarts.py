"""Does fitting each part of the 3-D chain's map T more than once, and keeping per part the fit
with the lowest fold score on its own training pairs, catch map T's twists?

Usage (from the repository root, ``MUJOCO_GL=egl PYTHONPATH=src``)::

    python benchmarks/bench_icub3d_restarts.py run 0 1 2 --restarts 1 2 3 --head --out T.jsonl
    python benchmarks/bench_icub3d_restarts.py run 426 ... 435 --restarts 1 3 --out F.jsonl
    python benchmarks/bench_icub3d_restarts.py run 422 --restarts 1 3 --arms pixels projections \\
        --out A.jsonl
    python benchmarks/bench_icub3d_restarts.py collect T.jsonl F.jsonl A.jsonl

``run``: per seed one :func:`~sigmapi.experiments.icub.space3d.record_box` (2,000 training
pairs per stage, 400 evaluation pairs, as ``run_maps`` records), then per arm (``pixels``, the
robot's detections; ``projections``, the reference arm that reads the truth,
:func:`~sigmapi.experiments.icub.space3d.projected`) and per ``restarts`` the chain learned
with the defaults on the SAME views, both maps scored by ``score_map``; one JSON line per seed,
arm and setting (``--head``: also ``restarts`` applied to map H's parts, a variant the library
does not offer, ``"3+H"``). ``collect``: writes ``benchmarks/results/icub3d-restarts.json``
(the lines, a summary per set of seeds, map and setting, and this script).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import machine, write_result

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"
COMMANDS = [
    "python benchmarks/bench_icub3d_restarts.py run 0 1 2 --restarts 1 2 3 --head"
    " --out tuning_0-2.jsonl",
    "python benchmarks/bench_icub3d_restarts.py parts 0 1 2 --fits 20 --out tuning_parts_0-2.jsonl",
    "python benchmarks/bench_icub3d_restarts.py run 426 427 428 429 430 431 432 433 434 435"
    " --restarts 1 2 3 --out fresh_426-435.jsonl",
    "python benchmarks/bench_icub3d_restarts.py run 422 --restarts 1 2 3"
    " --arms pixels projections --out seed_422_arms.jsonl",
    "python benchmarks/bench_icub3d_restarts.py collect tuning_0-2.jsonl tuning_parts_0-2.jsonl"
    " fresh_426-435.jsonl seed_422_arms.jsonl",
]
"""The runs of ``benchmarks/results/icub3d-restarts.json`` (``MUJOCO_GL=egl PYTHONPATH=src``,
one after the other in one background process)."""
KEYS = ("order_r2", "order_r2_per_axis", "error_cm", "error_cm_median", "fold_score", "folded")


def _learn(s3: Any, train: dict[str, Any], seed: int, eye_size: int, r: int, head: bool) -> Any:
    """The chain with ``restarts=r``; ``head``: map H's parts refitted the same way."""
    if not head:
        return s3.learn_chain3d(
            train["eyes"], train["head"], seed=seed, eye_size=eye_size, restarts=r
        )
    plain = s3._fit

    def fit_h(m: Any, a: Any, b: Any) -> None:  # map H only: learn_chain3d's one _fit call
        m.parts = s3._fit_restarts(m, a, b, r)[0].parts

    s3._fit = fit_h
    try:
        return s3.learn_chain3d(
            train["eyes"], train["head"], seed=seed, eye_size=eye_size, restarts=r
        )
    finally:
        s3._fit = plain


def _projected(s3: Any, scene: Any, pair: Any) -> tuple[Any, ...]:
    """Both views of a pair with the detections replaced by the projections (the truth)."""
    return tuple(s3.projected(scene, v) for v in pair)


def run(seeds: list[int], restarts: list[int], arms: list[str], head: bool, out: Path) -> None:
    from sigmapi.experiments.icub import space3d as s3

    for seed in seeds:
        t0 = time.perf_counter()
        scene, train, ev = s3.record_box(np.random.default_rng(seed), 2000, 400)
        t_record = time.perf_counter() - t0
        data = {"pixels": (train, ev)}
        if "projections" in arms:
            data["projections"] = (
                {s: _projected(s3, scene, p) for s, p in train.items()},
                {
                    s: (_projected(s3, scene, c), _projected(s3, scene, t))
                    for s, (c, t) in ev.items()
                },
            )
        scene.close()
        settings = [(r, False) for r in restarts] + ([(max(restarts), True)] if head else [])
        for arm in arms:
            tr, e = data[arm]
            for r, h in settings:
                t1 = time.perf_counter()
                chain = _learn(s3, tr, seed, scene.eye_size, r, h)
                learn = time.perf_counter() - t1
                row: dict[str, Any] = {
                    "seed": seed,
                    "arm": arm,
                    "restarts": f"{r}+H" if h else r,
                    "learn_s": learn,
                    "record_s": t_record,
                    "restart_scores_t": chain.restart_scores,
                }
                for name, stage, d in (("map_h", "head", "eyes"), ("map_t", "torso", "head")):
                    sc = s3.score_map(chain, stage, *e[d])
                    row[name] = {k: sc[k] for k in KEYS}
                    row[name]["parts"] = {k: v["fold_score"] for k, v in sc["parts"].items()}
                with out.open("a", encoding="utf-8") as f:
                    f.write(json.dumps(row, default=float) + "\n")
                print(
                    seed,
                    arm,
                    row["restarts"],
                    round(learn, 1),
                    {
                        m: (
                            round(row[m]["order_r2"], 3),
                            round(row[m]["error_cm"], 2),
                            round(row[m]["fold_score"], 1),
                        )
                        for m in ("map_h", "map_t")
                    },
                    flush=True,
                )


def parts(seeds: list[int], fits: int, out: Path) -> None:
    """Per seed, map T's parts each fitted from ``fits`` seeds (:func:`restart_seeds`), the
    others left at the first fit: each fit's fold score on its training pairs (what the choice
    reads) beside map T's scores on the evaluation pairs with that fit in place."""
    from sigmapi.experiments.icub import space3d as s3

    for seed in seeds:
        scene, train, ev = s3.record_box(np.random.default_rng(seed), 2000, 400)
        scene.close()
        chain = s3.learn_chain3d(train["eyes"], train["head"], seed=seed, eye_size=scene.eye_size)
        first = chain.map_t
        a, b = (chain.inputs_t(v) for v in train["head"])
        names = s3.PART_NAMES[3]
        for i, part in enumerate(first.parts):
            for k, s in enumerate(s3.restart_seeds(part.config.seed, fits)):
                m = s3.SigmaPiSOM(part.config.replace(seed=s))
                m.fit((*a[i], *b[i]))
                chain.map_t = s3.FactorMap(*(m if j == i else p for j, p in enumerate(first.parts)))
                sc = s3.score_map(chain, "torso", *ev["head"])
                row = {
                    "seed": seed,
                    "part": names[i],
                    "fit": k,
                    "train_pair_fold": s3.pair_fold_score(m, a[i], b[i]),
                    "eval_part_fold": sc["parts"][names[i]]["fold_score"],
                    **{key: sc[key] for key in KEYS},
                    "order_r2_per_axis_spherical": sc["order_r2_per_axis_spherical"],
                }
                with out.open("a", encoding="utf-8") as f:
                    f.write(json.dumps(row, default=float) + "\n")
            print(seed, names[i], flush=True)


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per map: order R^2 median and worst, flagged count, error cm median and worst; the
    learning seconds median and worst."""
    out: dict[str, Any] = {"seeds": sorted({r["seed"] for r in rows}), "n": len(rows)}
    for m in ("map_h", "map_t"):
        o = [r[m]["order_r2"] for r in rows]
        e = [r[m]["error_cm"] for r in rows]
        out[m] = {
            "order_r2_median": float(np.median(o)),
            "order_r2_worst": float(min(o)),
            "flagged": int(sum(r[m]["folded"] for r in rows)),
            "fold_score_median": float(np.median([r[m]["fold_score"] for r in rows])),
            "fold_score_worst": float(max(r[m]["fold_score"] for r in rows)),
            "error_cm_median": float(np.median(e)),
            "error_cm_worst": float(max(e)),
        }
    s = [r["learn_s"] for r in rows]
    out["learn_s_median"], out["learn_s_worst"] = float(np.median(s)), float(max(s))
    return out


def parts_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per seed and part: the range of the fits' training-pair fold score and of map T's
    order R^2, the fits that twisted (order R^2 0.05 or more below the median of that part's
    fits), and what ``restarts`` 1, 2, 3 and 5 would keep (the lowest training-pair fold score
    of the first fits, the first on a tie): map T's order R^2 and the part's evaluation fold
    score with it."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(f"{r['seed']}/{r['part']}", []).append(r)
    out: dict[str, Any] = {}
    for key, g in groups.items():
        g.sort(key=lambda r: r["fit"])
        fold = [r["train_pair_fold"] for r in g]
        order = [r["order_r2"] for r in g]
        med = float(np.median(order))
        kept = {}
        for n in (1, 2, 3, 5):
            k = int(np.argmin(fold[:n]))
            kept[str(n)] = {
                "fit": k,
                "order_r2": order[k],
                "eval_part_fold": g[k]["eval_part_fold"],
            }
        out[key] = {
            "fits": len(g),
            "train_pair_fold_range": [min(fold), max(fold)],
            "order_r2_range": [min(order), max(order)],
            "twisted_fits": [r["fit"] for r in g if r["order_r2"] <= med - 0.05],
            "kept": kept,
        }
    return out


def collect(files: list[Path]) -> None:
    result: dict[str, Any] = {
        "commands": COMMANDS,
        "script": Path(__file__).read_text(encoding="utf-8"),
        "runs": {},
    }
    for path in files:
        rows = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]
        if "part" in rows[0]:
            result["runs"][path.stem] = {"rows": rows, "summary": parts_summary(rows)}
            continue
        groups: dict[str, list[dict[str, Any]]] = {}
        for r in rows:
            groups.setdefault(f"{r['arm']}/restarts={r['restarts']}", []).append(r)
        result["runs"][path.stem] = {
            "rows": rows,
            "summary": {k: summary(v) for k, v in groups.items()},
        }
    result["machine"] = machine()
    write_result(RESULTS / "icub3d-restarts.json", result)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("seeds", type=int, nargs="+")
    r.add_argument("--restarts", type=int, nargs="+", default=[1, 3])
    r.add_argument("--arms", nargs="+", default=["pixels"], choices=["pixels", "projections"])
    r.add_argument("--head", action="store_true")
    r.add_argument("--out", type=Path, required=True)
    q = sub.add_parser("parts")
    q.add_argument("seeds", type=int, nargs="+")
    q.add_argument("--fits", type=int, default=20)
    q.add_argument("--out", type=Path, required=True)
    c = sub.add_parser("collect")
    c.add_argument("files", type=Path, nargs="+")
    a = p.parse_args()
    if a.cmd == "run":
        run(a.seeds, a.restarts, a.arms, a.head, a.out)
    elif a.cmd == "parts":
        parts(a.seeds, a.fits, a.out)
    else:
        collect(a.files)


if __name__ == "__main__":
    main()
